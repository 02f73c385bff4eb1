"""The run loop, :meth:`Simulator.run <bhgrasp.sim.simulator.Simulator.run>`: a controller closed on the simulation.

Each physics step: the controller reads the sensed state every ``control_dt`` (inputs held in between), a sample is
recorded every ``record_every`` steps, the disturbance torques and object forces of the step's start time are added,
and the run stops early at the first state ``until`` accepts.  The loop steps through the Simulator's public
:meth:`~bhgrasp.sim.simulator.Simulator.step`, and the function is the Simulator's ``run`` method (one signature).
While the controller offers its next cycles as a compiled loop (``compiled_control``, a :class:`LoopOffer`) and the
run is plain (exact sensors, one cycle and one sample a step, no disturbance, object forces or ``until``), the
simulator's ``run_compiled`` takes them in C++ instead, with the same bits (``tests/test_closed_loop.py``).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np

from bhgrasp._validation import as_positive, as_vector
from bhgrasp.data import State, Trajectory
from bhgrasp.errors import InputError
from bhgrasp.sim.inputs import joint_torques
from bhgrasp.sim.recorder import Recorder
from bhgrasp.sim.sensor_model import SensorModel, Sensors
from bhgrasp.sim.step_output import StepInfo

if TYPE_CHECKING:
    from bhgrasp.sim.actuation import Actuation
    from bhgrasp.sim.scene import Scene


class Stepper(Protocol):
    """What the loop needs of a :class:`~bhgrasp.sim.simulator.Simulator`: its step, scene, actuation and dt.

    Optional: ``closes_loops_in_cpp()`` and ``run_compiled(state, loop, until, steps)``, the compiled loop
    (:meth:`Simulator.run_compiled <bhgrasp.sim.simulator.Simulator.run_compiled>`).
    """

    dt: float
    scene: Scene
    actuation: Actuation

    def initial_state(self) -> State:
        """The scene's start state."""
        ...

    def check_state(self, state: State) -> State:
        """``state`` if it belongs to this scene, else an ``InputError``."""
        ...

    def step(self, state: State, u: Any, disturbance: Any = None, object_forces: Any = None) -> tuple[State, StepInfo]:
        """One physics step from ``state`` under inputs ``u``."""
        ...


def run(
    simulator: Stepper,
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
    """Simulate ``duration`` [s] under ``controller`` and record everything.

    Args:
        simulator: The simulator (``self`` of :meth:`Simulator.run <bhgrasp.sim.simulator.Simulator.run>`).
        controller: ``(t, state) -> u`` callable or object with ``reset(state)``; an optional ``log`` dict
            (name -> latest value) is recorded at every sample; an optional ``compiled_control(t, state)`` offers
            its next cycles as a compiled loop (:class:`LoopOffer`, or ``None``).
        duration: Simulated time [s].
        state: Start state (default :meth:`~bhgrasp.sim.simulator.Simulator.initial_state`).
        control_dt: Controller period [s] (a multiple of ``dt``; inputs held in between); default ``dt``.
        sensor_noise: (sigma_q [rad], sigma_v [rad/s]) Gaussian noise on the hand state the controller sees:
            short for ``sensors=SensorModel(joint_position=sigma_q, joint_velocity=sigma_v)``.
        disturbance: Joint torques [N m] added to the actuators': an array, or a callable ``t -> array``.
        seed: Seed of the sensor noise (required with noisy ``sensor_noise`` or ``sensors``).
        progress: Show a tqdm progress bar for runs of more than 20 000 steps.
        record_every: Record one sample every this many physics steps.
        object_forces: ``t -> (n_objects, 3)`` forces [N, world frame] on the objects' centres of mass (e.g. a
            shake test), or ``None``.
        until: ``state -> bool`` checked after every step: the run stops early at the first state it accepts
            (e.g. an object that left the hand); the trajectory ends there.
        sensors: What the controller's sensors get wrong (:class:`~bhgrasp.sim.sensor_model.SensorModel`: noise
            on the joints, the object's pose and twist and the contact forces, and a delay).
    """
    steps = round(as_positive(duration, "duration") / simulator.dt)
    hold = _control_steps(simulator.dt, control_dt)
    reader = Sensors(_sensor_model(sensor_noise, sensors, seed), seed)
    if isinstance(record_every, bool) or not isinstance(record_every, int | np.integer) or record_every < 1:
        raise InputError(f"`record_every` must be a positive integer (physics steps per sample), got {record_every!r}")
    if disturbance is not None and not callable(disturbance):
        disturbance = joint_torques(disturbance, simulator.scene.nv_hand, "disturbance")
    state = _start(simulator, controller, state)
    recorder = Recorder(simulator.scene, simulator.actuation, steps // record_every + 2)
    u = np.zeros(simulator.actuation.n_inputs)
    info = StepInfo.empty(simulator.scene.nv_hand)
    bar = None
    if progress and steps > 20_000:
        from tqdm import tqdm

        bar = tqdm(total=steps, desc="simulating", unit="step", mininterval=1.0)
    plain = hold == 1 and record_every == 1 and reader.model.exact and disturbance is None and object_forces is None
    in_cpp = plain and until is None and hasattr(controller, "compiled_control")
    in_cpp = in_cpp and getattr(simulator, "closes_loops_in_cpp", lambda: False)()
    k = 0
    try:
        while k < steps:
            if in_cpp:  # the steps the controller's compiled loop takes (none if it offers none), then one here
                taken, state, info, last = _compiled_steps(simulator, controller, recorder, state, info, steps - k)
                k, u = k + taken, u if last is None else last
                if bar is not None:
                    bar.update(taken)
                if k >= steps:
                    break
            if k % hold == 0:
                sensed = reader.read(state)
                u = _control(controller, state.t, sensed)
            if k % record_every == 0:
                recorder.add(state, u, info, getattr(controller, "log", None))
            torque = disturbance
            if callable(disturbance):
                torque = joint_torques(disturbance(state.t), simulator.scene.nv_hand, "disturbance(t)")
            forces = None if object_forces is None else object_forces(state.t)
            state, info = simulator.step(state, u, torque, forces)
            k += 1
            if bar is not None:
                bar.update(1)
            if until is not None and until(state):
                break
    finally:
        if bar is not None:
            bar.close()
    recorder.add(state, u, info, getattr(controller, "log", None))
    return recorder.trajectory()


class LoopOffer(Protocol):
    """What the loop needs of a controller's ``compiled_control(t, state)``: its next cycles as a compiled loop.

    ``loop``: the loop controller (a ``bhgrasp._core.LoopController``); ``until`` [s]: its next switch (the loop
    stops before a step at t >= until); ``log_rows``, ``settle`` and ``fail`` as their docstrings say.
    """

    loop: Any
    until: float

    def log_rows(self, rows: np.ndarray, q_hand: np.ndarray) -> dict[str, np.ndarray]:
        """Every entry of the controller's log after each of n cycles, ``(n, *shape)``.

        From the loop's log rows (n, log_size) and the hand's joint positions [rad] the cycles read (n, nq).
        """
        ...

    def settle(self, run: Any, q_hand: np.ndarray) -> None:
        """The controller's clock and log as the last cycle the run completed left them (``q_hand``: one row each)."""
        ...

    def fail(self, run: Any, state: State) -> None:
        """Raise what the cycle that stopped the run (its ``status`` > 0) raises at ``state``; else nothing."""
        ...


CHUNK = 4096  # steps at most in one compiled call (the GIL and Ctrl-C wait for it; its rows are allocated at once)


def _compiled_steps(
    simulator: Any, controller: Any, recorder: Recorder, state: State, info: StepInfo, steps: int
) -> tuple[int, State, StepInfo, np.ndarray | None]:
    """The steps (up to ``steps``) the controller's compiled loop takes from ``state``, recorded as the loop would.

    The controller's ``compiled_control(t, state)`` offers a :class:`LoopOffer` for the steps from ``state``
    (``None``: not now); the simulator's ``run_compiled`` runs them in C++ (``None``: it cannot), bit for bit the
    steps this loop would take with exact sensors, one control cycle and one sample a step and no disturbance.
    Returns the steps taken, the state and info after them and the last inputs (``None`` if none).

    Raises:
        SimulationDiverged: A step diverged (the controller settled first, as this loop leaves it).
    """
    control = controller.compiled_control(state.t, state)
    done = None if control is None else simulator.run_compiled(state, control.loop, control.until, min(steps, CHUNK))
    if done is None:
        return 0, state, info, None
    run, after, after_info, diverged = done
    n = int(run.steps)
    cycles = n + (diverged is not None)  # the diverged step's cycle ran
    nq = simulator.scene.nq_hand
    q_hand = np.concatenate((state.scene_q[None, :nq], run.q[: cycles - 1, :nq]))[:cycles]
    if n:
        recorder.add_run(state, info, run, control.log_rows(run.log[:n], q_hand[:n]))
    control.settle(run, q_hand)
    if diverged is not None:
        raise diverged
    control.fail(run, after)
    return n, after, after_info if n else info, run.u[n - 1] if n else None


def _control_steps(dt: float, control_dt: float | None) -> int:
    """Physics steps per control period: ``control_dt`` [s] must be a positive multiple of ``dt`` (default ``dt``)."""
    hold = 1 if control_dt is None else round(as_positive(control_dt, "control_dt") / dt)
    if hold < 1 or abs(hold * dt - (control_dt or dt)) > 1e-9 * max(1.0, hold):
        raise InputError(f"`control_dt` must be a positive multiple of dt = {dt}, got {control_dt}")
    return hold


def _sensor_model(sensor_noise: Any, sensors: SensorModel | None, seed: int | None) -> SensorModel:
    """The run's sensor model: ``sensors``, or ``sensor_noise`` = (sigma_q, sigma_v) as one (seeded), or exact."""
    if sensor_noise is None:
        return SensorModel() if sensors is None else sensors
    if sensors is not None:
        raise InputError("give `sensor_noise` or `sensors`, not both (sensor_noise is short for sensors)")
    if seed is None:
        raise InputError("`sensor_noise` needs a `seed` (runs are deterministic)")
    sigma = as_vector(sensor_noise, "sensor_noise", 2)
    return SensorModel(joint_position=sigma[0], joint_velocity=sigma[1])


def _start(simulator: Stepper, controller: Any, state: State | None) -> State:
    """The run's checked start state (default the scene's), the actuation in its modes, the controller reset."""
    state = simulator.initial_state() if state is None else state
    simulator.check_state(state)  # before anything runs
    simulator.actuation.restore(state.actuation_modes, state.scene_q[: simulator.scene.nq_hand])
    if isinstance(getattr(controller, "log", None), dict):
        controller.log.clear()  # each run records its own internals, never the last run's
    if hasattr(controller, "reset"):
        controller.reset(state)
    return state


def _control(controller: Callable[[float, State], Any], t: float, sensed: State) -> np.ndarray:
    """The controller's input at ``t`` as a new float array (the recorder keeps it)."""
    u = controller(t, sensed)
    try:
        return np.array(u, dtype=float)
    except (TypeError, ValueError) as error:
        raise InputError(f"the controller must return numbers (the inputs u), got {u!r} at t = {t:.6g} s") from error


__all__ = ["CHUNK", "LoopOffer", "Stepper", "run"]
