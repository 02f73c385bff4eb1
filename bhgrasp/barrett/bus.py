"""The BH8-280's four motor pucks on their bus, as one controller: what libbarrett's calls act on.

:class:`PuckBus` reads the motor encoders from the sensed joint angles (:class:`~bhgrasp.barrett.readout.HandReadout`
keeps where they count from), runs the pucks (:mod:`bhgrasp.barrett.pucks`) at their 1 kHz tick (holding the output
in between), sets their properties as each libbarrett call does (:meth:`PuckBus._apply`, the table of
:mod:`bhgrasp.barrett.commands`), runs a script of timed and blocking calls, and returns the motor torques [N m] in
:class:`~bhgrasp.barrett.transmission.BarrettTransmission`'s input order (SPREAD, F1, F2, F3, then zero for a
mount's joints).  :class:`~bhgrasp.barrett.commands.BarrettDriver` adds libbarrett's ``Hand`` calls.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from bhgrasp._validation import as_vector, require_name
from bhgrasp.barrett import pucks as fw
from bhgrasp.barrett.readout import HandReadout
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
COMMANDS = (
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
    "set_property",
)  # what a script step may call


class PuckBus(Controller):
    """Four pucks for a Barrett hand's motors, ticked at 1 kHz as a controller (module docstring).

    Logs ``puck_modes`` (MODE per digit, F1 F2 F3 SPREAD) and ``motor_torques`` [N m] in the same order.
    """

    def __init__(
        self,
        hand: Hand,
        finger: fw.PuckProperties | Sequence[fw.PuckProperties] = fw.FINGER_PUCK,
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
            finger, spread: Firmware properties of the finger pucks (one for all, or F1, F2, F3's: libbarrett sets a
                property on each puck) and of the spread puck.
            finger_gains, spread_gains: (kp [N m/rad], kd [N m s/rad], ki [N m/(rad s)]) at the motor, instead of
                KP, KD, KI through :data:`~bhgrasp.barrett.pucks.PID_SCALE`.
            fingertip_torque_sensors, tactile_sensors: Whether the hand has the options (libbarrett's ``has*``).
            homed: Whether the encoders count from the open stops at power-on (:mod:`bhgrasp.barrett.commands`).
        """
        super().__init__()
        self.drive = BarrettTransmission(hand)
        self.readout = HandReadout(hand, fingertip_torque_sensors, tactile_sensors, homed)
        d = self.drive
        upper = hand.upper
        travel = fw.COUNTS_PER_RAD * motor_angles(upper[d.proximal], upper[d.distal], upper[d.spread[0]])
        fingers = [finger] * 3 if isinstance(finger, fw.PuckProperties) else list(finger)
        if len(fingers) != 3 or not all(isinstance(f, fw.PuckProperties) for f in fingers):
            raise InputError(f"`finger` must be PuckProperties or three of them (F1, F2, F3), got {finger!r}")
        self.pucks = [
            fw.Puck(props, (0.0, top), *(gains or (None, None, None)))
            for props, gains, top in zip([*fingers, spread], [finger_gains] * 3 + [spread_gains], travel)
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

        ``Simulator.run`` calls it at the start of every run.  Un-homed (``homed=False``), each encoder then counts 0
        where it stands (an earlier ``initialize()`` is forgotten); properties set by ``set_property`` stay (build a
        new driver for the firmware's defaults).
        """
        self.reset_state()
        self.readout.power_on(state)
        self._read(state)
        for puck, counts in zip(self.pucks, self._counts):
            puck.reset(counts)

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
        """Motor torques [N m] (SPREAD, F1, F2, F3, then zeros) for the sensed ``state`` at ``t`` [s].

        The encoders are read (from ``state``) when a puck ticks or a command or a homing takes them; between the
        pucks' ticks the output holds.
        """
        self.readout.sensed = state
        self._run_script(t)
        ticks = 1.0 if self._last_tick is None else float(math.floor((t - self._last_tick) / fw.PERIOD + 1e-9))
        if self._pending or self._home_spread or ticks >= 1.0:  # what reads the encoders
            self._read(state)
        changed = bool(self._pending) or "puck_modes" not in self.log  # the log: each run's first call, then changes
        for name, args, kwargs in self._pending:
            self._apply(name, args, kwargs["digits"])
        self._pending = []
        spread = DIGITS.index("SPREAD")
        if self._home_spread and all(self.pucks[i].done() for i in range(spread)):
            self.pucks[spread].home(self._counts[spread])  # libbarrett: the spread homes once the fingers are done
            self._home_spread, changed = False, True
        if ticks >= 1.0:
            self._last_tick = t if self._last_tick is None else self._last_tick + ticks * fw.PERIOD
            torques = [p.update(c, s, ticks) for p, c, s in zip(self.pucks, self._counts, self._speeds)]
            self._u[INPUT] = torques
            self._rezero()
            changed = True
        if changed:
            self.log["puck_modes"] = np.array([float(p.mode) for p in self.pucks])
            self.log["motor_torques"] = self._u[INPUT].copy()
        return self._u.copy()

    def _read(self, state: State) -> None:
        """The motor encoders [counts] and speeds [counts/ms] at ``state``."""
        v = np.asarray(state.v, dtype=float)
        d = self.drive
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
            elif name == "set_property":
                puck.properties = props.with_(**{args[0]: args[1]})
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
        return getattr(self, require_name(name, COMMANDS, "command"))

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


__all__ = ["COMMANDS", "DIGITS", "GROUPS", "INPUT", "JOINT_RATIO", "PuckBus"]
