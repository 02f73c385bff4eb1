"""Simulation: the scene, contacts, actuation, integrators, the Simulator and its two engines, states and batches.

Modules, one concept each: :mod:`~bhgrasp.sim.scene` (hand, objects and environment as one Pinocchio model and coal
geometry), :mod:`~bhgrasp.sim.contact` (detection: the contact engine), :mod:`~bhgrasp.sim.contact_law` (the
spring-damper + Coulomb law), :mod:`~bhgrasp.sim.contact_set` (contacts as data: ContactSet, Contact,
ContactMemory), :mod:`~bhgrasp.sim.actuation` (full actuation; the Barrett hand's four motors and TorqueSwitch),
:mod:`~bhgrasp.sim.integrators` (free-body rotation: gyroscopic torque and Munthe-Kaas increments),
:mod:`~bhgrasp.sim.simulator` (the Simulator: options, input and divergence checks, a step's dispatch to its
engine), :mod:`~bhgrasp.sim.python_engine` (the Python reference step and its integrators),
:mod:`~bhgrasp.sim.compiled` (the C++ engine of ``bhgrasp._core``), :mod:`~bhgrasp.sim.step_output` (what a step
returns: StepInfo, the source of its state's fields), :mod:`~bhgrasp.sim.run_loop` (the loop of ``Simulator.run``:
controller, sensors, disturbances, recording), :mod:`~bhgrasp.sim.sensor_model` (what the sensors get wrong),
:mod:`~bhgrasp.sim.batch` (batched rollouts), :mod:`~bhgrasp.sim.state` (State, Trajectory) and
:mod:`~bhgrasp.sim.recorder`.  ``from bhgrasp.sim import Simulator`` keeps working; the package's public names are
re-exported from :mod:`bhgrasp` as well.
"""

from bhgrasp.sim.simulator import ENGINES, INTEGRATORS, Simulator, StepInfo

__all__ = ["ENGINES", "INTEGRATORS", "Simulator", "StepInfo"]
