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
wrist brakes: 0.8 rad on a 10 cm lift in 0.5 s), or ``"zero"``: zero on the finger rows, for a hand whose fingers
another input drives (e.g. the BH8-280's pucks, :class:`~bhgrasp.barrett.commands.BarrettDriver`).

Two engines: ``"compiled"`` runs a call in one call of ``bhgrasp._core.WristServo`` (``src/wrist_servo.cpp``,
:mod:`bhgrasp.controllers._wrist_kernel`) for a servo on a pose path (a
:class:`~bhgrasp.motion.wrist.MountReference` of a :class:`~bhgrasp.motion.pose_references.PosePath` or
:class:`~bhgrasp.motion.pose_references.PoseMotion`, possibly in a :class:`~bhgrasp.motion.held.HeldReference`)
without load feedforward, the fingers held or zero; ``"python"`` is the readable twin (``tests/test_wrist_servo.py``
holds them together to round-off).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
import pinocchio as pin

from bhgrasp._native import engine_name, required_core
from bhgrasp._validation import as_vector
from bhgrasp.controllers._wrist_kernel import CompiledWristServo, covers
from bhgrasp.controllers.base import Controller, gain_vector
from bhgrasp.data import State
from bhgrasp.errors import FrozenSettingError, InputError
from bhgrasp.grasp.sensing import ContactSensing
from bhgrasp.model.hand import Hand
from bhgrasp.model.mount import MOUNT_JOINTS
from bhgrasp.motion.trajectories import Reference, time_of

SERVO_KP = (2e4, 2e4, 2e4, 100.0, 100.0, 100.0)  # [N/m, N m/rad]: stiff, inside the 1 kHz loop's stability
SERVO_KD = (300.0, 300.0, 300.0, 1.0, 1.0, 1.0)  # [N s/m, N m s/rad]
_MOUNT_ROWS = np.zeros(6)  # the finger hold's torques on the mount rows
SETUP = ("nominal", "reference", "fingers", "kp", "kd", "finger_kp", "finger_kd", "compensate_load", "engine")


class MountServo(Controller):
    """Mount coordinates along ``reference``; the fingers under ``fingers`` (module docstring).

    Logs ``mount_error`` (c - c_d) and ``mount_reference`` (c_d), besides the finger controller's log entries.
    """

    def __init__(
        self,
        nominal: Hand,
        reference: Reference,
        fingers: Callable[[float, State], Any] | str | None = None,
        kp: Any = SERVO_KP,
        kd: Any = SERVO_KD,
        finger_gains: tuple[float, float] = (1.0, 0.01),
        compensate_load: bool = True,
        engine: str | None = None,
    ) -> None:
        """Set up the servo.

        Args:
            nominal: The controller's model of the mounted hand.
            reference: Mount coordinates c_d(t) (size 6: x, y, z [m], yaw, pitch, roll [rad]).
            fingers: The finger controller, ``(t, state) -> tau`` (nv joint torques of the mounted hand; its mount
                rows are replaced), or ``None``: the fingers hold the configuration of the first call (the finger
                rows of the same inverse dynamics, plus a joint PD of ``finger_gains``; the PD takes their loads),
                or ``"zero"``: zero torques on the finger rows.
            kp, kd: Servo gains per mount coordinate (scalar or six values) [N/m, N m/rad], [N s/m, N m s/rad].
            finger_gains: (kp [N m/rad], kd [N m s/rad]) of the finger hold when ``fingers`` is ``None``.
            compensate_load: Feed the sensed contact load forward on the mount rows (module docstring).
            engine: ``None`` (default): the default engine (:func:`~bhgrasp._native.default_engine`) where the
                compiled servo covers the set-up (module docstring), else the Python one; ``"compiled"`` (raises if
                the core does not load or the set-up is not covered) or ``"python"``.

        Raises:
            InputError: A bad argument, or ``engine="compiled"`` with a set-up it does not cover.
            CompiledEngineUnavailable: ``engine="compiled"`` but ``bhgrasp._core`` does not load.
        """
        super().__init__()
        if not isinstance(nominal, Hand) or nominal.joint_names[:6] != MOUNT_JOINTS:
            raise InputError(f"`nominal` must be a mounted hand (bhgrasp.model.mount.mounted(hand)), got {nominal!r}")
        if not isinstance(reference, Reference) or reference.size != 6:
            raise InputError(f"`reference` must be a Reference of size 6 (mount coordinates), got {reference!r}")
        if not (fingers is None or fingers == "zero" or callable(fingers)):
            raise InputError(f"`fingers` must be a controller (t, state) -> tau, None or 'zero', got {fingers!r}")
        self.nominal, self.reference, self.fingers = nominal, reference, fingers
        self.kp, self.kd = gain_vector(kp, 6, "kp"), gain_vector(kd, 6, "kd")
        self.kp.flags.writeable = self.kd.flags.writeable = False
        self.finger_kp, self.finger_kd = finger_gains
        self.sensing = ContactSensing(nominal)
        self.compensate_load = bool(compensate_load)
        self._acceleration = np.zeros(nominal.nv)
        self._hold: np.ndarray | None = None
        chosen, uncovered = engine_name(engine), covers(self)
        if engine == "compiled" and uncovered:
            raise InputError(f"engine='compiled' does not cover {uncovered}; pass engine='python' (or None)")
        self._compiled = None
        if chosen == "compiled" and not uncovered:
            self._compiled = CompiledWristServo(self, required_core("the compiled wrist servo"))
        self.engine = "python" if self._compiled is None else "compiled"

    def __setattr__(self, name: str, value: Any) -> None:
        """The set-up (:data:`SETUP`) is fixed once built: both engines read it from then on."""
        if name in SETUP and "engine" in self.__dict__:
            raise FrozenSettingError(
                f"MountServo.{name} cannot change after the servo is built (its compiled engine copied it); build a "
                f"new MountServo"
            )
        object.__setattr__(self, name, value)

    def __getstate__(self) -> dict:
        """Copies and pickles rebuild the compiled servo, holding the fingers where the original holds them."""
        return {**self.__dict__, "_compiled": None, "_rebuild": self._compiled is not None}

    def __setstate__(self, state: dict) -> None:
        """Restore a copy, building its own compiled servo if the original had one."""
        rebuild = state.pop("_rebuild", False)
        self.__dict__.update(state)
        if rebuild:
            self._compiled = CompiledWristServo(self, required_core("the compiled wrist servo"))
            if self._hold is not None:
                self._compiled.kernel.hold(self._hold)

    def reset(self, state: State) -> None:
        """Reset the finger controller (or hold the fingers at ``state``'s configuration)."""
        self._hold = None
        if self._compiled is not None:
            self._compiled.reset()
        if hasattr(self.fingers, "reset"):
            self.fingers.reset(state)

    def __call__(self, t: float, state: State) -> np.ndarray:
        """Joint torques [N m, N] of the mounted hand."""
        hand = self.nominal
        q, v = as_vector(state.q, "state.q", hand.nq), as_vector(state.v, "state.v", hand.nv)
        if self._compiled is not None:
            if self.fingers is None and self._hold is None:
                self._hold = q[6:].copy()  # as the kernel takes it (a copy carries it: __setstate__)
            tau, c_d, error = self._compiled.torques(time_of(t), q, v)
            self.log["mount_error"], self.log["mount_reference"] = error, c_d
            return tau
        c_d, c_dot_d, c_dd_d = self.reference(t)
        self._acceleration[:6] = c_dd_d
        model = pin.rnea(hand.model, hand.data, q, v, self._acceleration)
        if self.fingers == "zero":
            tau = np.zeros(hand.nv)
        elif self.fingers is not None:
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


__all__ = ["SERVO_KD", "SERVO_KP", "SETUP", "MountServo"]
