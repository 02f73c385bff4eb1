"""The wrist servo of a mounted hand (:func:`~bhgrasp.model.mount.mounted`): lift, carry, shake and place.

:class:`MountServo` drives the six mount coordinates c (x, y, z [m], yaw, pitch, roll [rad]) along a reference
(any :class:`~bhgrasp.motion.trajectories.Reference` of size 6: a :class:`~bhgrasp.motion.trajectories.Quintic` lift, a
:class:`~bhgrasp.motion.trajectories.Sinusoid` shake, ...) while another controller runs the fingers.  On the mount rows

    tau_m = [ID(q, v, a_ref)]_m - [tau_contact]_m + kp (c_d - c) + kd (c_dot_d - c_dot),

ID the nominal hand's inverse dynamics with a_ref = (c_dd_d on the mount, 0 on the fingers), tau_contact the joint
torques of the sensed contact forces (:meth:`~bhgrasp.grasp.sensing.ContactSensing.reaction_torques`: what a wrist
force-torque sensor gives an arm), so the servo carries the hand and its load and the PD only corrects the rest,
like an arm's joint servos.  That feedforward closes a loop through the environment when the grasped object also
rests on a support (squeezing it into a table raises the sensed force, which the servo then pushes harder
against: a gain-one loop that oscillates): ``compensate_load=False`` leaves the load to the PD, as for grasps from
a support (:mod:`~bhgrasp.bench`).  The finger rows are the finger controller's, or by default
the fingers' rows of the same
inverse dynamics plus a joint PD that holds them still (a finger under gravity compensation alone swings when the
wrist brakes: 0.8 rad on a 10 cm lift in 0.5 s).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
import pinocchio as pin

from bhgrasp._validation import as_vector
from bhgrasp.controllers.base import Controller, gain_vector
from bhgrasp.data import State
from bhgrasp.errors import InputError
from bhgrasp.grasp.sensing import ContactSensing
from bhgrasp.model.hand import Hand
from bhgrasp.model.mount import MOUNT_JOINTS
from bhgrasp.motion.trajectories import Reference

SERVO_KP = (2e4, 2e4, 2e4, 100.0, 100.0, 100.0)  # [N/m, N m/rad]: stiff, inside the 1 kHz loop's stability
SERVO_KD = (300.0, 300.0, 300.0, 1.0, 1.0, 1.0)  # [N s/m, N m s/rad]
_MOUNT_ROWS = np.zeros(6)  # the finger hold's torques on the mount rows


class MountServo(Controller):
    """Mount coordinates along ``reference``; the fingers under ``fingers`` (module docstring).

    Logs ``mount_error`` (c - c_d) and ``mount_reference`` (c_d), besides the finger controller's log entries.
    """

    def __init__(
        self,
        nominal: Hand,
        reference: Reference,
        fingers: Callable[[float, State], Any] | None = None,
        kp: Any = SERVO_KP,
        kd: Any = SERVO_KD,
        finger_gains: tuple[float, float] = (1.0, 0.01),
        compensate_load: bool = True,
    ) -> None:
        """Set up the servo.

        Args:
            nominal: The controller's model of the mounted hand.
            reference: Mount coordinates c_d(t) (size 6: x, y, z [m], yaw, pitch, roll [rad]).
            fingers: The finger controller, ``(t, state) -> tau`` (nv joint torques of the mounted hand; its mount
                rows are replaced), or ``None``: the fingers hold the configuration of the first call (the finger
                rows of the same inverse dynamics, plus a joint PD of ``finger_gains``; the PD takes their loads).
            kp, kd: Servo gains per mount coordinate (scalar or six values) [N/m, N m/rad], [N s/m, N m s/rad].
            finger_gains: (kp [N m/rad], kd [N m s/rad]) of the finger hold when ``fingers`` is ``None``.
            compensate_load: Feed the sensed contact load forward on the mount rows (module docstring).
        """
        super().__init__()
        if not isinstance(nominal, Hand) or nominal.joint_names[:6] != MOUNT_JOINTS:
            raise InputError(f"`nominal` must be a mounted hand (bhgrasp.model.mount.mounted(hand)), got {nominal!r}")
        if not isinstance(reference, Reference) or reference.size != 6:
            raise InputError(f"`reference` must be a Reference of size 6 (mount coordinates), got {reference!r}")
        self.nominal, self.reference, self.fingers = nominal, reference, fingers
        self.kp, self.kd = gain_vector(kp, 6, "kp"), gain_vector(kd, 6, "kd")
        self.finger_kp, self.finger_kd = finger_gains
        self.sensing = ContactSensing(nominal)
        self.compensate_load = bool(compensate_load)
        self._acceleration = np.zeros(nominal.nv)
        self._hold: np.ndarray | None = None

    def reset(self, state: State) -> None:
        """Reset the finger controller (or hold the fingers at ``state``'s configuration)."""
        self._hold = None
        if hasattr(self.fingers, "reset"):
            self.fingers.reset(state)

    def __call__(self, t: float, state: State) -> np.ndarray:
        """Joint torques [N m, N] of the mounted hand."""
        hand = self.nominal
        q, v = as_vector(state.q, "state.q", hand.nq), as_vector(state.v, "state.v", hand.nv)
        c_d, c_dot_d, c_dd_d = self.reference(t)
        self._acceleration[:6] = c_dd_d
        model = pin.rnea(hand.model, hand.data, q, v, self._acceleration)
        if self.fingers is not None:
            tau = as_vector(self.fingers(t, state), "finger torques", hand.nv).copy()
            log = getattr(self.fingers, "log", None)
            if isinstance(log, dict):
                self.log.update(log)
        else:  # hold the fingers where they were, against gravity, their loads and the mount's acceleration
            if self._hold is None:
                self._hold = q[6:].copy()
            hold = self.finger_kp * (q[6:] - self._hold) + self.finger_kd * v[6:]
            tau = model - np.concatenate((_MOUNT_ROWS, hold))
        load = self.sensing.reaction_torques(state)[:6] if self.compensate_load else 0.0
        tau[:6] = model[:6] - load - self.kp * (q[:6] - c_d) - self.kd * (v[:6] - c_dot_d)
        self.log["mount_error"], self.log["mount_reference"] = q[:6] - c_d, c_d
        return tau


__all__ = ["SERVO_KD", "SERVO_KP", "MountServo"]
