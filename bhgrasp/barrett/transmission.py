"""The BH8-280's drive: four motors (spread, F1, F2, F3), their gears and the TorqueSwitch (thesis 2.4.7).

Facts (sources in ``../shared/reference/barrett_public_data.md`` sections 1.4 and 5, keys as there):

- spread motor : spread joint (F1 and F2 together) 17.5 : 1 (libbarrett ``SPREAD_RATIO``);
- finger motor : proximal joint 125 : 1 (libbarrett ``J2_RATIO``; Barrett wiki, kinematics page);
- finger motor : distal joint relative to the proximal link, coupled, 375 : 1, so distal = proximal / 3
  (libbarrett ``J3_RATIO``);
- finger motor : distal worm, absolute, 93.75 : 1: it drives the distal joint alone after breakaway (Barrett
  wiki; BH8 manual p. 61);
- puck torque limit MT 2200 (Robotnik ``pyHand_api.py`` default); speed limit MV 200 counts/ms at 4096
  counts/rev = 307 rad/s at the motor (Robotnik defaults; libbarrett counts/ms);
- the motor torque at MT, :data:`MAX_MOTOR_TORQUE`, calibrated (below) to Barrett's stalled fingertip force;
- breakaway torque 0.5 N m at the proximal joint (GraspIt! ``breakAwayTorque``; Barrett publishes no N m value,
  its firmware sets the threshold through the puck properties IVEL, IOFF, IHIT, OT).

TorqueSwitch (BH8 manual; Barrett wiki): a finger motor turns the proximal joint and, through the clutch, the distal
joint at one third of its speed, until, while closing, the torque the clutch passes to the proximal link exceeds the
breakaway threshold (a contact on either link, a joint stop; whatever the link's speed, :meth:`switch`); then the
proximal joint holds and the motor drives the distal joint alone through its 93.75:1
worm.  Opening a broken-away finger drives the fingertip back to its stop, then the proximal link alone to its open
stop, where the switch re-arms.  Modes per finger: 0 armed (coupled), 1 broken away, 2 re-opening the proximal link.

Worm drives: each finger motor turns its joints through single-start worms (Barrett wiki, kinematics page), which
Barrett calls "non-backdrivable" (Barrett wiki, safety page).  A worm is self-locking when its friction angle phi
exceeds its lead angle lambda; its forward efficiency is then eta = tan(lambda) / tan(lambda + phi) < tan(lambda) /
tan(2 lambda) = (1 - tan^2 lambda) / 2 < 1/2 (Shigley's Mechanical Engineering Design, worm gearing).  Barrett
publishes neither angle, so the default efficiency is that bound, 0.5 (a user who measured theirs sets it).  Model
(:meth:`locks`): a finger's motor coordinate is *locked* (held, its reaction carried by the worm) whenever its load
would drive it back against the motor or the motor is idle, and it unlocks when the motor alone gives more than
holding needs in the motor's direction.  The spread is back-drivable ("the backdrivability built into this degree
of freedom", BH8 manual 9.3.2): its puck holds it (default HOLD = 1), where the fingers' HOLD = 0 leaves them to
their worms.

The motor torque at MT.  Barrett publishes no torque constant for the hand's motors; Robotnik's default IPNM = 20000
puck units per N m would make MT 0.11 N m, which through a self-locking worm (eta <= 0.5) presses a stalled
fingertip with about 100 N (5 N m on the distal joint).  Barrett's own figures agree on a fifth of that: the
fingertip torque sensor's range "+/- 1 N-m (+/- 2 kg at finger tip is about 20 N @ 5 cm)", the stalled fingertip
force it plots against commanded velocity up to about 25 N (BH8 manual 9.3.1, Fig. 25), "the load limit of the
fingers, 2 kg per finger" (Barrett wiki, safety page).  So the drive is calibrated to the stall of a broken-away
finger, whose motor drives the distal joint alone: :data:`STALL_TIP_FORCE` 20 N at :data:`TIP_LEVER` 5 cm from the
distal axis, eta 93.75 u_max = 1 N m, u_max = 0.0213 N m at the motor (the pucks' IPNM becomes MT / u_max = 103125,
:mod:`~bhgrasp.barrett.pucks`).  A worm's efficiency and the motor's torque enter a stall only as their product;
keeping eta at its bound puts the calibration in the motor's torque (a worm of 3-5 deg lead that self-locks, its
friction angle above the lead, at friction 0.06-0.15 has eta 0.25-0.48, so the motor torque is 0.02-0.04 N m either
way).  The motor's torque-speed
line keeps its no-load speed, so the unloaded close still takes about 1 s.

Inputs are motor torques [N m] at the motor shafts, then one torque [N m or N] per joint outside the hand's eight
(e.g. the wrist mount's of :func:`~bhgrasp.model.mount.mounted`), applied directly.  A linear torque-speed line through
the puck limits gives each motor a viscous damping [N m s/rad] at its shaft; through a gear ratio r and the
efficiency eta it damps the driven joint by eta b_m r^2 (a finger's torque is eta r (u - b_m r w)).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from bhgrasp._validation import as_positive
from bhgrasp.errors import InputError
from bhgrasp.model.hand import Hand
from bhgrasp.model.transmission import Transmission, per_joint

SPREAD_RATIO = 17.5  # motor : spread joint (libbarrett SPREAD_RATIO)
PROXIMAL_RATIO = 125.0  # motor : proximal joint (libbarrett J2_RATIO, Barrett wiki)
DISTAL_RATIO = 375.0  # motor : distal joint relative to the proximal link, coupled (libbarrett J3_RATIO)
DISTAL_ALONE_RATIO = 93.75  # motor : distal worm gear, absolute (Barrett wiki); drives the distal after breakaway
WORM_EFFICIENCY = 0.5  # forward efficiency of a finger's worm drive: the bound for a self-locking worm (docstring)
STALL_TIP_FORCE, TIP_LEVER = 20.0, 0.05  # [N], [m] Barrett: +/- 1 N m "is about 20 N @ 5 cm" (docstring)
# [N m] the motor torque at the pucks' MT: a broken-away finger's stall presses STALL_TIP_FORCE at TIP_LEVER
MAX_MOTOR_TORQUE = STALL_TIP_FORCE * TIP_LEVER / (WORM_EFFICIENCY * DISTAL_ALONE_RATIO)
MAX_MOTOR_SPEED = 200e3 / 4096 * 2 * np.pi  # [rad/s] finger puck default MV = 200 counts/ms, 4096 counts/rev
# A linear torque-speed line through (MAX_MOTOR_TORQUE, 0) and (0, MAX_MOTOR_SPEED): motor viscous damping
# [N m s/rad] at the shaft; through 125:1 it caps the proximal speed at 2.45 rad/s under full torque.
MOTOR_DAMPING = MAX_MOTOR_TORQUE / MAX_MOTOR_SPEED
BREAKAWAY_TORQUE = 0.5  # [N m] at the proximal joint (GraspIt! breakAwayTorque)
FINGERS = ("F1", "F2", "F3")
ARMED, BROKEN_AWAY, REOPENING = 0, 1, 2
STOP_TOLERANCE = 1e-4  # [rad] a joint this close to its lower limit is at its stop


class BarrettTransmission(Transmission):
    """The BH8-280's four motors: spread coupling, finger gears and the TorqueSwitch rule (module docstring)."""

    def __init__(
        self,
        hand: Hand,
        breakaway_torque: float = BREAKAWAY_TORQUE,
        motor_damping: float = MOTOR_DAMPING,
        damping: float | Sequence[float] = 0.0,
        efficiency: float = WORM_EFFICIENCY,
        self_locking: bool = True,
    ) -> None:
        """Couple a Barrett hand's joints.

        Args:
            hand: A Barrett hand (joints F1_spread, F2_spread and F*_proximal, F*_distal), possibly mounted: its
                other joints are driven directly.
            breakaway_torque: Proximal load torque [N m] above which the TorqueSwitch breaks away (:meth:`switch`).
            motor_damping: Motor viscous damping at the shaft [N m s/rad] (its torque-speed line).
            damping: Passive viscous joint damping [N m s/rad], scalar or per joint.
            efficiency: Forward efficiency of the finger worm drives, in (0, 1] (1: ideal gears).
            self_locking: Whether the finger drives self-lock (:meth:`locks`); ``False``: they back-drive freely.
        """
        super().__init__(hand, damping)
        names = hand.joint_names
        required = ["F1_spread", "F2_spread"] + [f"{f}_{j}" for f in FINGERS for j in ("proximal", "distal")]
        missing = [name for name in required if name not in names]
        if missing:
            raise InputError(f"the BH8-280 transmission needs a Barrett hand; `hand` lacks joints {missing}")
        self.breakaway_torque = as_positive(breakaway_torque, "breakaway_torque")
        self.motor_damping = float(per_joint(motor_damping, 1, "motor_damping")[0])
        self.efficiency = as_positive(efficiency, "efficiency")
        if self.efficiency > 1.0:
            raise InputError(f"`efficiency` must be in (0, 1], got {efficiency!r}")
        self.self_locking = bool(self_locking)
        self.spread = (names.index("F1_spread"), names.index("F2_spread"))
        self.proximal = [names.index(f"{f}_proximal") for f in FINGERS]
        self.distal = [names.index(f"{f}_distal") for f in FINGERS]
        self.direct = [i for i, name in enumerate(names) if name not in required]  # e.g. a wrist mount's joints
        self._lower = hand.lower
        self._matrices: dict[tuple[int, ...], np.ndarray] = {}  # matrix() per mode combination

    @property
    def n_inputs(self) -> int:
        """Spread motor, then the F1, F2, F3 finger motors, then one torque per joint of :attr:`direct`."""
        return 4 + len(self.direct)

    def matrix(self, modes: Any = None) -> np.ndarray:
        """Spread column (1, 1) on F1/F2 spread; per finger (1, 1/3) on (proximal, distal), or (0, 1) if broken.

        A fresh array; each of the 27 mode combinations is built once per drive (the contact loop asks every step).
        """
        modes = switch_modes(modes)
        key = tuple(modes.tolist())
        built = self._matrices.get(key)
        if built is None:
            built = self._matrices[key] = self._matrix(modes)
        return built.copy()

    def _matrix(self, modes: np.ndarray) -> np.ndarray:
        columns = np.zeros((self.hand.nv, self.n_inputs))
        columns[self.direct, range(4, self.n_inputs)] = 1.0
        columns[list(self.spread), 0] = 1.0
        for finger in range(3):
            if modes[finger] == BROKEN_AWAY:
                columns[self.distal[finger], finger + 1] = 1.0
            elif modes[finger] == REOPENING:
                columns[self.proximal[finger], finger + 1] = 1.0
            else:
                columns[self.proximal[finger], finger + 1] = 1.0
                columns[self.distal[finger], finger + 1] = PROXIMAL_RATIO / DISTAL_RATIO
        return columns

    def joint_torques(self, u: np.ndarray, modes: Any = None) -> np.ndarray:
        """Motor torques through the gears: the power u * motor speed enters each driven coordinate [N m]."""
        modes = switch_modes(modes)
        tau = np.zeros(self.hand.nv)
        tau[self.direct] = u[4:]
        tau[self.spread[0]] = SPREAD_RATIO * u[0]  # the coupled F2 spread shares the (1, 1) column
        for finger in range(3):
            if modes[finger] == BROKEN_AWAY:
                tau[self.distal[finger]] = self.efficiency * DISTAL_ALONE_RATIO * u[finger + 1]
            else:
                tau[self.proximal[finger]] = self.efficiency * PROXIMAL_RATIO * u[finger + 1]
        return tau

    def gears(self, modes: Any = None) -> np.ndarray:
        """B (nv, n_inputs): :meth:`joint_torques` of each unit input."""
        return np.column_stack([self.joint_torques(unit, modes) for unit in np.eye(self.n_inputs)])

    def joint_damping(self, modes: Any = None) -> np.ndarray:
        """Passive damping plus the motors' damping reflected onto each driven coordinate (b_m ratio^2).

        It is put on one joint of each transmission column whose entry is 1, so that ``T^T D T`` holds it once.
        """
        modes = switch_modes(modes)
        damping = self.passive_damping.copy()
        damping[self.spread[0]] += self.motor_damping * SPREAD_RATIO**2
        for finger in range(3):
            if modes[finger] == BROKEN_AWAY:
                damping[self.distal[finger]] += self.efficiency * self.motor_damping * DISTAL_ALONE_RATIO**2
            else:
                damping[self.proximal[finger]] += self.efficiency * self.motor_damping * PROXIMAL_RATIO**2
        return damping

    def switch(self, modes: Any, q_hand: np.ndarray, u: np.ndarray, load: np.ndarray) -> np.ndarray:
        """The TorqueSwitch modes after a step that ended at ``q_hand`` under motor torques ``u``.

        ``load``: the joint torques the drive carried over the step less the links' own inertial torques [N m]
        (:attr:`~bhgrasp.sim.engine.StepResult.load`).  The clutch sits between the worm gear and the proximal
        link and slips on the torque it transmits, whatever the link's speed.  Between a motor geared 125:1 and a
        light link, the motor's reflected rotor inertia is far the larger (a rotor of 1e-6 kg m^2 reflects 0.016
        kg m^2; a finger's links have about 5e-4 kg m^2 about the proximal axis), so a change of speed is the
        rotor's business and the clutch carries the links' load: gravity, contacts, joint stops.  The simulated
        motor has no rotor inertia, so the drive's own torque would break a switch at start-up in free air; the
        load does not.  Armed -> broken away when the finger closes (u > 0) and its proximal load exceeds the
        breakaway torque; broken away -> re-opening when it opens (u < 0) with the fingertip at its stop;
        re-opening -> armed at the proximal stop, or when it closes again.
        """
        modes = switch_modes(modes).copy()
        for finger in range(3):
            motor, proximal, distal = u[finger + 1], self.proximal[finger], self.distal[finger]
            at_stop = q_hand[[proximal, distal]] <= self._lower[[proximal, distal]] + STOP_TOLERANCE
            if modes[finger] == ARMED:
                if motor > 0.0 and load[proximal] > self.breakaway_torque:
                    modes[finger] = BROKEN_AWAY
            elif modes[finger] == BROKEN_AWAY and motor < 0.0 and at_stop[1]:
                modes[finger] = REOPENING
            elif modes[finger] == REOPENING and (at_stop[0] or motor > 0.0):
                modes[finger] = ARMED
        return modes

    def locks(self, locked: np.ndarray, modes: Any, v_hand: np.ndarray, u: np.ndarray, drive: np.ndarray) -> np.ndarray:
        """Which finger drives are locked after a step that ended at velocity ``v_hand`` under motor torques ``u``.

        ``locked`` (3,) bool: the drives locked during the step; ``modes``: the TorqueSwitch modes after it (a
        finger whose mode changed starts unlocked, on its new coordinate); ``drive``: the joint torques the drive
        delivered [N m].  Along a finger's motor coordinate w (its column c of :meth:`matrix`), the motor gives
        F = c . B u and the drive delivered H = c . drive (what holding took, while locked).  A locked drive
        unlocks when the motor turns (u != 0) and gives more than holding needs in its direction, sign(u) F >
        sign(u) H; an unlocked drive locks when the motor is idle (u = 0) or the load turns it back, u w < 0.
        """
        if not self.self_locking:
            return np.zeros(3, dtype=bool)
        modes = switch_modes(modes)
        columns, torques = self.matrix(modes), self.joint_torques(u, modes)
        result = np.array(locked, dtype=bool)
        for finger in range(3):
            motor, column = u[finger + 1], columns[:, finger + 1]
            if locked[finger]:
                result[finger] = motor == 0.0 or np.sign(motor) * (column @ torques - column @ drive) <= 0.0
            else:
                speed = column @ v_hand / (column @ column)  # w from v = c w on the finger's joints
                result[finger] = motor == 0.0 or motor * speed < 0.0
        return result


_ARMED = np.zeros(3, dtype=int)


def switch_modes(modes: Any) -> np.ndarray:
    """TorqueSwitch modes (3,) as ints from a state's flags (3, or 6 with the worm locks); ``None``/empty: armed."""
    if type(modes) is np.ndarray and modes.dtype == _ARMED.dtype and modes.shape == (3,):  # the drive's own: fast
        if all(ARMED <= mode <= REOPENING for mode in modes.tolist()):
            return modes
    if modes is None or len(modes) == 0:
        return _ARMED
    array = np.asarray(modes)
    if array.shape == (6,) and np.isin(array[3:], (0, 1)).all():
        array = array[:3]
    integers = array if array.dtype.kind == "i" else array.astype(int)
    if array.shape != (3,) or not (integers == array).all() or integers.min() < ARMED or integers.max() > REOPENING:
        raise InputError(f"TorqueSwitch modes must be 3 values in (0, 1, 2), got {array.tolist()}")
    return integers


__all__ = [
    "ARMED",
    "BREAKAWAY_TORQUE",
    "BROKEN_AWAY",
    "DISTAL_ALONE_RATIO",
    "DISTAL_RATIO",
    "MAX_MOTOR_SPEED",
    "MAX_MOTOR_TORQUE",
    "MOTOR_DAMPING",
    "PROXIMAL_RATIO",
    "REOPENING",
    "SPREAD_RATIO",
    "STALL_TIP_FORCE",
    "TIP_LEVER",
    "WORM_EFFICIENCY",
    "BarrettTransmission",
    "switch_modes",
]
