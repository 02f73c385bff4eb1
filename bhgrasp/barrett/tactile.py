"""The BH8-280's tactile pads: 24 pressure cells on each fingertip's inner face and 24 on the palm.

Layout (cell rectangles [mm]) from GraspIt!'s ``models/robots/BarrettBH8_280_Tactile/BarrettBH8_280_Tactile.xml``
(graspit-simulator/graspit @83a6d4c5), whose ``filter`` boxes Robotnik's BSD ``bh280_tactile.urdf.xacro``
(RobotnikAutomation/barrett_hand_common @b3d96feb) converts into sensor frames in the same order:

- fingertip: 8 rows along the link (x 19.5 .. 57.5 mm from the distal joint axis, rows 5.5 mm long, shorter
  toward the tip: "the density of cells becomes higher towards the very tips", Barrett wiki
  ``Hand/280/SystemComponentList``) by 3 columns across it (z -7.5 .. 7.55 mm), on the inner face (+y of the
  distal link frame); cell ``3 row + column``, row 0 nearest the joint (libbarrett ``sandbox/tactile_test.cpp``
  draws cell i at row i / 3, column i % 3 of an 8 x 3 grid);
- palm: 10 mm square cells in rows of 5, 7, 7, 5 (x -38 .. 38, y -21.5 .. 21.5 mm of GraspIt's palm frame, whose F3
  lies on -y: here x and y change sign), on the ``palm_surface`` frame's plane, normal +z.

Readings are pressures [N/cm^2], libbarrett's ``TactilePuck::getFullData()`` unit (``tactile_test.cpp`` prints
"N*cm^-2"): each cell arrives as a 12-bit count that ``TactilePuck::FullTactParser`` divides by
``FULL_SCALE_FACTOR`` = 256 (``src/products/tactile_puck.cpp``), so a cell reads in steps of 1/256 N/cm^2 and
saturates at 4095/256 = 16.0 N/cm^2 (:func:`digitise_pressures`).

Assumptions (not from a source): the simulator gives point contacts; each point's normal force (n . F, clipped at 0:
a pad does not feel tension) is spread uniformly over a square of half-width ``spread`` (default 3 mm, half a cell
pitch, standing for the pad's compliant cover) and shared among the cells in proportion to the square's overlap with
each cell, normalised so that the pad keeps the whole force (the 0.5 mm gaps between cells lose nothing). A point
belongs to a pad when the hand's side of its pair (body a for an object, body b for the environment) is a frame on
the pad's link, it lies within ``margin`` (half the widest gap) of a cell in the pad plane and not below ``floor``
along the pad normal (fingertip: the link's inner half).
Whether the cell order matches the pucks' TACT order and which side column 0 lies on are not verified.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bhgrasp._validation import as_positive

CM2_PER_M2 = 1e4
TACTILE_SCALE = 256.0  # counts per N/cm^2 (libbarrett TactilePuck FULL_SCALE_FACTOR)
TACTILE_MAX_COUNTS = 4095  # 12-bit cells
TACTILE_FULL_SCALE = TACTILE_MAX_COUNTS / TACTILE_SCALE  # [N/cm^2] 16.0
# [mm] along the distal link x
_FINGER_ROWS = (
    (19.5, 25.0),
    (25.5, 31.0),
    (31.5, 37.0),
    (37.5, 43.0),
    (43.5, 49.0),
    (49.5, 52.5),
    (53.0, 55.5),
    (55.75, 57.5),
)
_FINGER_COLUMNS = ((-7.5, -2.85), (-2.35, 2.35), (2.85, 7.55))  # [mm] along the distal joint axis z
# [mm] GraspIt palm frame: (y band, x extent), 10 mm cells
_PALM_ROWS = (
    ((11.5, 21.5), (-27.0, 27.0)),
    ((0.5, 10.5), (-38.0, 38.0)),
    ((-10.5, -0.5), (-38.0, 38.0)),
    ((-21.5, -11.5), (-27.0, 27.0)),
)


@dataclass(frozen=True)
class TactilePad:
    """One 24-cell pad: its cells as rectangles in the pad's plane.

    Attributes:
        name: ``"F1"``, ``"F2"``, ``"F3"`` or ``"palm"``.
        frame: The frame the pad is fixed in; contacts on a frame of the same body (either side of the pair) touch it.
        axes: (3, 3) rows: the pad's u, w (plane) and normal axes in ``frame`` coordinates.
        cells: (24, 4) cell rectangles (u0, u1, w0, w1) [m].
        margin: Distance [m] from a cell within which a point counts as on the pad.
        floor: Lowest height [m] along the normal of a point on the pad.
    """

    name: str
    frame: str
    axes: np.ndarray
    cells: np.ndarray
    margin: float
    floor: float

    @property
    def centres(self) -> np.ndarray:
        """(24, 2) cell centres (u, w) [m]."""
        return 0.5 * (self.cells[:, [0, 2]] + self.cells[:, [1, 3]])

    @property
    def areas(self) -> np.ndarray:
        """(24,) cell areas [m^2]."""
        return (self.cells[:, 1] - self.cells[:, 0]) * (self.cells[:, 3] - self.cells[:, 2])

    def locate(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Points in ``frame`` coordinates [m] -> (plane coordinates (n, 2), whether each lies on the pad (n,))."""
        local = points @ self.axes.T
        uw = local[:, :2]
        outside = np.maximum(self.cells[None, :, [0, 2]] - uw[:, None], uw[:, None] - self.cells[None, :, [1, 3]])
        near = (outside.max(axis=2) <= self.margin + 1e-9).any(axis=1)  # 1 nm for round-off
        return uw, near & (local[:, 2] >= self.floor)

    def cell_forces(self, uw: np.ndarray, forces: np.ndarray, spread: float) -> np.ndarray:
        """(24,) normal force [N] per cell of point forces ``forces`` (n,) at plane points ``uw`` (n, 2) on the pad.

        Each force is shared in proportion to the overlap of its square of half-width ``spread`` with each cell.
        """
        low = np.maximum(uw[:, None] - spread, self.cells[None, :, [0, 2]])
        high = np.minimum(uw[:, None] + spread, self.cells[None, :, [1, 3]])
        overlap = np.clip(high - low, 0.0, None).prod(axis=2)  # (n, 24) [m^2]
        return (forces / overlap.sum(axis=1)) @ overlap


def finger_pad(finger: str) -> TactilePad:
    """A fingertip's pad, on the inner face (+y) of ``{finger}_distal_link``."""
    cells = [(*row, *column) for row in _FINGER_ROWS for column in _FINGER_COLUMNS]
    axes = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, 1.0, 0.0]])  # u = x, w = z, normal = y
    return TactilePad(finger, f"{finger}_distal_link", axes, 1e-3 * np.array(cells), margin=0.25e-3, floor=0.0)


def palm_pad() -> TactilePad:
    """The palm's pad on the ``palm_surface`` plane (GraspIt's palm x, y are this frame's -x, -y).

    Points down to 5 mm below the plane (a penetrating contact on the palm's top) count; the palm cylinder's side
    (radius 44.5 mm) lies outside every cell's reach.
    """
    cells = [(x, x + 10.0, *band) for band, (start, stop) in _PALM_ROWS for x in np.arange(start, stop, 11.0)]
    axes = np.array([[-1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, 1.0]])
    return TactilePad("palm", "palm_surface", axes, 1e-3 * np.array(cells), margin=0.5e-3, floor=-5e-3)


def pad_pressures(pad: TactilePad, points: np.ndarray, normal_forces: np.ndarray, spread: float) -> np.ndarray:
    """(24,) pressures [N/cm^2] on ``pad`` of contacts at ``points`` [m, pad frame] with normal forces [N].

    Points off the pad add nothing; pressing forces are clipped at zero.
    """
    spread = as_positive(spread, "spread")
    if not len(points):
        return np.zeros(len(pad.cells))
    uw, on = pad.locate(points)
    forces = pad.cell_forces(uw[on], np.maximum(normal_forces[on], 0.0), spread)
    return forces / (pad.areas * CM2_PER_M2)


def digitise_pressures(pressures: np.ndarray) -> np.ndarray:
    """Pressures [N/cm^2] as the pads report them: 12-bit counts / 256, so steps of 1/256 up to 16.0 N/cm^2.

    A pad feels no tension: negative pressures read 0.
    """
    counts = np.clip(np.rint(np.asarray(pressures, dtype=float) * TACTILE_SCALE), 0, TACTILE_MAX_COUNTS)
    return counts / TACTILE_SCALE


__all__ = [
    "CM2_PER_M2",
    "TACTILE_FULL_SCALE",
    "TACTILE_MAX_COUNTS",
    "TACTILE_SCALE",
    "TactilePad",
    "digitise_pressures",
    "finger_pad",
    "pad_pressures",
    "palm_pad",
]
