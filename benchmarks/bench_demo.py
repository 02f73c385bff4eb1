"""The grasp demo as a user waits for it (``bhgrasp demo``'s run), against real time and MuJoCo's step in the same run.

The demo (``bhgrasp.scenarios.grasp_demo.run_grasp_demo``, its defaults: the Barrett hand grasps, lifts and turns a
0.6 kg box under the SMC-adaptive law and the internal-force QP, 3 s at 1 kHz) runs ``--repeat`` times, interleaved
with ``mj_step`` of the reference hold (``bench_sim.mujoco_hold``, the same hand and a box, dt 1 ms) as the baseline.

Per run: the simulation's wall time (``GraspDemoResult.wall_time``: ``Simulator.run``, the recorder included), the
whole call (the grasp choice, the scene, the supervisor, the summary), the real-time factor and the wall per physics
step over ``mj_step``'s.  Then one run with timers around its parts (the controller and ``Simulator.step`` of the
steps the Python loop takes, the recorder, the compiled loop's calls with the steps they take; the timers' own cost
included), and the share of grasp cycles whose QP the last active set answered (``qp_iterations`` 0).  Targets:
RTF >= 20 on this machine, the wall per step <= 1x ``mj_step``.

Usage: ``python benchmarks/bench_demo.py [--repeat 5] [--duration 3.0]``.
"""

from __future__ import annotations

import argparse
import os
import platform
import time

import numpy as np
from bench_sim import mujoco_step_only

import bhgrasp.sim.run_loop as run_loop
from bhgrasp.scenarios.grasp_demo import run_grasp_demo
from bhgrasp.sim.recorder import Recorder
from bhgrasp.sim.simulator import Simulator


def demo(duration: float) -> dict:
    """One demo run: its simulation's and whole call's wall [s], steps, and its QP iteration log."""
    start = time.perf_counter()
    result = run_grasp_demo(duration=duration)
    whole = time.perf_counter() - start
    log = result.trajectory.log
    grasping = np.asarray(log["contacts"]) >= 2
    return {
        "wall": result.wall_time,
        "whole": whole,
        "steps": len(result.trajectory.t) - 1,
        "iterations": np.asarray(log["qp_iterations"])[grasping],
        "position_error": result.position_error,
    }


def parts(duration: float) -> tuple[dict[str, float], int]:
    """One demo run with timers around its parts: seconds in each, and the steps the compiled loop took."""
    spent = {"controller": 0.0, "Simulator.step": 0.0, "recorder": 0.0, "compiled loop": 0.0}
    patched = [(run_loop, "_control", "controller"), (Simulator, "step", "Simulator.step")]
    patched += [(Recorder, "add", "recorder"), (Recorder, "add_run", "recorder"), (Recorder, "trajectory", "recorder")]
    patched += [(Simulator, "run_compiled", "compiled loop")]
    originals = [(owner, name, getattr(owner, name)) for owner, name, _ in patched]
    in_cpp: list[int] = []

    def timer(function, key):
        def timed(*args, **kwargs):
            start = time.perf_counter()
            try:
                result = function(*args, **kwargs)
            finally:
                spent[key] += time.perf_counter() - start
            if key == "compiled loop" and result is not None:
                in_cpp.append(int(result[0].steps))
            return result

        return timed

    for owner, name, key in patched:
        setattr(owner, name, timer(getattr(owner, name), key))
    try:
        result = run_grasp_demo(duration=duration)
    finally:
        for owner, name, function in originals:
            setattr(owner, name, function)
    spent["total (timed run)"] = result.wall_time
    return spent, sum(in_cpp)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--repeat", type=int, default=5, help="demo runs (best taken), each with an mj_step baseline")
    parser.add_argument("--duration", type=float, default=3.0, help="simulated time of each run [s]")
    args = parser.parse_args()
    machine = platform.processor() or platform.machine()
    print(f"machine: {machine}, {os.cpu_count()} CPUs, Python {platform.python_version()}")
    demo(min(args.duration, 1.0))  # imports, the compiled kernels' first calls
    runs, mujoco = [], []
    for _ in range(args.repeat):
        runs.append(demo(args.duration))
        mujoco.append(mujoco_step_only(runs[-1]["steps"], 1e-3)["step"] / runs[-1]["steps"])
    best = min(runs, key=lambda run: run["wall"])
    steps, mj_step = best["steps"], min(mujoco)
    per_step = best["wall"] / steps
    print(f"grasp demo, {args.duration:g} s at 1 kHz ({steps} steps), best of {args.repeat}:")
    walls = ", ".join(f"{run['wall']:.3f}" for run in runs)
    print(f"  simulation wall   {best['wall']:.3f} s   (runs: {walls})")
    print(f"  whole call        {best['whole']:.3f} s   (the grasp choice, scene, supervisor and summary included)")
    print(f"  real-time factor  {args.duration / best['wall']:.1f}   (target >= 20)")
    print(f"  wall per step     {per_step * 1e6:.1f} us / mj_step {mj_step * 1e6:.1f} us = {per_step / mj_step:.2f}")
    iterations = best["iterations"]
    print(
        f"  grasp cycles      {len(iterations)}, the QP answered by the last active set in "
        f"{np.sum(iterations == 0)} (proxsuite iterations: {int(np.sum(iterations))} in all)"
    )
    print(f"  position error    {best['position_error'] * 1e6:.2f} um (the same in every run)")
    spent, in_cpp = parts(args.duration)
    print(f"one run with timers (us per physics step; {in_cpp} of its {steps} steps in the compiled loop):")
    for key, seconds in spent.items():
        print(f"  {key:20s} {seconds / steps * 1e6:7.1f}")


if __name__ == "__main__":
    main()
