"""The Barrett BH8-280 as its users know it: its drive (four motors, gears, TorqueSwitch) and its driver.

:mod:`bhgrasp.barrett.transmission` holds the hand's own facts (gear ratios, puck limits, the TorqueSwitch rule);
the simulator (:class:`~bhgrasp.sim.actuation.BarrettActuation`) and the controllers
(:class:`~bhgrasp.controllers.supervisor.MotorCommands`) both use it.  :mod:`bhgrasp.barrett.pucks` models the
motor pucks' firmware (modes, PID, trapezoidal and velocity moves) and :mod:`bhgrasp.barrett.commands` the
libbarrett ``Hand`` calls on them (:class:`BarrettDriver`, a controller that outputs motor torques).
"""

from typing import Any

from bhgrasp.barrett.pucks import (
    FINGER_PUCK,
    IDLE,
    PID,
    SPREAD_PUCK,
    TORQUE,
    TRAPEZOIDAL,
    VELOCITY,
    Puck,
    PuckProperties,
)
from bhgrasp.barrett.transmission import BarrettTransmission


def __getattr__(name: str) -> Any:
    """The driver loads on first use: it is a controller, and the simulator imports this package's transmission."""
    if name in ("DIGITS", "BarrettDriver"):
        from bhgrasp.barrett import commands

        return getattr(commands, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = [
    "DIGITS",
    "FINGER_PUCK",
    "IDLE",
    "PID",
    "SPREAD_PUCK",
    "TORQUE",
    "TRAPEZOIDAL",
    "VELOCITY",
    "BarrettDriver",
    "BarrettTransmission",
    "Puck",
    "PuckProperties",
]
