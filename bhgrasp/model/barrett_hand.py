"""The packaged Barrett BH8-280 model (``urdf/barrett_hand.urdf``, sources in ``urdf/README.md``)."""

from __future__ import annotations

from collections.abc import Sequence

import pinocchio as pin

from bhgrasp.model import urdf
from bhgrasp.model.hand import STANDARD_GRAVITY, Hand
from bhgrasp.model.resources import barrett_urdf_path

BARRETT_FINGERTIPS = {"F1": "F1_tip", "F2": "F2_tip", "F3": "F3_tip"}


class BarrettHand(Hand):
    """The packaged Barrett BH8-280 (``urdf/barrett_hand.urdf``): 8 independent joints, fingers F1, F2, F3.

    Joint order: F1_spread, F1_proximal, F1_distal, F2_spread, F2_proximal, F2_distal, F3_proximal, F3_distal.
    """

    def __init__(
        self,
        *,
        base_placement: pin.SE3 | None = None,
        gravity: Sequence[float] = STANDARD_GRAVITY,
        name: str = "BarrettHand BH8-280",
    ) -> None:
        """Load the packaged URDF; ``base_placement`` and ``gravity`` as for :class:`Hand`."""
        path = barrett_urdf_path()
        model, _ = urdf.build_model(path)
        super().__init__(
            model, BARRETT_FINGERTIPS, name=name, base_placement=base_placement, gravity=gravity, urdf_path=path
        )
