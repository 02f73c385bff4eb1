"""The fitness chapter 4's CMA-ES tuning minimises: F3 under FIM with the Tustin filter, scored by (4.49).

:func:`impedance_fitness` (mean |f_d - f| from first contact [N]) and the held-out evaluation ``evaluate_press`` are
top-level functions of this module, so that worker processes can import and run them.  Every run at one
(K_s, f_d, duration) shares its approach up to first contact, whatever M_I and K_I: ``_approach`` simulates it once
per process and ``_discrete_fim`` continues from it, to the bit the run from the start.
"""

from __future__ import annotations

import functools
from typing import Any

import numpy as np

from bhgrasp.controllers.impedance import ForceImpedance
from bhgrasp.controllers.impedance_controller import ImpedanceController
from bhgrasp.errors import SimulationDiverged
from bhgrasp.grasp.sensing import ContactSensing
from bhgrasp.motion.trajectories import Constant
from bhgrasp.scenarios.finger_press import DT, F3_GAINS, ForceMetrics, Setup, f3_setup, force_metrics, normal_force, run

TUNING_SPRING = 500.0  # K_s [N/m]: the thesis' k_e = 500 N/m
TUNING_FORCE = 6.0  # f_d [N] of the fitness; 4 and 8 N are held out
TUNING_DURATION = 1.0  # [s] simulated per evaluation: first contact at ~0.36 s, then ~0.64 s of force response
# the CMA-ES search over (log10 M_I, log10 K_I) (thesis chapter 4.7; `bhgrasp tune` and chapter 4's tuning)
TUNING_BOUNDS = ((1e-4, 0.1), (1.0, TUNING_SPRING))  # (lower, upper) of (M_I [kg], K_I [N/m]): chapter 4's notes
TUNING_SIGMA = 0.5  # [decades] initial step size (thesis sigma = 0.5)
TUNING_TOL_FUN = 1e-4  # [N] cma tolfun: 0.1 mN of mean force error
TUNING_TOL_X = 1e-3  # [decades] cma tolx: 0.23 % of M_I and K_I


def impedance_fitness(
    log_params: np.ndarray,
    force: float = TUNING_FORCE,
    spring: float = TUNING_SPRING,
    duration: float = TUNING_DURATION,
) -> float:
    """Fitness (4.49) of FIM with the Tustin filter on F3: mean |f_d - f_k| from first contact on [N].

    ``log_params`` = (log10 M_I, log10 K_I); B_I is critical for K_I + k_e.  A run that diverges or never touches
    scores 10 f_d.  Top-level and picklable, so generations can be evaluated in worker processes.
    """
    mass, stiffness = 10.0 ** np.asarray(log_params, dtype=float)
    try:
        _, measured = _discrete_fim(mass, stiffness, force, spring, duration)
    except SimulationDiverged:
        return 10.0 * force
    touching = np.flatnonzero(measured > 0)
    if len(touching) == 0:
        return 10.0 * force
    return float(np.mean(np.abs(force - measured[touching[0] :])))  # (4.49) over the samples since contact


def _discrete_fim(
    mass: float, stiffness: float, force: float, spring: float, duration: float
) -> tuple[np.ndarray, np.ndarray]:
    """F3 pressing the object under FIM with the Tustin filter: times [s] and normal force [N] of the run.

    The run continues the shared approach (:func:`_approach`) from its last sample before the controller first senses
    contact: it is the run from the start, to the bit (tests/test_impedance.py), with the approach simulated once.
    """
    setup = cached_f3_setup(spring)
    controller = _discrete_fim_controller(setup, mass, stiffness, force)
    approach = _approach(spring, force, duration)
    if approach is None:
        traj = run(setup, controller, duration)
        return traj.t, normal_force(setup, traj)
    start, t_before, force_before = approach
    controller.inner.q_rest = setup.q0  # the joints outside F3 held where a run from the start holds them
    controller.reset(start)
    # Simulator.run's loop without its recorder: only the forces are read, per sample as normal_force reads them
    sim, state = setup.simulator, start
    sim.actuation.restore(state.actuation_modes, state.scene_q[: sim.scene.nq_hand])
    steps = round((duration - start.t) / sim.dt)
    times, forces = np.empty(steps), np.empty(steps)
    for k in range(steps):
        state, _ = sim.step(state, controller(state.t, state))
        times[k], forces[k] = state.t, float(np.sum(state.contact_forces @ setup.normal))
    return np.concatenate((t_before, times)), np.concatenate((force_before, forces))


def _discrete_fim_controller(setup: Setup, mass: float, stiffness: float, force: float) -> ImpedanceController:
    law = ForceImpedance(
        Constant(setup.tip0),
        setup.normal,
        force,
        setup.surface_point(),
        setup.k_e,
        mass=mass,
        stiffness=stiffness,
        period=DT,
    )
    return ImpedanceController(setup.hand, {"F3": law}, *F3_GAINS, log_reaction_torque=False)  # forces only


@functools.lru_cache(maxsize=8)
def _approach(spring: float, force: float, duration: float) -> tuple[Any, np.ndarray, np.ndarray] | None:
    """The part that every :func:`_discrete_fim` run at (spring, force, duration) shares, whatever M_I and K_I.

    Until the controller senses contact no force error reaches the impedance filter, whose output stays zero (it
    starts at rest), so the commanded trajectory, and with it every torque and state, does not depend on the filter's
    M_I, B_I, K_I.  Returns the state S at the last sample before the controller first senses contact, with the
    times [s] and normal forces [N] of the samples up to S (inclusive); ``None`` if the run never touches, touches at
    once or records contacts (without force) before.  A run continued from S (the controller reset there: filter at
    rest, first step dt = 0, as the filter saw only zeros; the other joints held at q0) is the run from the start.
    """
    setup = cached_f3_setup(spring)
    sim = setup.simulator
    controller = _discrete_fim_controller(setup, 0.01, 100.0, force)  # any M_I, K_I: the filter only sees zeros
    sensing = ContactSensing(setup.hand)
    state = sim.initial_state(setup.q0)
    controller.reset(state)
    last = None
    for _ in range(round(duration / sim.dt)):  # sim.run's loop, stopped where the runs part
        if sensing.fingers(state)[setup.finger].touching:
            break
        last = state
        state, _ = sim.step(state, controller(state.t, state))
    else:
        return None
    if last is None or last.t <= 0.0:
        return None
    before = run(setup, _discrete_fim_controller(setup, 0.01, 100.0, force), last.t)  # samples up to `last`
    if before.contact_offsets[-1]:  # contacts before: later samples' rows would sit elsewhere than in a full run's
        return None
    return last, before.t, normal_force(setup, before)


@functools.lru_cache(maxsize=4)
def cached_f3_setup(spring: float) -> Setup:
    """:func:`~bhgrasp.scenarios.finger_press.f3_setup` of ``spring`` [N/m], built once per process (a few kept)."""
    return f3_setup(spring)


def evaluate_press(
    params: tuple[float, float], desired: float, spring: float = TUNING_SPRING, duration: float = TUNING_DURATION
) -> tuple[ForceMetrics, float]:
    """Impedance ``params`` pressing ``desired`` [N] (held out): force metrics, mean |f_d - f| from contact [N]."""
    t, force = _discrete_fim(params[0], params[1], desired, spring, duration)
    start = int(np.argmax(force > 0))
    return force_metrics(t, force, desired), float(np.mean(np.abs(desired - force[start:])))


__all__ = [
    "TUNING_BOUNDS",
    "TUNING_DURATION",
    "TUNING_FORCE",
    "TUNING_SIGMA",
    "TUNING_SPRING",
    "TUNING_TOL_FUN",
    "TUNING_TOL_X",
    "cached_f3_setup",
    "evaluate_press",
    "impedance_fitness",
]
