"""The host's side of the BH8-280's sensors: what libbarrett's ``Hand::update`` last read, where encoders count from.

libbarrett (``src/products/hand.cpp``, ``Hand::update``) requests the pucks' P (primary and secondary encoders), SG
(fingertip torque) and TACT (pads) properties for the sensors a call names (``S_POSITION``, ``S_FINGERTIP_TORQUE``,
``S_TACT_FULL``), skipping the options the hand lacks (``hasFingertipTorqueSensors``, ``hasTactSensors``); its
getters return what that call received.  Link positions come from the secondary encoders unless
``enableBreakawayEncoders(false)`` (then from P, valid before breakaway only).

Encoders are incremental: a puck counts from where it was zeroed.  A hand just powered on counts 0 wherever it
stands; ``Hand::initialize`` (CMD_HI) opens each finger until it stalls on its stop and zeroes it there, then the
spread.  Assumption: the HI zeroes a finger's secondary encoder with its primary.
"""

from __future__ import annotations

import numpy as np

from bhgrasp.barrett.pucks import COUNTS_PER_RAD
from bhgrasp.barrett.sensors import (
    SECONDARY_RATIO,
    BarrettReading,
    BarrettSensors,
    link_positions,
    motor_angles,
)
from bhgrasp.barrett.transmission import BarrettTransmission
from bhgrasp.data import State
from bhgrasp.errors import InputError
from bhgrasp.model.hand import Hand

S_POSITION, S_FINGERTIP_TORQUE, S_TACT_FULL = 1, 2, 4  # libbarrett Hand::update's sensor flags
S_ALL = S_POSITION | S_FINGERTIP_TORQUE | S_TACT_FULL


class HandReadout:
    """Encoder zeros and the last :meth:`update`'s readings of one simulated hand (module docstring)."""

    def __init__(
        self, hand: Hand, fingertip_torque_sensors: bool = True, tactile_sensors: bool = True, homed: bool = True
    ) -> None:
        """``homed``: whether the encoders count from the open stops at power-on (as after ``initialize()``)."""
        drive = BarrettTransmission(hand)
        self._proximal, self._distal, self._spread = drive.proximal, drive.distal, drive.spread[0]
        self.sensors = BarrettSensors(hand)
        self.options = {S_FINGERTIP_TORQUE: bool(fingertip_torque_sensors), S_TACT_FULL: bool(tactile_sensors)}
        self.homed, self.breakaway_encoders = bool(homed), True
        self.power_on(None)

    def power_on(self, state: State | None) -> None:
        """Forget the readings; zero the encoders at ``state`` unless homed (or at the stops if ``state`` is None)."""
        self.sensed: State | None = state
        self.readings: dict[int, BarrettReading] = {}
        self.zero, self.secondary_zero = np.zeros(4), np.zeros(3)  # absolute counts where each counts 0
        if state is not None and not self.homed:
            self.zero = np.rint(self.motor_counts(state.q, absolute=True))
            self.secondary_zero = np.rint(SECONDARY_RATIO * COUNTS_PER_RAD * np.asarray(state.q)[self._proximal])

    def motor_counts(self, q: np.ndarray, absolute: bool = False) -> np.ndarray:
        """(4,) motor angles of F1, F2, F3, SPREAD at joint angles ``q`` in counts (unrounded), from the zeros."""
        q = np.asarray(q, dtype=float)
        counts = COUNTS_PER_RAD * motor_angles(q[self._proximal], q[self._distal], q[self._spread])
        return counts if absolute else counts - self.zero

    def rezero(self, puck: int, counts: float) -> None:
        """Puck ``puck`` ended its HI at ``counts`` (from its old zero): it counts 0 there from now on."""
        self.zero[puck] += counts
        if puck < 3 and self.sensed is not None:
            inner = np.asarray(self.sensed.q, dtype=float)[self._proximal[puck]]
            self.secondary_zero[puck] = np.rint(SECONDARY_RATIO * COUNTS_PER_RAD * inner)

    def update(self, sensors: int = S_ALL) -> None:
        """Read ``sensors`` (an OR of the ``S_*`` flags) at the state last sensed, skipping absent options."""
        if isinstance(sensors, bool) or not isinstance(sensors, int | np.integer) or not 0 <= sensors <= S_ALL:
            flags = "an OR of S_POSITION 1, S_FINGERTIP_TORQUE 2, S_TACT_FULL 4"
            raise InputError(f"`sensors` must be {flags}, got {sensors!r}")
        if self.sensed is None:
            raise InputError("the driver has sensed no state yet: reset it or run it before update()")
        reading = self.sensors.read(self.sensed)
        for flag in (S_POSITION, S_FINGERTIP_TORQUE, S_TACT_FULL):
            if sensors & flag and self.options.get(flag, True):
                self.readings[flag] = reading
        if sensors & S_POSITION:  # the counts from the zeros, and libbarrett's link formulas, as of this update
            self._zeros_read = (self.zero.astype(np.int64), self.secondary_zero.astype(np.int64))
            secondary = self.secondary() if self.breakaway_encoders else None
            self._links = link_positions(self.primary(), secondary)

    def reading(self, flag: int) -> BarrettReading:
        """The last update's reading of sensor ``flag``.

        Raises:
            InputError: The hand lacks that option, or no update has read it.
        """
        if not self.options.get(flag, True):
            name = {S_FINGERTIP_TORQUE: "fingertip torque sensors", S_TACT_FULL: "tactile pads"}[flag]
            raise InputError(f"this hand has no {name} (built without the option)")
        if flag not in self.readings:
            raise InputError("no reading yet: call update() (libbarrett's getters return what update() read)")
        return self.readings[flag]

    def primary(self) -> np.ndarray:
        """(4,) P [counts] of F1, F2, F3, SPREAD."""
        return self.reading(S_POSITION).primary_encoder - self._zeros_read[0]

    def secondary(self) -> np.ndarray:
        """(3,) inner-link encoder counts of F1, F2, F3."""
        return self.reading(S_POSITION).secondary_encoder - self._zeros_read[1]

    def link_positions(self) -> tuple[np.ndarray, np.ndarray]:
        """(inner, outer) link positions [rad] (F1, F2, F3, SPREAD) as libbarrett computed them at the last update."""
        self.reading(S_POSITION)  # raises before the first update
        return self._links[0].copy(), self._links[1].copy()


__all__ = ["S_ALL", "S_FINGERTIP_TORQUE", "S_POSITION", "S_TACT_FULL", "HandReadout"]
