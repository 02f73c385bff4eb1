"""The side pinch: how the grasp benchmark takes an object that it cannot grasp from above.

A low object (a 15-35 mm box, a 33 mm can) or a small ball leaves no top-down grasp height
(:mod:`~bhgrasp.bench.height`): the fingers, 126 mm long, sweep past the object's side onto its stand before they
touch it.  (A ball of 70 mm radius leaves none at the pre-shape either, for it reaches into the open F3; the hand opens
wider for it, :mod:`~bhgrasp.bench.opening`, and takes it from above.)  Turned palm sideways
(:data:`~bhgrasp.bench.reach.SIDEWAYS`: the palm's normal along world +x, F3 up, F1 towards world -y) with F1 and F2
spread to face each other (:data:`SIDE_SPREAD`), the two fingers close in one horizontal plane, the pinch plane, and
press the object between them across its y edges; F3 stays open above it.
The stand has the object's footprint, so the palm passes beside it, below the object's top; on a table (a trial
among neighbours) the palm, 44.5 mm in radius about the pinch plane, would be inside the table wherever that plane is
lower, as it is for every low or small object, and no pinch qualifies (the large ball's plane is higher).

The rule (:func:`side_centre`), the same for both grasps (how it came about: :mod:`~bhgrasp.bench.protocol`):

- the pinch plane at the object's mid-height (a sphere's equator), but no lower than a finger's half width
  (:func:`finger_half_width`, its knuckle housing's 12.8 mm) and :data:`~bhgrasp.bench.height.STAND_MARGIN` above
  the stand's top;
- the object's centre on the palm's normal, on a 2 mm grid outwards from its near side on the knuckle housings: the
  nearest at which both fingers, closing from the pre-shape, touch the object (in a precision grasp first with
  their fingertips; a finger moving in a horizontal plane that straddles the object's side cannot press it onto its
  stand, as a finger coming down on its top does), every hand shape stays ``STAND_MARGIN`` from the stand from the
  open hand to each finger's touch, and the open hand's way in (:data:`~bhgrasp.bench.protocol.APPROACH`, up to
  the grasp) does not touch the object.  On every object of the benchmark's sets that is the first grid point: a
  box's near face on the knuckle housings; a round object tangent to the palm's axis there, 0.9-2.9 mm off the
  housings, which stand to its sides (tests/test_bench_side.py), until the pinch, whose contacts beyond its centre
  push it inwards, presses it onto them (the tuna can, tested).  Two fingertip contacts hold no moment about the
  line through them but what their patches twist; the housings, flat against the object's near side, do.  Measured
  once each on the development set's 3 cm flat box: with the way in checked at the grasp itself and the pinch plane
  at the outer link's half width (its housings then 2.2 mm from the stand), which put it 4 mm off the housings, the
  lift turned it over; so did moving the fingertips' touches onto its centre of mass (the
  object 40 mm further out); on the housings it held within 0.05 mm.

A trial takes the pinch only where the top-down rules find no grasp (:func:`approach_of`,
:func:`~bhgrasp.bench.opening.top_down`).
"""

from __future__ import annotations

import functools
import math

import coal
import numpy as np
import pinocchio as pin

from bhgrasp.bench.height import STAND_HEIGHT, STAND_MARGIN, support_box
from bhgrasp.bench.objects import BenchObject
from bhgrasp.bench.opening import top_down
from bhgrasp.bench.placement import grasp_centre
from bhgrasp.bench.protocol import APPROACH, PRESHAPE, Trial, spread_of
from bhgrasp.bench.reach import ORIENTATIONS, Reach, hand_depth, placed_corners, reach_of

SIDE_SPREAD = math.pi / 2  # [rad] F1 and F2 face each other across the palm
PINCH = ("F1", "F2")  # the fingers that close in a side pinch
FURTHEST = 0.15  # [m] the rule's search for the object's centre, beyond the knuckle housings touching it
STEP = 0.002  # [m] of that search
WAY_IN = 0.005  # [m] the open hand's way in is checked every this


@functools.lru_cache(maxsize=1)
def finger_half_width() -> float:
    """Half the width [m] of F1 across its closing plane at :data:`SIDE_SPREAD`: its knuckle housing's 12.8 mm.

    The housing (25 mm, its centre 0.3 mm off the plane), the outer link (23.7 mm) and the inner link (21.3 mm)
    across the plane, by their collision shapes.
    """
    reach = reach_of(BenchObject("sphere", (0.01,), 0.1), SIDE_SPREAD, PRESHAPE, "side")
    pin.updateGeometryPlacements(
        reach.hand.model, reach.model_data, reach.geometry, reach.data, reach.configuration(PRESHAPE)
    )
    geometry, placements = reach.geometry.geometryObjects, reach.data.oMg
    return max(  # hand y: across F1's closing plane
        float(np.abs(placed_corners(item.geometry, placements[i])[:, 1]).max())
        for i, item in enumerate(geometry)
        if item.name.startswith("F1")
    )


def pinch_height(item: BenchObject) -> float:
    """The pinch plane's height [m] above the stand's top: the object's mid-height, or low enough for the fingers."""
    return max(float(item.half_extents[2]), finger_half_width() + STAND_MARGIN)


def _support_gap(reach: Reach, item: BenchObject, centre: np.ndarray, touches: dict[str, float], table: bool) -> float:
    """The hand's least distance [m] from the stand (or table): open, then each pinching finger up to its touch."""
    support = support_box(item, table)
    below = centre + reach.axes @ np.array([0.0, 0.0, -(item.half_extents[2] + 0.5 * STAND_HEIGHT)])
    nearest = reach.open_distance(support, coal.Transform3s(reach.axes, below))
    for finger, touch in touches.items():
        for angle in [*np.arange(reach.opening, touch, 0.01), touch]:
            nearest = min(nearest, reach.distance(finger, float(angle), below, support))
    return nearest


def _way_in_clear(reach: Reach, centre: np.ndarray) -> bool:
    """Whether the open hand, moving in along its palm's normal over its last APPROACH, stays off the object.

    Up to the grasp, not at it: there the object may rest against the knuckle housings (the module's rule).
    """
    backs = [WAY_IN / 10, *np.arange(WAY_IN, APPROACH + 1e-9, WAY_IN)]  # from half a millimetre off
    further = (coal.Transform3s(reach.axes, centre + np.array([0.0, 0.0, back])) for back in backs)  # the object
    return all(reach.open_distance(reach.shape, where) > 0.0 for where in further)


@functools.lru_cache(maxsize=256)
def side_centre(item: BenchObject, grasp: str, table: bool = False) -> tuple[float, float, float] | None:
    """The object's centre [m] in the palm-sideways hand frame by the module's rule, or ``None`` if none qualifies.

    ``grasp``: 'power' or 'precision'; ``table``: the stand flush with a table (:func:`~.height.stand_clearance`).
    Computed once per process for each set of arguments.
    """
    reach = reach_of(item, SIDE_SPREAD, PRESHAPE, "side")
    across = item.half_extents[2] - pinch_height(item)  # hand y: the object's centre below the pinch plane
    near = hand_depth(SIDE_SPREAD, PRESHAPE) + item.half_extents[0]  # its x edge (world) on the knuckle housings
    for depth in np.arange(near, near + FURTHEST + 1e-9, STEP):
        centre = np.array([0.0, across, float(depth)])
        touches = {finger: reach.touch(finger, centre) for finger in PINCH}
        if any(not reach.opening < angle < reach.closed for angle in touches.values()):
            continue
        landed = [reach.first_touch(finger, centre) for finger in PINCH]
        if grasp == "precision" and any("distal" not in link for link, _ in landed):
            continue
        if _support_gap(reach, item, centre, touches, table) < STAND_MARGIN or not _way_in_clear(reach, centre):
            continue
        return (0.0, float(across), float(depth))
    return None


@functools.lru_cache(maxsize=256)
def approach_of(trial: Trial) -> str:
    """``"top"`` (palm down) or ``"side"`` (:func:`side_centre`): from above wherever the top-down rules find a grasp.

    A trial with its own ``spread`` (a study of the spread) is always grasped from above.
    """
    item = trial.item
    if trial.spread is not None:
        return "top"
    if top_down(item, spread_of(item), trial.grasp, trial.table) is not None:
        return "top"
    return "side" if side_centre(item, trial.grasp, trial.table) is not None else "top"


def trial_spread(trial: Trial) -> float:
    """The spread [rad] a trial's hand takes before closing: :data:`SIDE_SPREAD` in a side pinch, else the grasp's."""
    return SIDE_SPREAD if approach_of(trial) == "side" else trial.preshape_spread


def closing_fingers(trial: Trial) -> tuple[str, ...]:
    """The fingers a trial closes: :data:`PINCH` in a side pinch, else all three."""
    return PINCH if approach_of(trial) == "side" else ("F1", "F2", "F3")


def trial_reach(trial: Trial) -> tuple[Reach, np.ndarray]:
    """The trial's :class:`~bhgrasp.bench.reach.Reach` and its object's centre [m] in the hand frame at the grasp."""
    if approach_of(trial) == "side":
        return reach_of(trial.item, SIDE_SPREAD, PRESHAPE, "side"), np.array(
            side_centre(trial.item, trial.grasp, trial.table)
        )
    item, spread = trial.item, trial.preshape_spread
    opening, clearance = top_grasp(trial)
    return reach_of(item, spread, opening), grasp_centre(item, spread, clearance, opening)


def top_grasp(trial: Trial) -> tuple[float, float]:
    """(opening [rad], clearance [m]) of a trial from above (:func:`~bhgrasp.bench.opening.top_down`).

    Where the rules find no top-down grasp (a trial with its own spread, or one with no side pinch either): the
    pre-shape and the knuckles on the object's top (0), and the trial's failure says so
    (:data:`~bhgrasp.bench.metrics.NO_HEIGHT`).
    """
    found = top_down(trial.item, trial.preshape_spread, trial.grasp, trial.table)
    return (PRESHAPE, 0.0) if found is None else found


def trial_opening(trial: Trial) -> float:
    """The proximal angle [rad] of a trial's open hand: the pre-shape, or wider (:func:`top_grasp`) from above."""
    return PRESHAPE if approach_of(trial) == "side" else top_grasp(trial)[0]


def way_in(trial: Trial) -> np.ndarray:
    """The world direction (unit) in which the open hand moves to its grasp: down, or along the palm's normal."""
    return np.array([0.0, 0.0, -1.0]) if approach_of(trial) == "top" else ORIENTATIONS["side"][:, 2].copy()


__all__ = [
    "FURTHEST",
    "PINCH",
    "SIDE_SPREAD",
    "STEP",
    "WAY_IN",
    "approach_of",
    "closing_fingers",
    "finger_half_width",
    "pinch_height",
    "side_centre",
    "top_grasp",
    "trial_opening",
    "trial_reach",
    "trial_spread",
    "way_in",
]
