"""Thesis chapter 2: the fingertip workspace of Table 2.2 beside ours.

The thesis' frame is not ours: its (2.2) puts the palm-normal (approach) direction on y (y = h + ...), the finger's
radial direction on z and the spread (sideways) direction on x.  To compare, our world frame W (z = palm normal,
F3 on +y) is mapped to the thesis' axes as  x_thesis = x_W,  y_thesis = z_W,  z_thesis = y_W  for F1 and F2, whose
radial direction at zero spread is -y_W: so z_thesis = -y_W for them.  The thesis does not say where its origin
is; only the extents (max - min) are therefore comparable without assumptions.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bhgrasp.model.hand import Hand
from bhgrasp.model.ik import workspace

# Thesis Table 2.2 [m]: finger -> ((x_min, x_max), (y_min, y_max), (z_min, z_max)); F2's x range is printed
# as [0.02, -0.18] (mirrored F1) and F3's x as 0.
THESIS_TABLE_2_2 = {
    "F1": ((-0.02, 0.18), (0.10, 0.18), (-0.15, 0.15)),
    "F2": ((-0.18, 0.02), (0.10, 0.18), (-0.15, 0.15)),
    "F3": ((0.0, 0.0), (0.10, 0.18), (0.05, 0.15)),
}


@dataclass(frozen=True)
class WorkspaceRow:
    """One finger's workspace bounds in the thesis' axes [m]: ours (sampled) and the thesis'."""

    finger: str
    ours: np.ndarray  # (3, 2): (min, max) per thesis axis
    thesis: np.ndarray  # (3, 2)

    def format(self) -> str:
        """One line per axis: ours beside the thesis', with extents."""
        cells = []
        for axis, (mine, theirs) in zip("xyz", zip(self.ours, self.thesis)):
            cells.append(
                f"{self.finger} {axis}: ours [{mine[0]:+.3f}, {mine[1]:+.3f}] (extent {mine[1] - mine[0]:.3f})"
                f"   thesis [{theirs[0]:+.3f}, {theirs[1]:+.3f}] (extent {theirs[1] - theirs[0]:.3f})"
            )
        return "\n".join(cells)


def workspace_table(hand: Hand, n: int = 20_000, seed: int = 0) -> list[WorkspaceRow]:
    """Sample each Barrett finger's workspace and express its bounds in the thesis' axes (see module doc)."""
    rows = []
    for finger in ("F1", "F2", "F3"):
        points = workspace(hand, finger, n, rng=seed).points
        radial_sign = 1.0 if finger == "F3" else -1.0
        thesis_axes = np.column_stack((points[:, 0], points[:, 2], radial_sign * points[:, 1]))
        ours = np.column_stack((thesis_axes.min(axis=0), thesis_axes.max(axis=0)))
        rows.append(WorkspaceRow(finger, ours, np.array(THESIS_TABLE_2_2[finger])))
    return rows
