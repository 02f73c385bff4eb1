"""Motor commands from any joint-torque controller, for a drive with fewer inputs than joints.

:class:`MotorCommands` adapts a joint-torque controller to a drive such as the BH8-280's four motors
(:mod:`bhgrasp.barrett.transmission`): u solves T^T B u = T^T tau, i.e. the motors do the same work as tau on every
motion the transmission T allows (B: joint torques per unit motor input).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from bhgrasp.controllers.base import Controller
from bhgrasp.data import State
from bhgrasp.errors import InputError
from bhgrasp.model.transmission import Transmission


class MotorCommands(Controller):
    """Run a joint-torque controller through a drive with fewer inputs: u with T^T B u = T^T (tau + D v).

    The drive model (:class:`~bhgrasp.model.transmission.Transmission`, e.g. the BH8-280's
    :class:`~bhgrasp.barrett.transmission.BarrettTransmission`) is the hand's, not the simulator's: its mode (the
    TorqueSwitch states) is read from the state's ``actuation_modes``, as a real hand's driver reports them.  D v
    compensates the drive's known viscous damping (for the BH8-280 mostly the motors' torque-speed line reflected
    through 125:1 gears, ~5.6 N m s/rad at a proximal joint, which a model-based joint law ignores).
    """

    def __init__(self, controller: Controller | Callable[[float, State], Any], drive: Transmission) -> None:
        """Wrap ``controller`` (a :class:`Controller` or any ``(t, state) -> tau`` callable) for ``drive``."""
        super().__init__()
        if not isinstance(drive, Transmission):
            raise InputError(
                f"`drive` must be a bhgrasp Transmission (e.g. BarrettTransmission(hand), or a simulator "
                f"actuation's .drive), got {drive!r}"
            )
        self.controller = controller
        self.drive = drive
        log = getattr(controller, "log", None)
        if isinstance(log, dict):
            self.log = log

    def reset(self, state: State) -> None:
        """Reset the wrapped controller (if it has a ``reset``)."""
        if hasattr(self.controller, "reset"):
            self.controller.reset(state)

    def __call__(self, t: float, state: State) -> np.ndarray:
        """Motor inputs for the wrapped controller's joint torques."""
        modes = state.actuation_modes
        tau = self.controller(t, state) + self.drive.joint_damping(modes) * np.asarray(state.v, dtype=float)
        return self.drive.motor_inputs(tau, modes)


__all__ = ["MotorCommands"]
