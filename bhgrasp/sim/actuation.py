"""Actuation: how the simulator applies a hand's drive (its inputs, transmission, damping) and its joint friction.

An actuation model gives the simulator a transmission ``T`` (hand velocities ``v = T w`` for the driven
coordinates ``w``) and the joint torques its inputs produce, from the hand's drive model
(:mod:`bhgrasp.transmission`, shared with the controllers); it adds what only a simulation needs: saturation,
Coulomb joint friction, and the mode state carried from step to step.  Joints outside ``T``'s range are held
(their velocity is zero).  Passive joint damping and friction (the real hand's worm drives are not
back-drivable) are offered on both models.

- :class:`FullyActuated`: one torque per joint (the thesis' assumption), ``T = I``; optional saturation.
- :class:`BarrettActuation`: the BH8-280's four motors and TorqueSwitch (thesis 2.4.7), simulating
  :class:`~bhgrasp.barrett.transmission.BarrettTransmission` (the gear ratios, the breakaway rule and their
  sources are there).  Modes per finger: 0 coupled, 1 broken away, 2 re-opening.  Inputs are motor torques [N m]
  at the motor shafts.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Sequence

import numpy as np

from bhgrasp._validation import as_vector
from bhgrasp.barrett.transmission import (  # noqa: F401  (the drive's constants, importable from here as before)
    BREAKAWAY_TORQUE,
    DISTAL_ALONE_RATIO,
    DISTAL_RATIO,
    MAX_MOTOR_SPEED,
    MAX_MOTOR_TORQUE,
    MOTOR_DAMPING,
    PROXIMAL_RATIO,
    SPREAD_RATIO,
    BarrettTransmission,
)
from bhgrasp.errors import InputError
from bhgrasp.hand import Hand
from bhgrasp.transmission import DirectDrive, Transmission, per_joint


class Actuation(ABC):
    """Base of the actuation models: a drive (:attr:`drive`) simulated with saturation, friction and modes."""

    saturate: bool = False  # whether inputs are clipped to their limits
    motor_damping: float | None = None  # [N m s/rad] at the motor shafts, for drives with motors

    def __init__(self, drive: Transmission, friction: float | Sequence[float] = 0.0):
        """Simulate ``drive``.

        Args:
            drive: The hand's drive model; its ``passive_damping`` is this actuation's :attr:`damping`.
            friction: Coulomb joint friction [N m], scalar or per joint (regularised over 1e-3 rad/s).
        """
        if not isinstance(drive, Transmission):
            raise InputError(f"`drive` must be a bhgrasp Transmission (e.g. DirectDrive(hand)), got {drive!r}")
        self.drive = drive
        self.hand = drive.hand
        self.damping = drive.passive_damping
        self.friction = per_joint(friction, drive.hand.nv, "friction")
        self._inputs = drive.n_inputs  # read at every step: a drive's input count is fixed

    @property
    def n_inputs(self) -> int:
        """Number of control inputs."""
        return self._inputs

    def transmission(self) -> np.ndarray:
        """``T`` (nv_hand, n_driven): hand velocities = ``T @`` driven velocities, in the current mode."""
        return self.drive.matrix(self._modes())

    @abstractmethod
    def joint_torques(self, u: np.ndarray) -> np.ndarray:
        """Joint torques [N m] that the inputs ``u`` apply in the current mode (before coupling reactions)."""

    def reset(self, q_hand: np.ndarray) -> None:  # noqa: B027  (optional hook)
        """Start of a run at hand configuration ``q_hand`` (mode switches re-armed)."""

    def restore(self, modes: np.ndarray | None, q_hand: np.ndarray) -> None:
        """Take the mode flags a :class:`~bhgrasp.sim.state.State` carries (``None``: re-armed, as a run starts)."""
        if modes is None or len(modes) == 0:
            self.reset(q_hand)

    def update(self, q_hand: np.ndarray, v_hand: np.ndarray, u: np.ndarray, drive_torques: np.ndarray) -> None:  # noqa: B027
        """After each step: ``drive_torques`` are the joint torques the drive delivered (inputs + reactions)."""

    def modes(self) -> np.ndarray:
        """Numeric mode flags to record (e.g. TorqueSwitch broken per finger); empty if none (a fresh array)."""
        return np.zeros(0)

    def _modes(self) -> np.ndarray | None:
        """The current modes as the drive model reads them (``None``: it has one mode)."""
        return None

    def joint_damping(self) -> np.ndarray:
        """Viscous damping per joint [N m s/rad] in the current mode (passive joints + drive), for the solver."""
        return self.drive.joint_damping(self._modes())

    def check_input(self, u: object) -> np.ndarray:
        """Validate a control input vector."""
        return as_vector(u, "u", self.n_inputs)


class FullyActuated(Actuation):
    """One torque per joint [N m] (the thesis' assumption), optionally saturated at the hand's effort limits."""

    def __init__(
        self,
        hand: Hand,
        saturate: bool = False,
        damping: float | Sequence[float] = 0.0,
        friction: float | Sequence[float] = 0.0,
    ) -> None:
        """One torque per joint of ``hand``.

        Args:
            hand: The actuated hand.
            saturate: Clip each torque to ``hand.effort_limit``.
            damping: Passive viscous joint damping [N m s/rad], scalar or per joint.
            friction: Coulomb joint friction [N m], scalar or per joint.
        """
        super().__init__(DirectDrive(hand, damping), friction)
        self.saturate = bool(saturate)

    def joint_torques(self, u: np.ndarray) -> np.ndarray:
        """The inputs themselves (clipped to the effort limits if ``saturate``)."""
        if self.saturate:
            limit = self.hand.effort_limit
            return np.clip(u, -limit, limit)
        return np.array(u, dtype=float)

    def joint_damping(self) -> np.ndarray:
        """The passive damping (the array itself: one mode, nothing to build)."""
        return self.damping


class BarrettActuation(Actuation):
    """The BH8-280's 4 motors with spread coupling and TorqueSwitch breakaway (inputs: motor torques [N m]).

    On a mounted hand (:func:`~bhgrasp.mount.mounted`) the mount's joint torques follow the four motor torques.
    """

    FINGERS = ("F1", "F2", "F3")

    def __init__(
        self,
        hand: Hand,
        breakaway_torque: float = BREAKAWAY_TORQUE,
        saturate: bool = False,
        motor_damping: float = MOTOR_DAMPING,
        blocked_speed: float = 0.02,
        damping: float | Sequence[float] = 0.0,
        friction: float | Sequence[float] = 0.0,
    ) -> None:
        """Couple the Barrett hand's joints.

        Args:
            hand: A Barrett hand (joint names F1_spread ... F3_distal).
            breakaway_torque: Proximal drive torque [N m] above which the TorqueSwitch breaks away (GraspIt!'s
                breakAwayTorque, 0.5 N m).
            saturate: Clip motor torques to the puck limit, 0.11 N m (MT 2200 / IPNM 20000).
            motor_damping: Motor viscous damping at the shaft [N m s/rad] (its torque-speed line); it acts on
                each driven coordinate times the square of its gear ratio.  Default: 0.11 N m / 307 rad/s.
            blocked_speed: Proximal speed [rad/s] below which the proximal link counts as blocked; breakaway needs
                a blocked link (a start-up torque transient of a moving finger does not break the switch).
            damping: Viscous joint damping [N m s/rad].
            friction: Coulomb joint friction [N m].
        """
        super().__init__(BarrettTransmission(hand, breakaway_torque, motor_damping, blocked_speed, damping), friction)
        self.saturate = bool(saturate)
        self.mode = np.zeros(3, dtype=int)  # per finger: 0 coupled, 1 broken away, 2 re-opening the proximal

    # the drive's parameters, read from it (one source for the Python rule and the batch's C++ copy)
    @property
    def breakaway_torque(self) -> float:
        """Proximal drive torque [N m] above which the TorqueSwitch breaks away."""
        return self.drive.breakaway_torque

    @property
    def motor_damping(self) -> float:
        """Motor viscous damping at the shaft [N m s/rad]."""
        return self.drive.motor_damping

    @property
    def blocked_speed(self) -> float:
        """Proximal speed [rad/s] below which the proximal link counts as blocked."""
        return self.drive.blocked_speed

    @property
    def broken(self) -> np.ndarray:
        """Per finger: whether its TorqueSwitch is not armed (broken away or re-opening)."""
        return self.mode > 0

    def reset(self, q_hand: np.ndarray) -> None:
        """Re-arm every TorqueSwitch."""
        self.mode[:] = 0

    def restore(self, modes: np.ndarray | None, q_hand: np.ndarray) -> None:
        """Take the TorqueSwitch modes a state carries (``None``: every switch re-armed)."""
        if modes is None or len(modes) == 0:
            self.reset(q_hand)
        else:
            self.mode[:] = np.asarray(modes, dtype=int)

    def _modes(self) -> np.ndarray:
        return self.mode

    def joint_torques(self, u: np.ndarray) -> np.ndarray:
        """Motor torques (clipped to the puck limit if ``saturate``) through the gears [N m]."""
        if self.saturate:
            u = u.copy()
            u[:4] = np.clip(u[:4], -MAX_MOTOR_TORQUE, MAX_MOTOR_TORQUE)  # the pucks; a mount's joints are not
        return self.drive.joint_torques(u, self.mode)

    def update(self, q_hand: np.ndarray, v_hand: np.ndarray, u: np.ndarray, drive_torques: np.ndarray) -> None:
        """The TorqueSwitch rule (:meth:`~bhgrasp.barrett.transmission.BarrettTransmission.switch`)."""
        self.mode[:] = self.drive.switch(self.mode, q_hand, v_hand, u, drive_torques)

    def modes(self) -> np.ndarray:
        """TorqueSwitch state per finger: 0 armed (coupled), 1 broken away, 2 re-opening the proximal link."""
        return self.mode.astype(float)


__all__ = [
    "Actuation",
    "BarrettActuation",
    "FullyActuated",
]
