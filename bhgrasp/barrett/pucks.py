"""The BH8-280's motor pucks as firmware: modes, properties, PID, velocity and trapezoidal moves, in puck units.

Each of the four motors (F1, F2, F3, SPREAD) has a puck that reads its motor encoder (4096 counts/rev) and drives its
motor.  Names and numbers are libbarrett's (``BarrettTechnology/libbarrett`` @109faf6, GPL: read, not copied):

- modes ``MotorPuck::MotorMode`` (``include/barrett/products/motor_puck.h:50-57``): IDLE 0, (DUTY 1, not
  modelled), TORQUE 2, PID 3, VELOCITY 4, TRAPEZOIDAL 5; the same numbers in Robotnik's ``puck_properties_consts.py``;
- properties (``include/barrett/products/detail/property_list.h``): P position, V velocity [counts/ms], T torque
  [puck units], E trapezoidal endpoint, MV max velocity [counts/ms], MT max torque, KP, KD, KI, ACCEL, HOLD, TSTOP,
  CT/OT close/open targets, MCV/MOV close/open velocities, IPNM puck units per N m;
- defaults (Robotnik ``pyHand_api.py`` @4993a1f, ``set_puck_like`` lines 629-708): fingers KP 500, KD 2500,
  ACCEL 200, MV 200, TSTOP 50, HOLD 0, CT 195000; spread KP 1000, KD 10000, MV 50, TSTOP 150, HOLD 1, CT 35950;
  all: KI 0, MT 2200, MCV = MOV = 200; IPNM (puck units per N m at the motor) is ours, 103125, so that MT gives
  the calibrated motor torque :data:`~bhgrasp.barrett.transmission.MAX_MOTOR_TORQUE` (0.0213 N m; Robotnik's
  default 20000 would give 0.11 N m and a fingertip stall five times Barrett's figure: see that module).

Semantics (Barrett wiki ``Hand/282/ControlModes`` v5, for the BH8-280 and 282): TORQUE streams T; PID holds P with
KP, KD, KI; VELOCITY keeps V until a new one, limited to MV; TRAPEZOIDAL moves to E accelerating at ACCEL up to MV
and decelerating to rest, then "MODE drops from 5 to 3 (HOLD = 1) or to 0 (HOLD = 0)"; the pucks respect the joint
stops.  A move (trapezoidal, velocity, close, open) also ends when the motor has not turned for TSTOP ms (a stall).

Assumptions (Barrett publishes no firmware source nor units for KP, KD, ACCEL):

- PID output in puck torque units = (KP e + KD de + KI sum e) / 1024 (:data:`PID_SCALE`, Q10 fixed point), e in
  counts, de in counts per 1 ms tick; motor torque = units / IPNM.  So at the motor the finger defaults are
  kp = 3.09e-3 N m/rad, kd = 1.54e-5 N m s/rad (spread 6.17e-3, 6.17e-5).  Why: the simulated motor is its
  torque-speed line (a damper b_m = 0.0213 N m / 307 rad/s = 6.9e-5 N m s/rad at the shaft, no rotor inertia), and a
  finger's links reflect almost no inertia through 125:1, so a sampled D term is stable only with kd < b_m (unscaled,
  KD 2500 gives kd = 0.016 and KP 500 kp = 3.2 N m/rad: the output would chatter at MT).  With 2^10 a finger's loop
  is first order, time constant (b_m + kd) / kp = 27.5 ms; it holds the proximal joint with kp 125^2 = 48 N m/rad and
  closes in about 1 s (the often quoted, unverified, close time); the spread (which carries F1 and F2's inertia) is
  second order with damping ratio about 0.5.  Gains are overridable in SI.
- ACCEL in counts/ms^2 / 256 (:data:`ACCEL_UNIT`): the finger default ramps to MV in 256 ms.
- the control loop runs at 1 kHz (:data:`PERIOD`; libbarrett's velocities are counts per ms); a stall is a motor
  slower than :data:`STALL_SPEED` for TSTOP ms (and ends where it stands); a trapezoidal move is done within
  :data:`DONE_TOLERANCE` of E; VELOCITY integrates V into a PID reference kept within the error that saturates MT.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from bhgrasp.barrett.profiles import profile_at, trapezoid
from bhgrasp.barrett.sensors import COUNTS_PER_REV
from bhgrasp.barrett.transmission import MAX_MOTOR_TORQUE
from bhgrasp.errors import InputError

IDLE, TORQUE, PID, VELOCITY, TRAPEZOIDAL = 0, 2, 3, 4, 5  # MotorPuck::MotorMode
MODES = {IDLE: "IDLE", TORQUE: "TORQUE", PID: "PID", VELOCITY: "VELOCITY", TRAPEZOIDAL: "TRAPEZOIDAL"}
COUNTS_PER_RAD = COUNTS_PER_REV / (2.0 * np.pi)  # the motor encoder's (bhgrasp.barrett.sensors)
PID_SCALE = 1024.0  # assumption: PID gains are Q10 fixed point (module docstring)
ACCEL_UNIT = 1.0 / 256.0  # assumption: ACCEL in counts/ms^2 / 256
PERIOD = 1e-3  # [s] puck control period (assumption: 1 kHz)
STALL_SPEED = 1.0  # [counts/ms] slower than this the motor counts as stopped
DONE_TOLERANCE = 100  # [counts] a trapezoidal move this close to E (and stopped) is done


@dataclass(frozen=True)
class PuckProperties:
    """A puck's firmware properties, in puck units (counts, counts/ms, puck torque units; TSTOP in ms)."""

    KP: float = 500.0
    KD: float = 2500.0
    KI: float = 0.0
    ACCEL: float = 200.0
    MV: float = 200.0
    MT: float = 2200.0
    TSTOP: float = 50.0
    HOLD: int = 0
    CT: float = 195000.0
    OT: float = 0.0
    MCV: float = 200.0
    MOV: float = 200.0
    IPNM: float = 2200.0 / MAX_MOTOR_TORQUE  # 103125: MT at the calibrated motor torque (module docstring)

    def __post_init__(self) -> None:
        for name in ("KP", "KD", "KI", "ACCEL", "MV", "MT", "TSTOP", "IPNM", "MCV", "MOV"):
            value = getattr(self, name)
            if not np.isfinite(value) or value < 0.0 or (value == 0.0 and name in ("ACCEL", "MV", "IPNM")):
                raise InputError(
                    f"puck property {name} must be a finite non-negative number (ACCEL, MV, IPNM > 0), got {value!r}"
                )
        if self.HOLD not in (0, 1):
            raise InputError(f"puck property HOLD must be 0 or 1, got {self.HOLD!r}")

    @property
    def torque_limit(self) -> float:
        """MT as a motor torque [N m] (MT / IPNM: 0.0213 N m by default)."""
        return self.MT / self.IPNM

    def gains(self) -> tuple[float, float, float]:
        """(kp [N m/rad], kd [N m s/rad], ki [N m/(rad s)]) at the motor from KP, KD, KI (module docstring)."""
        unit = COUNTS_PER_RAD / (PID_SCALE * self.IPNM)  # N m per (puck unit x count) per rad
        return self.KP * unit, self.KD * unit * PERIOD, self.KI * unit / PERIOD

    def with_(self, **properties: float) -> PuckProperties:
        """A copy with some properties changed (unknown names raise)."""
        unknown = sorted(set(properties) - set(self.__dataclass_fields__))
        if unknown:
            raise InputError(f"unknown puck properties {unknown}; valid: {sorted(self.__dataclass_fields__)}")
        return replace(self, **properties)


FINGER_PUCK = PuckProperties()
SPREAD_PUCK = PuckProperties(KP=1000.0, KD=10000.0, MV=50.0, TSTOP=150.0, HOLD=1, CT=35950.0)


class Puck:
    """One puck's firmware: a mode, its set points and a PID on motor counts, updated once per tick.

    ``kp``, ``kd``, ``ki`` (SI, at the motor) override the gains of KP, KD, KI; ``travel`` is the motor's range
    [counts] (its joint stops): references are kept inside it.
    """

    def __init__(
        self,
        properties: PuckProperties,
        travel: tuple[float, float],
        kp: float | None = None,
        kd: float | None = None,
        ki: float | None = None,
    ) -> None:
        self.properties = properties
        gains = properties.gains()
        self.kp, self.kd, self.ki = (float(g if o is None else o) for g, o in zip(gains, (kp, kd, ki)))
        if not all(np.isfinite(g) and g >= 0.0 for g in (self.kp, self.kd, self.ki)) or self.kp == 0.0:
            raise InputError(f"puck gains must be finite, kp > 0, kd, ki >= 0; got {self.kp}, {self.kd}, {self.ki}")
        self.travel = (float(travel[0]), float(travel[1]))
        self.reset(0.0)

    def reset(self, position: float) -> None:
        """Power-on: IDLE at ``position`` [counts]."""
        self.mode, self.torque, self.target = IDLE, 0.0, float(position)
        self.reference, self.ref_velocity, self.velocity = float(position), 0.0, 0.0
        self.integral, self.stalled_ms, self.elapsed_ms = 0.0, 0.0, 0.0
        self._profile: tuple[float, float, float, float] | None = None
        self._stop_at: float | None = None
        self._start = float(position)
        self._homing = False
        self.homed_at: float | None = None  # where the last HI found the open stop [counts], until the driver reads it

    # --- commands (setting MODE and its set point) ---
    def set_mode(self, mode: int, position: float) -> None:
        """Set MODE; entering PID holds ``position`` [counts] (the motor's present one)."""
        if mode not in MODES:
            raise InputError(f"puck MODE must be one of {MODES}, got {mode!r}")
        self.mode, self.integral, self.stalled_ms, self._homing = mode, 0.0, 0.0, False
        if mode == PID:
            self.reference, self.ref_velocity = self._clamp(position), 0.0

    def set_torque(self, units: float) -> None:
        """T [puck units], used in TORQUE mode."""
        self.torque = float(units)

    def set_position(self, counts: float) -> None:
        """P [counts], the PID set point."""
        self.reference, self.ref_velocity = self._clamp(counts), 0.0

    def velocity_move(self, counts_per_ms: float, position: float, stop_at: float | None = None) -> None:
        """V [counts/ms] (limited to MV) from ``position``; ``stop_at`` [counts]: a close/open target."""
        limit = self.properties.MV
        self.velocity = float(np.clip(counts_per_ms, -limit, limit))
        self.reference, self.ref_velocity, self._stop_at = self._clamp(position), self.velocity, stop_at
        self.set_mode(VELOCITY, position)

    def home(self, position: float) -> None:
        """HI (``CMD_HI``): open at MOV (limited to MV), past any travel limit, until stalled on the open stop (TSTOP).

        That position then becomes count 0 (:attr:`homed_at` keeps it for the encoder's reader).
        """
        self.velocity_move(-self.properties.MOV, position)
        self._homing = True

    def trapezoidal_move(self, endpoint: float, position: float) -> None:
        """E [counts]: a trapezoidal profile from ``position`` at rest to E, ACCEL and MV limited."""
        self.target = self._clamp(endpoint)
        self._profile = trapezoid(self.target - position, self.properties.MV, self.properties.ACCEL * ACCEL_UNIT)
        self.reference, self.ref_velocity, self.elapsed_ms, self._start = position, 0.0, 0.0, float(position)
        self.set_mode(TRAPEZOIDAL, position)

    def done(self) -> bool:
        """Whether the move is over, as libbarrett's ``Hand::doneMoving`` reads it: IDLE, or PID with HOLD."""
        return self.mode == IDLE or (self.mode == PID and self.properties.HOLD != 0)

    # --- the firmware's tick ---
    def update(self, position: float, speed: float, ticks: float = 1.0) -> float:
        """One control tick from the encoder ``position`` [counts] and ``speed`` [counts/ms]: motor torque [N m].

        ``ticks``: control periods since the last update (the profiles advance by that many ms).
        """
        props, ms = self.properties, ticks * PERIOD * 1e3
        if self.mode == IDLE:
            return 0.0
        if self.mode == TORQUE:
            units = self.torque
        else:
            moving = self._advance(position, ms)
            units = self._pid(position, speed, ms)
            if moving:
                self._check_stall(position, speed, ms)
        limit = props.MT
        return float(np.clip(units, -limit, limit)) / props.IPNM

    def _advance(self, position: float, ms: float) -> bool:
        """Move the reference along the active profile; whether the puck is in a move (stall-checked)."""
        if self.mode == VELOCITY:
            lag = self.properties.MT / self.properties.IPNM / self.kp * COUNTS_PER_RAD  # saturating error [counts]
            ahead = float(np.clip(self.reference + self.velocity * ms, position - lag, position + lag))
            end = self.travel[1] if self.velocity > 0.0 else self.travel[0]  # the joint stop ahead
            if self._homing:
                end = -np.inf  # the puck does not know where its stop is yet
            elif self._stop_at is not None:
                end = self._clamp(self._stop_at)
            arrived = ahead >= end if self.velocity > 0.0 else ahead <= end
            self.reference, self.ref_velocity = (end, 0.0) if arrived else (ahead, self.velocity)
            if arrived and self._stop_at is not None and abs(position - end) <= DONE_TOLERANCE:
                self._finish(end)
                return False
            return abs(self.velocity) >= 2.0 * STALL_SPEED and (arrived or self._lagging(position))
        if self.mode == TRAPEZOIDAL:
            self.elapsed_ms += ms
            offset, self.ref_velocity = profile_at(self._profile, self.elapsed_ms)
            self.reference = self._start + offset
            ended = self.elapsed_ms >= self._profile[3]
            if ended and abs(position - self.target) <= DONE_TOLERANCE:
                self._finish(self.target)
                return False
            return ended or self._lagging(position)
        return False

    def _pid(self, position: float, speed: float, ms: float) -> float:
        """PID on counts in puck torque units (the SI gains converted back: the firmware's arithmetic)."""
        error = (self.reference - position) / COUNTS_PER_RAD  # [rad]
        rate = (self.ref_velocity - speed) * 1e3 / COUNTS_PER_RAD  # [rad/s]
        self.integral += error * ms * 1e-3
        torque = self.kp * error + self.kd * rate + self.ki * self.integral
        return torque * self.properties.IPNM

    def _lagging(self, position: float) -> bool:
        """Whether the reference is more than :data:`DONE_TOLERANCE` away from the motor (it should be turning)."""
        return abs(self.reference - position) > DONE_TOLERANCE

    def _check_stall(self, position: float, speed: float, ms: float) -> None:
        """TSTOP: a move whose motor has not turned for TSTOP ms ends where it stands."""
        tstop = self.properties.TSTOP
        self.stalled_ms = self.stalled_ms + ms if abs(speed) < STALL_SPEED else 0.0
        if tstop > 0 and self.stalled_ms >= tstop:
            self._finish(position)

    def _finish(self, position: float) -> None:
        """End of a move at ``position`` [counts]: PID holding it (HOLD = 1) or IDLE (HOLD = 0).

        The end of a HI zeroes the encoder there: :attr:`homed_at` records it and the PID holds count 0.
        """
        self._stop_at, self._profile = None, None
        if self._homing:
            self.homed_at, position = float(np.rint(position)), position - float(np.rint(position))
            self._homing = False
        if self.properties.HOLD:
            self.set_mode(PID, position)
        else:
            self.mode = IDLE

    def _clamp(self, counts: float) -> float:
        return float(np.clip(counts, *self.travel))


__all__ = [
    "ACCEL_UNIT",
    "COUNTS_PER_RAD",
    "COUNTS_PER_REV",
    "FINGER_PUCK",
    "IDLE",
    "MODES",
    "PERIOD",
    "PID",
    "PID_SCALE",
    "SPREAD_PUCK",
    "TORQUE",
    "TRAPEZOIDAL",
    "VELOCITY",
    "Puck",
    "PuckProperties",
]
