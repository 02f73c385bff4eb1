"""The grasp chosen for the motion asked: the first BH8-280 pinch of the demo's box that makes the requested offset.

Candidates (:data:`PINCHES`, in order): the thesis' pinch (F1 and F2 50 mm apart, the spread on its stop) and a pinch
with the spread off its stop (:data:`~bhgrasp.scenarios.box_grasp.OFF_STOP_SPACING`), which can also turn the box
about y.  A pinch makes an offset when the offset lies in its manipulable space (no contact slides or rolls, no joint
passes its limit: :meth:`~bhgrasp.scenarios.box_grasp.BoxGrasp.manipulable_space`) and its path keeps the box off
the pedestal (:meth:`~bhgrasp.scenarios.box_grasp.BoxGrasp.check_clearance`).  Both are checked before anything is
simulated; the first pinch that passes is chosen, and the choice keeps why the ones before it were refused.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from bhgrasp.errors import UnreachableError
from bhgrasp.scenarios.box_grasp import KNUCKLE_SPACING, OFF_STOP_SPACING, BoxGrasp, box_grasp

PINCHES = (
    ("pinch, spread on its stop (thesis)", KNUCKLE_SPACING),
    ("pinch, spread off its stop", OFF_STOP_SPACING),
)
"""(label, F1-F2 contact spacing [m]) of the pinches tried, in order."""


@dataclass(frozen=True)
class GraspChoice:
    """The grasp a motion was given to, and why the grasps tried before it were refused.

    Attributes:
        label: The chosen grasp: a pinch of :data:`PINCHES`, the grasp the caller gave, or a synthesised candidate
            (:func:`~bhgrasp.scenarios.object_choice.grasp_for_motion`).
        finger_spacing: Its F1-F2 contact spacing [m] (``None`` for another hand's or a synthesised grasp).
        refused: (label, reason) of each grasp tried before it.
    """

    label: str
    finger_spacing: float | None
    refused: tuple[tuple[str, str], ...] = ()

    def summary(self) -> str:
        """One line per grasp tried: refused ones with their reason, then the chosen one."""
        lines = [f"refused {label}: {reason}" for label, reason in self.refused]
        spacing = "" if self.finger_spacing is None else f" ({1e3 * self.finger_spacing:.1f} mm between F1 and F2)"
        return "\n".join([*lines, f"chosen {self.label}{spacing}"])


def checked_pinch(setup: Any, offset: Any) -> None:
    """Raise :class:`UnreachableError` unless ``setup``'s grasp makes ``offset`` (manipulable space, clearance).

    ``setup``: a :class:`~bhgrasp.scenarios.box_grasp.BoxGrasp` or an
    :class:`~bhgrasp.scenarios.object_grasp.ObjectGrasp` (both offer the two checks).
    """
    setup.manipulable_space().check(offset)
    setup.check_clearance(offset)


def given_grasp(setup: BoxGrasp, offset: Any, finger_spacing: float | None) -> GraspChoice:
    """The caller's grasp (``finger_spacing`` [m] for the Barrett pinch, ``None`` for another hand), checked."""
    checked_pinch(setup, offset)
    label = "the given pinch" if finger_spacing is not None else f"the {setup.hand.name} scene's grasp"
    return GraspChoice(label, None if finger_spacing is None else float(finger_spacing))


def choose_pinch(mass: float, offset: Any, stiffness: float, **plant: Any) -> tuple[BoxGrasp, GraspChoice]:
    """The first pinch of :data:`PINCHES` that makes ``offset``, and the choice.

    The pinches grasp the demo's box of ``mass`` [kg] (``plant`` as :func:`~bhgrasp.scenarios.box_grasp.box_grasp`
    takes it).

    Raises:
        UnreachableError: No pinch makes it; the message gives each pinch's reason (its ``result``: the first
            pinch's nearest offset, where it gave one).
    """
    refused: list[tuple[str, str]] = []
    nearest = None
    for label, spacing in PINCHES:
        setup = box_grasp(mass=mass, stiffness=stiffness, finger_spacing=spacing, **plant)
        try:
            checked_pinch(setup, offset)
        except UnreachableError as error:
            refused.append((label, str(error)))
            nearest = error.result if nearest is None else nearest
            continue
        return setup, GraspChoice(label, spacing, tuple(refused))
    motion = np.round(np.asarray(offset, dtype=float), 6).tolist()
    reasons = "; ".join(f"{label}: {reason}" for label, reason in refused)
    raise UnreachableError(f"no BH8-280 pinch of this box makes the motion {motion}. {reasons}", nearest)


__all__ = ["PINCHES", "GraspChoice", "checked_pinch", "choose_pinch", "given_grasp"]
