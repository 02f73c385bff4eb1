"""Simulation: the scene, contacts, actuation, the Simulator over its engine protocol, and batches.

Modules, one concept each:

- the scene: :mod:`~bhgrasp.sim.scene` (hand, objects and environment as one Pinocchio model and coal geometry),
  :mod:`~bhgrasp.sim.scene_parts` (its dynamics part by part: the hand's model and one per object),
  :mod:`~bhgrasp.sim.scene_layout` (what a step reads of it: free bodies' spin, springs, quaternions, its signature);
- contacts: :mod:`~bhgrasp.sim.contact` (detection), :mod:`~bhgrasp.sim.contact_law` (the spring-damper + Coulomb
  law);
- actuation: :mod:`~bhgrasp.sim.actuation` (full actuation; the Barrett hand's four motors and TorqueSwitch);
- the Simulator: :mod:`~bhgrasp.sim.settings` (its frozen settings), :mod:`~bhgrasp.sim.simulator` (its contract and
  a step's dispatch), :mod:`~bhgrasp.sim.state_check` (a state checked against the scene; divergences in words),
  :mod:`~bhgrasp.sim.inputs` (inputs checked), :mod:`~bhgrasp.sim.step_output` (what a step returns),
  :mod:`~bhgrasp.sim.run_loop` (``Simulator.run``: controller, sensors, disturbances, recording),
  :mod:`~bhgrasp.sim.recorder`, :mod:`~bhgrasp.sim.sensor_model` (what the sensors get wrong);
- the engines: :mod:`~bhgrasp.sim.engine` (the protocol over plain data), :mod:`~bhgrasp.sim.python_engine` (the
  readable reference step) with :mod:`~bhgrasp.sim.integrators`, :mod:`~bhgrasp.sim.compiled` (the C++ step of
  ``bhgrasp._core``), :mod:`~bhgrasp.sim.batch` (batched rollouts).

The states, trajectories and contacts it makes are the plain data of :mod:`bhgrasp.data`.
"""

from bhgrasp.sim.settings import ENGINES, INTEGRATORS, SimulatorSettings
from bhgrasp.sim.simulator import Simulator
from bhgrasp.sim.step_output import StepInfo

__all__ = ["ENGINES", "INTEGRATORS", "Simulator", "SimulatorSettings", "StepInfo"]
