"""The BH8-280 as its users command it: libbarrett's ``Hand`` calls on four simulated pucks, as a controller.

:class:`BarrettDriver` is a :class:`~bhgrasp.controllers.base.Controller` (through
:class:`~bhgrasp.barrett.bus.PuckBus`, the pucks' mechanics): each call reads the motor encoders from
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
``pucks[i]->setProperty(p, v)``      any property, e.g. MT                      ``set_property(p, v, digits)``
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

from collections.abc import Sequence
from typing import Any

import numpy as np

from bhgrasp._validation import require_name
from bhgrasp.barrett import pucks as fw
from bhgrasp.barrett.bus import DIGITS, GROUPS, PuckBus
from bhgrasp.barrett.readout import S_ALL, S_FINGERTIP_TORQUE, S_TACT_FULL

SETTABLE = ("MT", "MV", "ACCEL", "TSTOP", "HOLD", "CT", "OT", "MCV", "MOV")  # set_property's


class BarrettDriver(PuckBus):
    """A simulated BH8-280 commanded through libbarrett's calls (module docstring; the mechanics: :class:`PuckBus`).

    Logs ``puck_modes`` (MODE per digit, F1 F2 F3 SPREAD) and ``motor_torques`` [N m] in the same order.
    """

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

    def set_property(self, name: str, value: float, digits: str | Sequence[str] = "WHOLE_HAND") -> None:
        """Set a puck property of ``digits`` (libbarrett ``Puck::setProperty``), e.g. ``("MT", 1100, "F1")``.

        One of :data:`SETTABLE` (the gains and IPNM are fixed when the driver is built).
        """
        require_name(name, SETTABLE, "puck property")
        fw.FINGER_PUCK.with_(**{name: value})  # checks the value
        self._command("set_property", (name, value), {"digits": digits})

    def initialize(self) -> None:
        """Home the hand (``Hand::initialize``, CMD_HI): fingers, then the spread, open to their stops and zero there.

        Done (``done_moving()``) once the spread has.
        """
        self._command("initialize", (), {"digits": "WHOLE_HAND"})

    # --- libbarrett's sensor calls (bhgrasp.barrett.readout) ---
    def has_fingertip_torque_sensors(self) -> bool:
        """Whether the hand has the fingertip torque (strain gauge) option (``Hand::hasFingertipTorqueSensors``)."""
        return self.readout.options[S_FINGERTIP_TORQUE]

    def has_tact_sensors(self) -> bool:
        """Whether the hand has the tactile pads (``Hand::hasTactSensors``)."""
        return self.readout.options[S_TACT_FULL]

    def enable_breakaway_encoders(self, enable: bool) -> None:
        """Link positions from the secondary encoders (default) or from P alone, valid before breakaway only.

        Applies from the next :meth:`update`, as libbarrett's flag does.
        """
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


__all__ = ["DIGITS", "GROUPS", "SETTABLE", "BarrettDriver"]
