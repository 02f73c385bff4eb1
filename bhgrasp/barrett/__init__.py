"""The Barrett BH8-280 as its users know it: its drive (motors, gears, TorqueSwitch), its sensors and its driver.

:mod:`bhgrasp.barrett.transmission` holds the hand's own facts (gear ratios, puck limits, the TorqueSwitch rule,
the worm drives); the simulator (:class:`~bhgrasp.sim.actuation.BarrettActuation`) and the controllers
(:class:`~bhgrasp.controllers.motor_commands.MotorCommands`) both use it.  :mod:`bhgrasp.barrett.sensors` reads a
:class:`~bhgrasp.data.state.State` as libbarrett reports the hand's encoders, fingertip torque sensors and tactile
pads (:mod:`bhgrasp.barrett.tactile`).  :mod:`bhgrasp.barrett.pucks` models the motor pucks' firmware (modes, PID,
trapezoidal and velocity moves, HI) and :mod:`bhgrasp.barrett.commands` the libbarrett ``Hand`` calls on them
(:class:`BarrettDriver`, a controller that outputs motor torques), whose ``update()`` reads the sensors into
:mod:`bhgrasp.barrett.readout`.
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
from bhgrasp.barrett.readout import S_ALL, S_FINGERTIP_TORQUE, S_POSITION, S_TACT_FULL
from bhgrasp.barrett.sensors import (
    BarrettReading,
    BarrettSensors,
    SensorLoads,
    encoder_counts,
    link_positions,
    motor_angles,
    strain_counts,
    strain_torques,
)
from bhgrasp.barrett.tactile import TactilePad, digitise_pressures, finger_pad, pad_pressures, palm_pad
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
    "S_ALL",
    "S_FINGERTIP_TORQUE",
    "S_POSITION",
    "S_TACT_FULL",
    "TORQUE",
    "TRAPEZOIDAL",
    "VELOCITY",
    "BarrettDriver",
    "BarrettReading",
    "BarrettSensors",
    "BarrettTransmission",
    "Puck",
    "PuckProperties",
    "SensorLoads",
    "TactilePad",
    "digitise_pressures",
    "encoder_counts",
    "finger_pad",
    "link_positions",
    "motor_angles",
    "pad_pressures",
    "palm_pad",
    "strain_counts",
    "strain_torques",
]
