"""Batched rollouts: environment-steps per second against the serial compiled engine, measured in the same run.

The reference hold (``bhgrasp.scenarios.hold``) stepped as N environments of a ``BatchSimulator`` with its law
written for the batch (compiled gravity and fingertip-Jacobian kernels, NumPy for the rest), at 1 and 2 threads,
against one environment stepped by ``Simulator.step`` with the scalar law, measured in the same run.  The
target: >= 100 000 environment-steps per second on 2 cores.  Then Barrett hands (four motor torques each) closing
on a box, whose TorqueSwitches break away in the batch's C++, against one hand stepped by ``Simulator.step``.  Last,
the settled hold with its inputs held, N environments on 2 threads, as open-loop rollouts in one call
(``BatchSimulator.rollout``) and as one ``BatchSimulator.step`` call per step, against MuJoCo's ``rollout`` of the same
scene (``bench_sim.mujoco_hold``) on 2 threads with its persistent pool, in the same run.  The target: >= 3x
MuJoCo's environment-steps per second at 64 environments.

Usage: ``python benchmarks/bench_batch.py [--steps 200] [--sizes 16 64 256] [--repeat 5]``.
"""

from __future__ import annotations

import argparse
import os
import platform
import time

import numpy as np
import pinocchio as pin

from bhgrasp.scenarios.hold import POSTURE_GAIN, SQUEEZE, reference_hold
from bhgrasp.sim.batch import BatchSimulator


def serial_rate(steps: int) -> float:
    """Environment-steps per second of one environment: Simulator.step with the scalar hold law."""
    hold = reference_hold()
    state = hold.state
    start = time.perf_counter()
    for _ in range(steps):
        state, _ = hold.simulator.step(state, hold.controller(state.t, state))
    return steps / (time.perf_counter() - start)


def batch_rate(size: int, threads: int, steps: int) -> tuple[float, float]:
    """Environment-steps per second of a batch: closed loop (the vectorised law) and step only (inputs held)."""
    hold = reference_hold()
    q0, fingers, forces = hold.state.q, list(SQUEEZE), np.array(list(SQUEEZE.values()))

    def controller(t: float, batch: BatchSimulator) -> np.ndarray:
        tips = np.einsum("nkij,ki->nj", batch.fingertip_jacobians(fingers), forces)
        return batch.gravity_torques() + POSTURE_GAIN * (q0 - batch.q) + tips

    batch = BatchSimulator(hold.simulator, [hold.state] * size, threads=threads)
    batch.run(controller, 20 * hold.simulator.dt)  # warm up
    start = time.perf_counter()
    for _ in range(steps):
        batch.step(controller(batch.t, batch))
    loop = size * steps / (time.perf_counter() - start)
    u = controller(batch.t, batch)
    start = time.perf_counter()
    for _ in range(steps):
        batch.step(u)
    assert not batch.diverged.any()
    return loop, size * steps / (time.perf_counter() - start)


def barrett_rate(size: int, threads: int, steps: int) -> tuple[float, float]:
    """Environment-steps per second of Barrett hands closing on the chapter-5 box, batch and serial.

    Four motor torques per hand, the TorqueSwitches breaking away in the batch's C++; the serial rate is one hand
    stepped by ``Simulator.step`` (its Python actuation model).
    """
    from bhgrasp.scenarios.box_grasp import box_grasp
    from bhgrasp.sim import Simulator
    from bhgrasp.sim.actuation import BarrettActuation

    setup = box_grasp(mass=0.3, actuation="barrett")
    simulator = Simulator(setup.simulator.scene, dt=setup.simulator.dt, contact=setup.simulator.law,
                          actuation=BarrettActuation(setup.hand))  # fmt: skip
    start_state = simulator.initial_state(setup.q_start)
    u = np.array([0.02, 0.11, 0.11, 0.11]) * np.linspace(0.8, 1.2, size)[:, None]
    batch = BatchSimulator(simulator, [start_state] * size, threads=threads)
    start = time.perf_counter()
    for _ in range(steps):
        batch.step(u)
    rate = size * steps / (time.perf_counter() - start)
    state, start = start_state, time.perf_counter()
    for _ in range(steps):
        state, _ = simulator.step(state, u[0])
    return rate, steps / (time.perf_counter() - start)


def against_mujoco(size: int, steps: int, repeat: int, threads: int = 2) -> dict[str, float] | None:
    """Environment-steps per second of the settled hold, inputs held: bhgrasp's rollout and step loop, MuJoCo's rollout.

    Both start every repetition from their settled hold (:data:`bench_sim.SETTLE` closed-loop steps of their own
    law) and run ``steps`` steps with the law's last output held; the best of ``repeat`` interleaved repetitions.
    None when MuJoCo is not installed.
    """
    try:
        import mujoco
        from mujoco import rollout
    except ImportError:
        return None
    from bench_sim import SETTLE, mujoco_hold

    hold = reference_hold()
    model, data, _, controller = mujoco_hold(hold.simulator.dt)
    for _ in range(SETTLE):
        data.qfrc_applied[:8] = controller()
        mujoco.mj_step(model, data)
    data.qfrc_applied[:8] = controller()
    physics, applied = mujoco.mjtState.mjSTATE_FULLPHYSICS, mujoco.mjtState.mjSTATE_QFRC_APPLIED
    start, held = np.zeros(mujoco.mj_stateSize(model, physics)), np.zeros(mujoco.mj_stateSize(model, applied))
    mujoco.mj_getState(model, data, start, physics)
    mujoco.mj_getState(model, data, held, applied)
    datas = [mujoco.MjData(model) for _ in range(threads)]
    starts, controls = np.tile(start, (size, 1)), np.tile(held, (size, steps, 1))
    record = np.zeros((size, steps, start.size))

    q0, fingers, forces = hold.state.q, list(SQUEEZE), np.array(list(SQUEEZE.values()))

    def law(t: float, batch: BatchSimulator) -> np.ndarray:
        tips = np.einsum("nkij,ki->nj", batch.fingertip_jacobians(fingers), forces)
        return batch.gravity_torques() + POSTURE_GAIN * (q0 - batch.q) + tips

    settled = BatchSimulator(hold.simulator, [hold.state] * size, threads=threads).run(law, SETTLE * hold.simulator.dt)
    u, states = law(settled.t, settled), [settled.state(i) for i in range(size)]
    best = {"bhgrasp rollout": np.inf, "bhgrasp step loop": np.inf, "MuJoCo rollout": np.inf}
    for _ in range(repeat):
        start_time = time.perf_counter()
        options = {"control_spec": applied, "state": record, "persistent_pool": True}
        rollout.rollout([model] * size, datas, starts, controls, **options)
        best["MuJoCo rollout"] = min(best["MuJoCo rollout"], time.perf_counter() - start_time)
        batch = BatchSimulator(hold.simulator, states, threads=threads)
        start_time = time.perf_counter()
        batch.rollout(u, steps=steps)
        best["bhgrasp rollout"] = min(best["bhgrasp rollout"], time.perf_counter() - start_time)
        assert not batch.diverged.any()
        batch = BatchSimulator(hold.simulator, states, threads=threads)
        start_time = time.perf_counter()
        for _ in range(steps):
            batch.step(u)
        best["bhgrasp step loop"] = min(best["bhgrasp step loop"], time.perf_counter() - start_time)
    rollout.shutdown_persistent_pool()
    return {name: size * steps / wall for name, wall in best.items()}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--steps", type=int, default=200, help="steps per measurement")
    parser.add_argument("--sizes", type=int, nargs="+", default=[16, 64, 256], help="environments per batch")
    parser.add_argument("--repeat", type=int, default=5, help="repetitions against MuJoCo (the best is kept)")
    args = parser.parse_args()
    print(f"machine: {platform.machine()}, {os.cpu_count()} cores, python {platform.python_version()}, "
          f"pinocchio {pin.__version__}")  # fmt: skip
    serial = serial_rate(args.steps * 4)
    print(f"serial Simulator.step + scalar law: {serial:10.0f} env-steps/s")
    print(f"\n{'environments':>12}{'threads':>9}{'closed loop':>14}{'step only':>12}{'loop / serial':>15}")
    for size in args.sizes:
        for threads in (1, 2):
            loop, step = batch_rate(size, threads, args.steps)
            print(f"{size:12d}{threads:9d}{loop:14.0f}{step:12.0f}{loop / serial:15.2f}")
    print("\nBarrett hands closing on a box (4 motor inputs, TorqueSwitch in C++), inputs held:")
    print(f"{'environments':>12}{'threads':>9}{'batch':>14}{'serial':>12}{'batch / serial':>16}")
    for size in args.sizes:
        for threads in (1, 2):
            rate, one = barrett_rate(size, threads, args.steps)
            print(f"{size:12d}{threads:9d}{rate:14.0f}{one:12.0f}{rate / one:16.2f}")
    print("\nThe settled hold, inputs held, 2 threads, against MuJoCo's rollout (env-steps/s, best of --repeat):")
    print(f"{'environments':>12}{'MuJoCo':>10}{'bhgrasp rollout':>17}{'/ MuJoCo':>10}{'step loop':>11}{'/ MuJoCo':>10}")
    for size in args.sizes:
        rates = against_mujoco(size, args.steps, args.repeat)
        if rates is None:
            print("MuJoCo is not installed (pip install mujoco): no comparison")
            break
        mujoco, whole, loop = rates["MuJoCo rollout"], rates["bhgrasp rollout"], rates["bhgrasp step loop"]
        print(f"{size:12d}{mujoco:10.0f}{whole:17.0f}{whole / mujoco:10.2f}{loop:11.0f}{loop / mujoco:10.2f}")


if __name__ == "__main__":
    main()
