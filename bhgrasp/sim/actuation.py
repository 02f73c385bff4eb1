"""Actuation: how the simulator applies a hand's drive (its inputs, transmission, damping) and its joint friction.

An actuation model gives the simulator a transmission ``T`` (hand velocities ``v = T w`` for the driven
coordinates ``w``) and the joint torques its inputs produce, from the hand's drive model
(:mod:`bhgrasp.model.transmission`, shared with the controllers); it adds what only a simulation needs: saturation,
Coulomb joint friction, and the mode state carried from step to step.  Joints outside ``T``'s range are held
(their velocity is zero).  Passive joint damping and Coulomb friction are offered on both models; the BH8-280's
self-locking worms are :class:`BarrettActuation`'s own (a locked finger's column leaves ``T``).

- :class:`FullyActuated`: one torque per joint (the thesis' assumption), ``T = I``; optional saturation.
- :class:`BarrettActuation`: the BH8-280's four motors, TorqueSwitch (thesis 2.4.7) and self-locking worm drives,
  simulating :class:`~bhgrasp.barrett.transmission.BarrettTransmission` (the gear ratios, the breakaway and
  locking rules and their sources are there).  Modes: per finger 0 coupled, 1 broken away, 2 re-opening, then per
  finger 1 if its worm drive is locked (its joints held).  Inputs are motor torques [N m] at the motor shafts.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Sequence
from typing import Any

import numpy as np

from bhgrasp._validation import as_vector
from bhgrasp.barrett.transmission import (
    BREAKAWAY_TORQUE,
    MAX_MOTOR_TORQUE,
    MOTOR_DAMPING,
    WORM_EFFICIENCY,
    BarrettTransmission,
)
from bhgrasp.errors import InputError
from bhgrasp.model.hand import Hand
from bhgrasp.model.transmission import DirectDrive, Transmission, per_joint


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
        """Take the mode flags a :class:`~bhgrasp.data.state.State` carries (``None``: re-armed, as a run starts)."""
        if modes is None or len(modes) == 0:
            self.reset(q_hand)

    def begin(self, u: np.ndarray) -> None:  # noqa: B027  (optional hook)
        """Before each step, with the step's inputs ``u`` (after :meth:`restore`)."""

    def update(  # noqa: B027
        self, q_hand: np.ndarray, v_hand: np.ndarray, u: np.ndarray, drive_torques: np.ndarray, load: np.ndarray
    ) -> None:
        """After each step, with the drive's torques and the links' load.

        ``drive_torques``: the joint torques the drive delivered (inputs + reactions); ``load``: the same less the
        links' own inertial torques.
        """

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
        limit: float | Sequence[float] | None = None,
    ) -> None:
        """One torque per joint of ``hand``.

        Args:
            hand: The actuated hand.
            saturate: Clip each torque to ``hand.effort_limit``.
            damping: Passive viscous joint damping [N m s/rad], scalar or per joint.
            friction: Coulomb joint friction [N m], scalar or per joint.
            limit: Clip each torque to this [N m] instead (scalar or per joint; implies ``saturate``).
        """
        super().__init__(DirectDrive(hand, damping), friction)
        self.saturate = bool(saturate) or limit is not None
        self.limit = hand.effort_limit if limit is None else per_joint(limit, hand.nv, "limit")

    def joint_torques(self, u: np.ndarray) -> np.ndarray:
        """The inputs themselves (clipped to :attr:`limit` if ``saturate``)."""
        if self.saturate:
            return np.clip(u, -self.limit, self.limit)
        return np.array(u, dtype=float)

    def joint_damping(self) -> np.ndarray:
        """The passive damping (the array itself: one mode, nothing to build)."""
        return self.damping


class BarrettActuation(Actuation):
    """The BH8-280's 4 motors with spread coupling and TorqueSwitch breakaway (inputs: motor torques [N m]).

    On a mounted hand (:func:`~bhgrasp.model.mount.mounted`) the mount's joint torques follow the four motor torques.
    On the compiled engine a Simulator steps this model's rules in C++ (``src/barrett.cpp``, in the step's own call;
    ``tests/test_compiled_drive.py`` holds them to these hooks bit for bit); a subclass runs its hooks in Python.
    """

    FINGERS = ("F1", "F2", "F3")

    def __init__(
        self,
        hand: Hand,
        breakaway_torque: float = BREAKAWAY_TORQUE,
        saturate: bool = False,
        motor_damping: float = MOTOR_DAMPING,
        damping: float | Sequence[float] = 0.0,
        friction: float | Sequence[float] = 0.0,
        efficiency: float = WORM_EFFICIENCY,
        self_locking: bool = True,
    ) -> None:
        """Couple the Barrett hand's joints.

        Args:
            hand: A Barrett hand (joint names F1_spread ... F3_distal).
            breakaway_torque: Proximal load torque [N m] above which the TorqueSwitch breaks away (GraspIt!'s
                breakAwayTorque, 0.5 N m; the rule: :meth:`~bhgrasp.barrett.transmission.BarrettTransmission.switch`).
            saturate: Clip motor torques to the pucks' limit, :data:`~bhgrasp.barrett.transmission.MAX_MOTOR_TORQUE`
                (0.0213 N m, calibrated to Barrett's stalled fingertip force).
            motor_damping: Motor viscous damping at the shaft [N m s/rad] (its torque-speed line); it acts on
                each driven coordinate times the square of its gear ratio.  Default: 0.0213 N m / 307 rad/s.
            damping: Viscous joint damping [N m s/rad].
            friction: Coulomb joint friction [N m].
            efficiency: Forward efficiency of the finger worm drives (default 0.5, the self-locking bound).
            self_locking: Whether the finger worm drives self-lock (the real hand's are "non-backdrivable").
        """
        drive = BarrettTransmission(hand, breakaway_torque, motor_damping, damping, efficiency, self_locking)
        super().__init__(drive, friction)
        self.saturate = bool(saturate)
        self.mode = np.zeros(3, dtype=int)  # per finger: 0 coupled, 1 broken away, 2 re-opening the proximal
        self.locked = np.zeros(3, dtype=bool)  # per finger: its worm drive holds its joints

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
    def broken(self) -> np.ndarray:
        """Per finger: whether its TorqueSwitch is not armed (broken away or re-opening)."""
        return self.mode > 0

    @property
    def self_locking(self) -> bool:
        """Whether the finger worm drives self-lock."""
        return self.drive.self_locking

    def parameters(self) -> tuple:
        """What the drive's rules and terms depend on besides the modes (a key: its compiled copy follows a change)."""
        drive = self.drive
        return (
            drive.breakaway_torque,
            drive.motor_damping,
            drive.efficiency,
            drive.self_locking,
            self.saturate,
            self.damping.tobytes(),
            self.friction.tobytes(),
        )

    def take(self, modes: tuple[int, ...]) -> None:
        """Set the TorqueSwitch modes and worm locks from 6 integers (a compiled step's)."""
        self.mode[:] = modes[:3]
        self.locked[:] = modes[3:]

    def reset(self, q_hand: np.ndarray) -> None:
        """Re-arm every TorqueSwitch; every worm drive starts unlocked."""
        self.mode[:] = 0
        self.locked[:] = False

    def restore(self, modes: np.ndarray | None, q_hand: np.ndarray) -> None:
        """Take the modes a state carries (:func:`barrett_modes`; ``None``: re-armed; no lock without self-locking).

        Raises:
            InputError: Modes that are not 3 TorqueSwitch values in (0, 1, 2), possibly with 3 worm locks.
        """
        values = barrett_modes(modes)
        self.mode[:] = values[:3]
        self.locked[:] = values[3:] if self.drive.self_locking else (0, 0, 0)  # no worm holds: its locks mean nothing

    def _modes(self) -> np.ndarray:
        return self.mode

    def transmission(self) -> np.ndarray:
        """``T`` in the current TorqueSwitch modes without the columns of locked finger drives (their joints hold)."""
        columns = self.drive.matrix(self.mode)
        if not self.locked.any():
            return columns
        return np.delete(columns, 1 + np.flatnonzero(self.locked), axis=1)

    def delivered(self, u: np.ndarray) -> np.ndarray:
        """The inputs the pucks deliver: clipped to their limit if ``saturate`` (a mount's joints are not)."""
        if not self.saturate:
            return u
        u = u.copy()
        u[:4] = np.minimum(np.maximum(u[:4], -MAX_MOTOR_TORQUE), MAX_MOTOR_TORQUE)  # np.clip's values, a third the cost
        return u

    def joint_torques(self, u: np.ndarray) -> np.ndarray:
        """Motor torques (clipped to the puck limit if ``saturate``) through the gears [N m]."""
        return self.drive.joint_torques(self.delivered(u), self.mode)

    def begin(self, u: np.ndarray) -> None:
        """An idle finger motor's worm is locked for the step: its load cannot turn it, not even for one step."""
        if self.drive.self_locking:
            self.locked |= u[1:4] == 0.0

    def update(
        self, q_hand: np.ndarray, v_hand: np.ndarray, u: np.ndarray, drive_torques: np.ndarray, load: np.ndarray
    ) -> None:
        """The TorqueSwitch and worm-lock rules, with the motor torques the pucks delivered.

        (``switch`` and ``locks`` of :class:`~bhgrasp.barrett.transmission.BarrettTransmission`.)
        """
        u = self.delivered(u)
        modes = self.drive.switch(self.mode, q_hand, u, load)
        locked = self.locked & (modes == self.mode)  # a finger on a new coordinate starts unlocked
        self.locked[:] = self.drive.locks(locked, modes, v_hand, u, drive_torques)
        self.mode[:] = modes

    def modes(self) -> np.ndarray:
        """Per finger the TorqueSwitch (0 armed, 1 broken away, 2 re-opening), then its worm lock (1.0: locked).

        Without ``self_locking``: the 3 TorqueSwitch values only.
        """
        if not self.drive.self_locking:
            return self.mode.astype(float)
        return np.concatenate((self.mode, self.locked)).astype(float)


def barrett_modes(flags: Any) -> tuple[int, ...]:
    """A state's Barrett flags as 6 integers: the TorqueSwitch of F1, F2, F3 (0, 1, 2), then their worm locks (0, 1).

    ``None`` or empty: re-armed and unlocked; 3 values: unlocked; a lock is any non-zero value.

    Raises:
        InputError: Not 3 or 6 numbers, or a TorqueSwitch value other than 0, 1 or 2.
    """
    if flags is None:
        return (0, 0, 0, 0, 0, 0)
    try:
        values = np.asarray(flags, dtype=float).reshape(-1).tolist()
    except (TypeError, ValueError) as error:
        raise InputError(f"Barrett modes must be numbers, got {flags!r}") from error
    if not values:
        return (0, 0, 0, 0, 0, 0)
    if len(values) not in (3, 6) or any(value not in (0, 1, 2) for value in values[:3]):
        raise InputError(f"Barrett modes must be 3 TorqueSwitch values in (0, 1, 2) and 3 worm locks, got {values}")
    locks = [1 if lock else 0 for lock in values[3:6]] if len(values) == 6 else [0, 0, 0]
    return (int(values[0]), int(values[1]), int(values[2]), *locks)


__all__ = [
    "Actuation",
    "BarrettActuation",
    "FullyActuated",
    "barrett_modes",
]
