"""The run loop of :meth:`Simulator.run <bhgrasp.sim.simulator.Simulator.run>`: a controller closed on the simulation.

Each physics step: the controller reads the sensed state every ``control_dt`` (inputs held in between), a sample is
recorded every ``record_every`` steps, the disturbance torques and object forces of the step's start time are added,
and the run stops early at the first state ``until`` accepts.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np

from bhgrasp._validation import as_positive, as_vector
from bhgrasp.errors import InputError
from bhgrasp.sim.contact import empty_contact_set
from bhgrasp.sim.recorder import Recorder
from bhgrasp.sim.sensor_model import SensorModel, Sensors
from bhgrasp.sim.state import State, Trajectory
from bhgrasp.sim.step_output import StepInfo

if TYPE_CHECKING:
    from bhgrasp.sim.simulator import Simulator


def run(
    simulator: Simulator,
    controller: Callable[[float, State], Any],
    duration: float,
    state: State | None = None,
    control_dt: float | None = None,
    sensor_noise: tuple[float, float] | None = None,
    disturbance: Callable[[float], Any] | Any = None,
    seed: int | None = None,
    progress: bool = True,
    record_every: int = 1,
    object_forces: Callable[[float], Any] | None = None,
    until: Callable[[State], bool] | None = None,
    sensors: SensorModel | None = None,
) -> Trajectory:
    """Simulate ``duration`` [s] of ``simulator`` under ``controller`` and record everything.

    The arguments are those of :meth:`~bhgrasp.sim.simulator.Simulator.run`, which documents them.
    """
    duration = as_positive(duration, "duration")
    steps = round(duration / simulator.dt)
    hold = 1 if control_dt is None else round(as_positive(control_dt, "control_dt") / simulator.dt)
    if hold < 1 or abs(hold * simulator.dt - (control_dt or simulator.dt)) > 1e-9 * max(1.0, hold):
        raise InputError(f"`control_dt` must be a positive multiple of dt = {simulator.dt}, got {control_dt}")
    if sensor_noise is not None:
        if sensors is not None:
            raise InputError("give `sensor_noise` or `sensors`, not both (sensor_noise is short for sensors)")
        if seed is None:
            raise InputError("`sensor_noise` needs a `seed` (runs are deterministic)")
        sigma = as_vector(sensor_noise, "sensor_noise", 2)
        sensors = SensorModel(joint_position=sigma[0], joint_velocity=sigma[1])
    reader = Sensors(SensorModel() if sensors is None else sensors, seed)
    if isinstance(record_every, bool) or not isinstance(record_every, int | np.integer) or record_every < 1:
        raise InputError(f"`record_every` must be a positive integer (physics steps per sample), got {record_every!r}")
    if disturbance is not None and not callable(disturbance):
        disturbance = simulator._disturbance(disturbance, "disturbance")
    state = simulator.initial_state() if state is None else state
    if state.scene_q is None or state.scene_q.shape != (simulator.scene.nq,):
        raise InputError(
            f"`state` must be a state of this simulator's scene (nq = {simulator.scene.nq}); use "
            "Simulator.initial_state() or a state a run of this simulator returned"
        )
    simulator.actuation.restore(state.actuation_modes, state.scene_q[: simulator.scene.nq_hand])
    if isinstance(getattr(controller, "log", None), dict):
        controller.log.clear()  # each run records its own internals, never the last run's
    if hasattr(controller, "reset"):
        controller.reset(state)
    recorder = Recorder(simulator.scene, simulator.actuation)
    u = np.zeros(simulator.actuation.n_inputs)
    info = StepInfo(empty_contact_set(), np.zeros(simulator._nvh))
    iterator = range(steps)
    if progress and steps > 20_000:
        from tqdm import tqdm

        iterator = tqdm(iterator, desc="simulating", unit="step", mininterval=1.0)
    for k in iterator:
        if k % hold == 0:
            sensed = reader.read(state)
            u = simulator._input(np.array(controller(state.t, sensed), dtype=float), state.t)
        if k % record_every == 0:
            recorder.add(state, u, info, getattr(controller, "log", None))
        torque = (
            simulator._disturbance(disturbance(state.t), "disturbance(t)") if callable(disturbance) else disturbance
        )
        if object_forces is not None:
            torque = simulator._with_object_forces(torque, object_forces(state.t))
        state, info = simulator._advance(state, u, torque)
        if until is not None and until(state):
            break
    recorder.add(state, u, info, getattr(controller, "log", None))
    return recorder.trajectory()


__all__ = ["run"]
