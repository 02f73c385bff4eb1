"""Actuation: how control inputs become joint torques, and which joints move together.

An actuation model gives the simulator a transmission ``T`` (hand velocities ``v = T w`` for the driven
coordinates ``w``) and the joint torques its inputs produce.  Joints outside ``T``'s range are held (their
velocity is zero).  Passive joint damping and friction (the real hand's worm drives are not back-drivable) are
offered on both models.

- :class:`FullyActuated`: one torque per joint (the thesis' assumption), ``T = I``; optional saturation.
- :class:`BarrettActuation`: the BH8-280's four motors (thesis 2.4.7, ratio dynamics and TorqueSwitch).  The
  spread motor turns F1 and F2 spread together (17.5:1 each); each finger motor drives its proximal joint at
  125:1 and its distal joint at 375:1 relative to the proximal link (distal = proximal / 3) until the
  TorqueSwitch breaks away: when the proximal link is blocked while closing and the torque it needs from the
  drive exceeds ``breakaway_torque``, the proximal joint holds and the motor drives the distal joint alone
  through its 93.75:1 worm.  A motor torque-speed line (viscous motor damping reflected through the gears) sets
  the speeds.  Opening a broken finger drives the fingertip back to its stop, then the proximal link
  alone to its open stop, where the switch re-arms (mode 0 coupled, 1 broken away, 2 re-opening).
  Inputs are motor torques [N m] at the motor shafts.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Sequence

import numpy as np

from bhgrasp._validation import as_positive, as_vector
from bhgrasp.errors import InputError
from bhgrasp.hand import Hand

SPREAD_RATIO = 17.5  # motor : spread joint (libbarrett SPREAD_RATIO)
PROXIMAL_RATIO = 125.0  # motor : proximal joint (libbarrett J2_RATIO, Barrett wiki)
DISTAL_RATIO = 375.0  # motor : distal joint relative to the proximal link, coupled (libbarrett J3_RATIO)
DISTAL_ALONE_RATIO = 93.75  # motor : distal worm gear, absolute (Barrett wiki); drives the distal after breakaway
MAX_MOTOR_TORQUE = 2200 / 20000  # [N m] puck MT / IPNM (Robotnik pyHand_api defaults)
MAX_MOTOR_SPEED = 200e3 / 4096 * 2 * np.pi  # [rad/s] finger puck default MV = 200 counts/ms, 4096 counts/rev
# A linear torque-speed line through (MAX_MOTOR_TORQUE, 0) and (0, MAX_MOTOR_SPEED): motor viscous damping
# [N m s/rad] at the shaft; through 125:1 it caps the proximal speed at 2.45 rad/s under full torque.
MOTOR_DAMPING = MAX_MOTOR_TORQUE / MAX_MOTOR_SPEED


class Actuation(ABC):
    """Base of the actuation models: inputs -> joint torques, transmission, passive joint damping/friction."""

    def __init__(self, hand: Hand, damping: float | Sequence[float] = 0.0, friction: float | Sequence[float] = 0.0):
        """Passive joint terms.

        Args:
            hand: The actuated hand.
            damping: Viscous joint damping [N m s/rad], scalar or per joint.
            friction: Coulomb joint friction [N m], scalar or per joint (regularised over 1e-3 rad/s).
        """
        self.hand = hand
        self.damping = _per_joint(damping, hand.nv, "damping")
        self.friction = _per_joint(friction, hand.nv, "friction")

    @property
    @abstractmethod
    def n_inputs(self) -> int:
        """Number of control inputs."""

    @abstractmethod
    def transmission(self) -> np.ndarray:
        """``T`` (nv_hand, n_driven): hand velocities = ``T @`` driven velocities, in the current mode."""

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
        """Numeric mode flags to record (e.g. TorqueSwitch broken per finger); empty if none."""
        return np.zeros(0)

    def joint_damping(self) -> np.ndarray:
        """Viscous damping per joint [N m s/rad] in the current mode (passive joints + drive), for the solver."""
        return self.damping

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
        """Args: ``saturate`` clips each torque to ``hand.effort_limit``; damping/friction as :class:`Actuation`."""
        super().__init__(hand, damping, friction)
        self.saturate = bool(saturate)
        self._identity = np.eye(hand.nv)

    @property
    def n_inputs(self) -> int:
        """One input per joint."""
        return self.hand.nv

    def transmission(self) -> np.ndarray:
        """Identity: every joint is driven."""
        return self._identity

    def joint_torques(self, u: np.ndarray) -> np.ndarray:
        """The inputs themselves (clipped to the effort limits if ``saturate``)."""
        if self.saturate:
            limit = self.hand.effort_limit
            return np.clip(u, -limit, limit)
        return np.array(u, dtype=float)


class BarrettActuation(Actuation):
    """The BH8-280's 4 motors with spread coupling and TorqueSwitch breakaway (inputs: motor torques [N m])."""

    FINGERS = ("F1", "F2", "F3")

    def __init__(
        self,
        hand: Hand,
        breakaway_torque: float = 0.5,
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
        super().__init__(hand, damping, friction)
        names = hand.joint_names
        required = ["F1_spread", "F2_spread"] + [f"{f}_{j}" for f in self.FINGERS for j in ("proximal", "distal")]
        missing = [name for name in required if name not in names]
        if missing:
            raise InputError(f"BarrettActuation needs a Barrett hand; `hand` lacks joints {missing}")
        self.breakaway_torque = as_positive(breakaway_torque, "breakaway_torque")
        self.saturate = bool(saturate)
        self.motor_damping = float(_per_joint(motor_damping, 1, "motor_damping")[0])
        self.blocked_speed = as_positive(blocked_speed, "blocked_speed")
        self._spread = (names.index("F1_spread"), names.index("F2_spread"))
        self._proximal = [names.index(f"{f}_proximal") for f in self.FINGERS]
        self._distal = [names.index(f"{f}_distal") for f in self.FINGERS]
        self._lower = hand.lower
        self.mode = np.zeros(3, dtype=int)  # per finger: 0 coupled, 1 broken away, 2 re-opening the proximal

    @property
    def broken(self) -> np.ndarray:
        """Per finger: whether its TorqueSwitch is not armed (broken away or re-opening)."""
        return self.mode > 0

    @property
    def n_inputs(self) -> int:
        """Spread motor, then the F1, F2, F3 finger motors."""
        return 4

    def reset(self, q_hand: np.ndarray) -> None:
        """Re-arm every TorqueSwitch."""
        self.mode[:] = 0

    def restore(self, modes: np.ndarray | None, q_hand: np.ndarray) -> None:
        """Take the TorqueSwitch modes a state carries (``None``: every switch re-armed)."""
        if modes is None or len(modes) == 0:
            self.reset(q_hand)
        else:
            self.mode[:] = np.asarray(modes, dtype=int)

    def transmission(self) -> np.ndarray:
        """Spread column (1, 1) on F1/F2 spread; per finger (1, 1/3) on (proximal, distal), or (0, 1) if broken."""
        columns = np.zeros((self.hand.nv, 4))
        columns[list(self._spread), 0] = 1.0
        for finger in range(3):
            if self.mode[finger] == 1:
                columns[self._distal[finger], finger + 1] = 1.0
            elif self.mode[finger] == 2:
                columns[self._proximal[finger], finger + 1] = 1.0
            else:
                columns[self._proximal[finger], finger + 1] = 1.0
                columns[self._distal[finger], finger + 1] = PROXIMAL_RATIO / DISTAL_RATIO
        return columns

    def joint_torques(self, u: np.ndarray) -> np.ndarray:
        """Motor torques through the gears: the power u * motor speed enters each driven coordinate."""
        if self.saturate:
            u = np.clip(u, -MAX_MOTOR_TORQUE, MAX_MOTOR_TORQUE)
        tau = np.zeros(self.hand.nv)
        tau[self._spread[0]] = SPREAD_RATIO * u[0]  # the coupled F2 spread shares the (1, 1) column
        for finger in range(3):
            if self.mode[finger] == 1:
                tau[self._distal[finger]] = DISTAL_ALONE_RATIO * u[finger + 1]
            else:
                tau[self._proximal[finger]] = PROXIMAL_RATIO * u[finger + 1]
        return tau

    def update(self, q_hand: np.ndarray, v_hand: np.ndarray, u: np.ndarray, drive_torques: np.ndarray) -> None:
        """Break away on a blocked proximal link; on opening, tip back to its stop, then proximal to its stop."""
        for finger in range(3):
            motor, proximal, distal = u[finger + 1], self._proximal[finger], self._distal[finger]
            at_stop = q_hand[[proximal, distal]] <= self._lower[[proximal, distal]] + 1e-4
            if self.mode[finger] == 0:
                blocked = abs(v_hand[proximal]) < self.blocked_speed
                if motor > 0.0 and blocked and drive_torques[proximal] > self.breakaway_torque:
                    self.mode[finger] = 1
            elif self.mode[finger] == 1 and motor < 0.0 and at_stop[1]:
                self.mode[finger] = 2
            elif self.mode[finger] == 2 and (at_stop[0] or motor > 0.0):
                self.mode[finger] = 0

    def modes(self) -> np.ndarray:
        """TorqueSwitch state per finger: 0 armed (coupled), 1 broken away, 2 re-opening the proximal link."""
        return self.mode.astype(float)

    def joint_damping(self) -> np.ndarray:
        """Joint damping plus the motors' damping reflected onto each driven coordinate (b_m ratio^2).

        It is put on one joint of each transmission column whose entry is 1, so that ``T^T D T`` holds it once.
        """
        damping = self.damping.copy()
        damping[self._spread[0]] += self.motor_damping * SPREAD_RATIO**2
        for finger in range(3):
            if self.mode[finger] == 1:
                damping[self._distal[finger]] += self.motor_damping * DISTAL_ALONE_RATIO**2
            else:
                damping[self._proximal[finger]] += self.motor_damping * PROXIMAL_RATIO**2
        return damping


def _per_joint(value: float | Sequence[float], size: int, name: str) -> np.ndarray:
    array = np.full(size, float(value)) if np.ndim(value) == 0 else as_vector(value, name, size)
    if not np.all(np.isfinite(array)) or np.any(array < 0):
        raise InputError(f"`{name}` must be finite and >= 0, got {np.asarray(value).tolist()}")
    return array.copy()
