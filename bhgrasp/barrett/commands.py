"""The BH8-280 as its users command it: libbarrett's ``Hand`` calls on four simulated pucks, as a controller.

:class:`BarrettDriver` is a :class:`~bhgrasp.controllers.base.Controller`: each call reads the motor encoders from
the sensed joint angles, runs the pucks (:mod:`bhgrasp.barrett.pucks`) at their 1 kHz tick (holding the output in
between) and returns the motor torques [N m] in :class:`~bhgrasp.barrett.transmission.BarrettTransmission`'s input
order (SPREAD, F1, F2, F3, then zero for a mount's joints).  Like libbarrett, commands and readings take 4-vectors in
the order F1, F2, F3, SPREAD (``Hand::SPREAD_INDEX = 3``) in joint units: inner (proximal) link angles [rad] and the
spread angle [rad], or their rates [rad/s]; ``digits`` names pucks: "F1", "F2", "F3", "SPREAD", "GRASP" (the three
fingers) or "WHOLE_HAND" (default).

Encoders: a finger's motor turns 93.75 (q_proximal + q_distal) (libbarrett ``hand.cpp:229``: outer = counts
(1/125 + 1/375) - inner; 125 q_proximal while the TorqueSwitch is armed), the spread motor 17.5 q_spread
(``hand.cpp:238``); 4096 counts/rev.

===================================  =========================================  =================================
libbarrett ``Hand`` (hand.h/.cpp)    puck properties it sets                    here (:class:`BarrettDriver`)
===================================  =========================================  =================================
``close(digits)`` cpp:151            CMD = CMD_CLOSE (18, h:170)                ``close(digits)``: V = +MCV to CT
``open(digits)`` cpp:146             CMD = CMD_OPEN (20, h:171)                 ``open(digits)``: V = -MOV to OT
``trapezoidalMove(jp)`` cpp:156      E = j2pp jp, MODE = TRAPEZOIDAL (5)        ``trapezoidal_move(positions)``
``velocityMove(jv)`` cpp:163         V = j2pp jv / 1000 [counts/ms], MODE = 4   ``velocity_move(velocities)``
``setPositionMode()`` cpp:171        MODE = PID (3)                             ``set_position_mode(digits)``
``setPositionCommand(jp)`` cpp:175   P = j2pp jp                                ``set_position(positions)``
``setTorqueMode()`` cpp:180          MODE = TORQUE (2)                          ``set_torque_mode(digits)``
``setTorqueCommand(jt)`` cpp:184     T = j2pt jt, j2pt = IPNM / ratio (cpp:96)  ``set_torque(torques)``
``idle()`` h:73                      MODE = IDLE (0), whole hand                ``idle()``
``initialize()``                     CMD = CMD_HI (13): fingers, then spread    ``initialize()``
``doneMoving(digits)`` cpp:119       reads MODE: IDLE, or PID with HOLD         ``done_moving(digits)``
``update(sensors)``                  reads P (both encoders), SG, TACT          ``update(sensors)``
``getPrimaryEncoderPosition()``      P [counts]                                 ``primary_encoder_positions()``
``getSecondaryEncoderPosition()``    inner-link encoder [counts]                ``secondary_encoder_positions()``
``getInnerLinkPosition()``           secondary / 50 (or P / 125)                ``inner_link_positions()``
``getOuterLinkPosition()``           P (1/125 + 1/375) - inner (or inner / 3)   ``outer_link_positions()``
``enableBreakawayEncoders(b)``       which formula the two above use            ``enable_breakaway_encoders(b)``
``getFingertipTorque()``             SG [counts, 0..4095]                       ``fingertip_torque()``
``getTactilePucks()``, getFullData   TACT cells [N/cm^2]                        ``tactile()``
``hasFingertipTorqueSensors()``      a puck with option RO_Strain               ``has_fingertip_torque_sensors()``
``hasTactSensors()``                 a puck with option RO_Tact                 ``has_tact_sensors()``
blocking call (``blockIf``) cpp:273  waits for ``doneMoving``                   script step ``("done", ...)``
===================================  =========================================  =================================

j2pp = 4096 / 2 pi x (125 finger, 17.5 spread) counts/rad (``hand.cpp:95-100``).  Close and open run at MCV / MOV
(capped at MV) until the target CT / OT or a stall (TSTOP); the Robotnik driver (``pyHand_api.py:848-880``) sets
TSTOP before them the same way.  A blocking libbarrett call is a :meth:`BarrettDriver.script` step ``"done"``.
An IDLE puck (HOLD = 0 after a move) gives no torque: the worm drives hold the finger (the simulator's
``BarrettActuation(self_locking=True)``, its default); with ``self_locking=False`` an idle finger sags.

Readings (libbarrett ``Hand::update``): the getters return what the last :meth:`BarrettDriver.update` read from the
state the driver last sensed (its last control call), as libbarrett's return what its last ``update()`` received,
through :class:`~bhgrasp.barrett.sensors.BarrettSensors` (counts, SG counts, quantised pads).  Encoders count from
where the pucks were zeroed: a hand built ``homed=True`` (default) starts as if ``initialize()`` had run (count 0 at
the open stops); ``homed=False`` is a hand just powered on, its counts 0 wherever it stands until ``initialize()``
(each finger opens until it stalls on its stop, TSTOP, and zeroes there, then the spread does).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from bhgrasp._validation import as_vector, require_name
from bhgrasp.barrett import pucks as fw
from bhgrasp.barrett.readout import S_ALL, S_FINGERTIP_TORQUE, S_TACT_FULL, HandReadout
from bhgrasp.barrett.sensors import motor_angles
from bhgrasp.barrett.transmission import PROXIMAL_RATIO, SPREAD_RATIO, BarrettTransmission
from bhgrasp.controllers.base import Controller
from bhgrasp.data import State
from bhgrasp.errors import InputError
from bhgrasp.model.hand import Hand

DIGITS = ("F1", "F2", "F3", "SPREAD")  # libbarrett's order
GROUPS = {"GRASP": DIGITS[:3], "WHOLE_HAND": DIGITS}
JOINT_RATIO = np.array([PROXIMAL_RATIO] * 3 + [SPREAD_RATIO])  # libbarrett J2_RATIO, SPREAD_RATIO
INPUT = [1, 2, 3, 0]  # BarrettTransmission input of each digit


class BarrettDriver(Controller):
    """A simulated BH8-280 commanded through libbarrett's calls (module docstring).

    Logs ``puck_modes`` (MODE per digit, F1 F2 F3 SPREAD) and ``motor_torques`` [N m] in the same order.
    """

    def __init__(
        self,
        hand: Hand,
        finger: fw.PuckProperties = fw.FINGER_PUCK,
        spread: fw.PuckProperties = fw.SPREAD_PUCK,
        finger_gains: tuple[float, float, float] | None = None,
        spread_gains: tuple[float, float, float] | None = None,
        fingertip_torque_sensors: bool = True,
        tactile_sensors: bool = True,
        homed: bool = True,
    ) -> None:
        """Four pucks for ``hand``'s motors.

        Args:
            hand: The controller's Barrett hand model (possibly mounted: its mount inputs get zero).
            finger, spread: Firmware properties of the finger pucks and the spread puck.
            finger_gains, spread_gains: (kp [N m/rad], kd [N m s/rad], ki [N m/(rad s)]) at the motor, instead of
                KP, KD, KI through :data:`~bhgrasp.barrett.pucks.PID_SCALE`.
            fingertip_torque_sensors, tactile_sensors: Whether the hand has the options (libbarrett's ``has*``).
            homed: Whether the encoders count from the open stops at power-on (module docstring).
        """
        super().__init__()
        self.drive = BarrettTransmission(hand)
        self.readout = HandReadout(hand, fingertip_torque_sensors, tactile_sensors, homed)
        d = self.drive
        upper = hand.upper
        travel = fw.COUNTS_PER_RAD * motor_angles(upper[d.proximal], upper[d.distal], upper[d.spread[0]])
        self.pucks = [
            fw.Puck(props, (0.0, top), *(gains or (None, None, None)))
            for props, gains, top in zip([finger] * 3 + [spread], [finger_gains] * 3 + [spread_gains], travel)
        ]
        self._script: list[tuple[Any, str, tuple]] = []
        self._pending: list[tuple[str, tuple, dict]] = []
        self.reset_state()

    def reset_state(self) -> None:
        """Clear the sensed encoders and the tick clock (the pucks keep their modes; :meth:`reset` powers on)."""
        self._counts, self._speeds = np.zeros(4), np.zeros(4)
        self._last_tick: float | None = None
        self._u = np.zeros(self.drive.n_inputs)
        self._next, self._waiting = 0, DIGITS
        self._home_spread = False

    def reset(self, state: State) -> None:
        """Power-on at ``state``: every puck IDLE at its encoder, the script rewound (pending commands kept).

        Un-homed (``homed=False``), each encoder counts 0 where it stands.
        """
        self.reset_state()
        self.readout.power_on(state)
        self._read(state)
        for puck, counts in zip(self.pucks, self._counts):
            puck.reset(counts)

    # --- libbarrett's Hand calls ---
    def close(self, digits: str | Sequence[str] = "WHOLE_HAND") -> None:
        """Close toward CT at MCV until there or stalled (``Hand::close``)."""
        self._command("close", (), {"digits": digits})

    def open(self, digits: str | Sequence[str] = "WHOLE_HAND") -> None:
        """Open toward OT at MOV until there or stalled (``Hand::open``)."""
        self._command("open", (), {"digits": digits})

    def trapezoidal_move(self, positions: Any, digits: str | Sequence[str] = "WHOLE_HAND") -> None:
        """Move to inner-link / spread angles [rad] (F1, F2, F3, SPREAD) on trapezoidal profiles."""
        self._command("trapezoidal_move", (self._vector(positions, "positions"),), {"digits": digits})

    def velocity_move(self, velocities: Any, digits: str | Sequence[str] = "WHOLE_HAND") -> None:
        """Run at inner-link / spread rates [rad/s] (F1, F2, F3, SPREAD), limited to MV."""
        self._command("velocity_move", (self._vector(velocities, "velocities"),), {"digits": digits})

    def set_position_mode(self, digits: str | Sequence[str] = "WHOLE_HAND") -> None:
        """PID holding the present positions (``Hand::setPositionMode``)."""
        self._command("set_position_mode", (), {"digits": digits})

    def set_position(self, positions: Any, digits: str | Sequence[str] = "WHOLE_HAND") -> None:
        """PID set points: inner-link / spread angles [rad] (``Hand::setPositionCommand``)."""
        self._command("set_position", (self._vector(positions, "positions"),), {"digits": digits})

    def set_torque_mode(self, digits: str | Sequence[str] = "WHOLE_HAND") -> None:
        """Stream torques (``Hand::setTorqueMode``)."""
        self._command("set_torque_mode", (), {"digits": digits})

    def set_torque(self, torques: Any, digits: str | Sequence[str] = "WHOLE_HAND") -> None:
        """Inner-link / spread joint torques [N m] through the gears, clipped at MT (``Hand::setTorqueCommand``)."""
        self._command("set_torque", (self._vector(torques, "torques"),), {"digits": digits})

    def idle(self) -> None:
        """Every puck IDLE (``Hand::idle``)."""
        self._command("idle", (), {"digits": "WHOLE_HAND"})

    def initialize(self) -> None:
        """Home the hand (``Hand::initialize``, CMD_HI): fingers, then the spread, open to their stops and zero there.

        Done (``done_moving()``) once the spread has.
        """
        self._command("initialize", (), {"digits": "WHOLE_HAND"})

    def done_moving(self, digits: str | Sequence[str] = "WHOLE_HAND") -> bool:
        """Whether each puck of ``digits`` is IDLE or holding in PID with HOLD = 1 (``Hand::doneMoving``)."""
        chosen = self._digits(digits)
        if any(set(chosen) & set(self._digits(kw["digits"])) for _, _, kw in self._pending):
            return False
        if self._home_spread and DIGITS.index("SPREAD") in chosen:
            return False
        return all(self.pucks[i].done() for i in chosen)

    def modes(self) -> dict[str, str]:
        """MODE of each puck by name."""
        return {name: fw.MODES[puck.mode] for name, puck in zip(DIGITS, self.pucks)}

    # --- libbarrett's sensor calls (bhgrasp.barrett.readout) ---
    def has_fingertip_torque_sensors(self) -> bool:
        """Whether the hand has the fingertip torque (strain gauge) option (``Hand::hasFingertipTorqueSensors``)."""
        return self.readout.options[S_FINGERTIP_TORQUE]

    def has_tact_sensors(self) -> bool:
        """Whether the hand has the tactile pads (``Hand::hasTactSensors``)."""
        return self.readout.options[S_TACT_FULL]

    def enable_breakaway_encoders(self, enable: bool) -> None:
        """Link positions from the secondary encoders (default) or from P alone, valid before breakaway only."""
        self.readout.breakaway_encoders = bool(enable)

    def update(self, sensors: int = S_ALL) -> None:
        """Read ``sensors`` at the last sensed state (``Hand::update``), skipping absent options.

        ``sensors``: an OR of ``S_POSITION``, ``S_FINGERTIP_TORQUE``, ``S_TACT_FULL`` (:mod:`bhgrasp.barrett.readout`).
        """
        self.readout.update(sensors)

    def primary_encoder_positions(self) -> np.ndarray:
        """Motor encoders P [counts] (F1, F2, F3, SPREAD) at the last update."""
        return self.readout.primary()

    def secondary_encoder_positions(self) -> np.ndarray:
        """Inner-link (breakaway) encoders [counts] (F1, F2, F3) at the last update."""
        return self.readout.secondary()

    def inner_link_positions(self) -> np.ndarray:
        """Inner-link (proximal) angles [rad] and the spread angle (F1, F2, F3, SPREAD) at the last update."""
        return self.readout.link_positions()[0]

    def outer_link_positions(self) -> np.ndarray:
        """Outer-link (distal, relative to the inner link) angles [rad] and the spread angle at the last update."""
        return self.readout.link_positions()[1]

    def fingertip_torque(self) -> np.ndarray:
        """SG counts (0..4095) of F1, F2, F3 at the last update.

        :func:`~bhgrasp.barrett.sensors.strain_torques` converts them to N m.
        """
        return self.readout.reading(S_FINGERTIP_TORQUE).fingertip_torque.copy()

    def tactile(self) -> np.ndarray:
        """(4, 24) pad cell pressures of F1, F2, F3 and the palm [N/cm^2] at the last update."""
        return self.readout.reading(S_TACT_FULL).tactile.copy()

    def script(self, steps: Sequence[tuple]) -> None:
        """Commands to run during the next simulations: ``(when, command, *args)`` in order.

        ``when``: a time [s] (the step runs once the clock reaches it and the previous step ran), or ``"done"`` (as
        soon as the previous step's digits are done moving: libbarrett's blocking call).  ``command``: a method
        name above, e.g. ``[(0.0, "close", "GRASP"), ("done", "open"), (2.0, "trapezoidal_move", [1, 1, 1, 0])]``.
        """
        checked = []
        for step in steps:
            if len(step) < 2 or not (step[0] == "done" or isinstance(step[0], int | float)):
                raise InputError(f"a script step must be (time [s] or 'done', command, *args), got {step!r}")
            self._method(step[1])  # raises on an unknown command
            checked.append((step[0], step[1], tuple(step[2:])))
        self._script = checked
        self._next = 0

    # --- the controller ---
    def __call__(self, t: float, state: State) -> np.ndarray:
        """Motor torques [N m] (SPREAD, F1, F2, F3, then zeros) for the sensed ``state`` at ``t`` [s]."""
        self._read(state)
        self._run_script(t)
        for name, args, kwargs in self._pending:
            self._apply(name, args, kwargs["digits"])
        self._pending = []
        spread = DIGITS.index("SPREAD")
        if self._home_spread and all(self.pucks[i].done() for i in range(spread)):
            self.pucks[spread].home(self._counts[spread])  # libbarrett: the spread homes once the fingers are done
            self._home_spread = False
        ticks = 1.0 if self._last_tick is None else np.floor((t - self._last_tick) / fw.PERIOD + 1e-9)
        if ticks >= 1.0:
            self._last_tick = t if self._last_tick is None else self._last_tick + ticks * fw.PERIOD
            torques = [p.update(c, s, ticks) for p, c, s in zip(self.pucks, self._counts, self._speeds)]
            self._u[INPUT] = torques
            self._rezero()
        self.log["puck_modes"] = np.array([float(p.mode) for p in self.pucks])
        self.log["motor_torques"] = self._u[INPUT].copy()
        return self._u.copy()

    def _read(self, state: State) -> None:
        v = np.asarray(state.v, dtype=float)
        d = self.drive
        self.readout.sensed = state
        self._counts = self.readout.motor_counts(state.q)
        self._speeds = fw.COUNTS_PER_RAD * motor_angles(v[d.proximal], v[d.distal], v[d.spread[0]]) * 1e-3  # /ms

    def _rezero(self) -> None:
        """A puck that ended its HI counts 0 there from now on."""
        for i, puck in enumerate(self.pucks):
            if puck.homed_at is not None:
                self.readout.rezero(i, puck.homed_at)
                self._counts[i] -= puck.homed_at
                puck.homed_at = None

    def _run_script(self, t: float) -> None:
        while self._next < len(self._script):
            when, name, args = self._script[self._next]
            ready = self.done_moving(self._waiting) if when == "done" else t >= when - 1e-9
            if not ready:
                return
            self._method(name)(*args)
            self._waiting = self._pending[-1][2]["digits"] if self._pending else DIGITS
            self._next += 1

    def _apply(self, name: str, args: tuple, digits: Any) -> None:
        """Set the pucks' properties as libbarrett's call does (module docstring's table)."""
        for i in self._digits(digits):
            puck, counts, j2pp = self.pucks[i], self._counts[i], fw.COUNTS_PER_RAD * JOINT_RATIO[i]
            props = puck.properties
            if name == "close":
                puck.velocity_move(min(props.MCV, props.MV), counts, stop_at=props.CT)
            elif name == "open":
                puck.velocity_move(-min(props.MOV, props.MV), counts, stop_at=props.OT)
            elif name == "trapezoidal_move":
                puck.trapezoidal_move(j2pp * args[0][i], counts)
            elif name == "velocity_move":
                puck.velocity_move(j2pp * args[0][i] * 1e-3, counts)
            elif name == "set_position_mode":
                puck.set_mode(fw.PID, counts)
            elif name == "set_position":
                puck.set_position(j2pp * args[0][i])
            elif name == "set_torque_mode":
                puck.set_mode(fw.TORQUE, counts)
            elif name == "set_torque":
                puck.set_torque(args[0][i] * props.IPNM / JOINT_RATIO[i])
            elif name == "initialize":
                if i == DIGITS.index("SPREAD"):
                    self._home_spread = True  # after the fingers (Hand::initialize waits between)
                else:
                    puck.home(counts)
            else:  # idle
                puck.set_mode(fw.IDLE, counts)

    def _command(self, name: str, args: tuple, kwargs: dict) -> None:
        self._digits(kwargs["digits"])  # checked now, where the user made the mistake
        self._pending.append((name, args, kwargs))

    def _method(self, name: Any) -> Callable:
        valid = (
            "close",
            "open",
            "trapezoidal_move",
            "velocity_move",
            "set_position_mode",
            "set_position",
            "set_torque_mode",
            "set_torque",
            "idle",
            "initialize",
        )
        return getattr(self, require_name(name, valid, "command"))

    @staticmethod
    def _digits(digits: str | Sequence[str]) -> list[int]:
        names = [digits] if isinstance(digits, str) else list(digits)
        chosen: list[int] = []
        for name in names:
            require_name(name, [*DIGITS, *GROUPS], "digit")
            chosen += [DIGITS.index(d) for d in GROUPS.get(name, (name,)) if DIGITS.index(d) not in chosen]
        return chosen

    @staticmethod
    def _vector(values: Any, name: str) -> np.ndarray:
        """A 4-vector (F1, F2, F3, SPREAD) from an array or a {digit: value} dict (others 0)."""
        if isinstance(values, dict):
            array = np.zeros(4)
            for digit, value in values.items():
                array[DIGITS.index(require_name(digit, DIGITS, "digit"))] = value
            values = array
        return as_vector(values, name, 4).copy()


__all__ = ["DIGITS", "GROUPS", "BarrettDriver"]
