"""The Barrett BH8-280 as its users know it: its drive (four motors, gears, TorqueSwitch) and, later, its driver.

:mod:`bhgrasp.barrett.transmission` holds the hand's own facts (gear ratios, puck limits, the TorqueSwitch rule);
the simulator (:class:`~bhgrasp.sim.actuation.BarrettActuation`) and the controllers
(:class:`~bhgrasp.controllers.supervisor.MotorCommands`) both use it.
"""

from bhgrasp.barrett.transmission import BarrettTransmission

__all__ = ["BarrettTransmission"]
