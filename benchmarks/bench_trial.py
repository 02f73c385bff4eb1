"""One grasp-benchmark trial as a user waits for it, against real time and against its Python twins in the same run.

The trial (``bhgrasp.bench``: the wrist-mounted BH8-280 under its Barrett drive, 18 s of the protocol at dt 0.25 ms,
72,000 steps) runs three ways in one process:

- **compiled**: as ``bhgrasp grasp-bench`` runs it: the compiled step with the Barrett drive in the same call
  (``src/barrett.cpp``) and the compiled wrist servo (``src/wrist_servo.cpp``);
- **Python drive and servo**: the same trial with the drive's rules and the servo in their Python twins (a
  ``BarrettActuation`` subclass, ``MountServo(engine="python")``): what a step cost before both were compiled;
- the placement search (the height and closing rules, ``bench.height``), paid once per object and grasp in a
  process, timed on the first setup.

Per run: wall time, the wall per step, the real-time factor (simulated / wall), the compiled step's share (the
``CompiledEngine`` call) and the ratio to the Python twins' run.  Both runs give the same trajectory (checked: the
object's last position to the bit on a trial alone).  Target (issue 33): a trial in <= 4 s, >= 5x real time.

Usage: ``python benchmarks/bench_trial.py [--object box:0.06x0.05x0.05:0.3] [--grasp power] [--duration S]``.
"""

from __future__ import annotations

import argparse
import os
import platform
import time

import numpy as np

from bhgrasp.bench.objects import BenchObject
from bhgrasp.bench.protocol import HELD_AT, RELEASE, SHAKE_TIME, Trial
from bhgrasp.bench.trial import BenchController, run_protocol, setup
from bhgrasp.controllers.mount import MountServo
from bhgrasp.sim import Simulator
from bhgrasp.sim.actuation import BarrettActuation
from bhgrasp.sim.compiled import CompiledEngine


class PythonRules(BarrettActuation):
    """The Barrett drive stepped by its Python hooks (a subclass is not run in C++)."""


def run(trial: Trial, duration: float, compiled: bool) -> dict:
    """One run of the trial: wall time [s], steps, the engine call's time [s] and the object's last position."""
    simulator, state, hand, path = setup(trial)
    controller = BenchController(trial, hand, path)
    if not compiled:
        rules = PythonRules(hand, saturate=True)
        simulator = Simulator.from_settings(simulator.scene, simulator.settings, simulator.law, rules)
        state = simulator.initial_state(state.q)
        controller.servo = MountServo(hand, controller.path, fingers="zero", compensate_load=False, engine="python")
    engine_time = [0.0]
    call = CompiledEngine.step_barrett if compiled else CompiledEngine.step

    def timed(*args, **kwargs):
        start = time.perf_counter()
        result = call(*args, **kwargs)
        engine_time[0] += time.perf_counter() - start
        return result

    name = "step_barrett" if compiled else "step"
    setattr(CompiledEngine, name, timed)
    try:
        start = time.perf_counter()
        trajectory = run_protocol(simulator, state, controller, record_every=40, duration=duration)
        wall = time.perf_counter() - start
    finally:
        setattr(CompiledEngine, name, call)
    steps = round(float(trajectory.t[-1]) / simulator.dt)
    return {
        "wall": wall,
        "steps": steps,
        "simulated": float(trajectory.t[-1]),
        "engine": engine_time[0],
        "object": trajectory.object_position[-1, 0],
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--object", default="box:0.06x0.05x0.05:0.3")
    parser.add_argument("--grasp", default="power")
    parser.add_argument("--duration", type=float, default=HELD_AT + 6 * SHAKE_TIME + 1.0 + RELEASE)
    args = parser.parse_args()
    trial = Trial(BenchObject.parse(args.object), args.grasp)
    print(f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores; {args.object} {args.grasp}")
    start = time.perf_counter()
    setup(trial)
    search = time.perf_counter() - start
    print(f"first setup (the placement search, once per object and grasp in a process): {search:.2f} s")
    runs = {"compiled": run(trial, args.duration, True), "Python drive and servo": run(trial, args.duration, False)}
    print("| run | simulated [s] | wall [s] | us / step | engine call us / step | real-time factor | / Python twins |")
    print("|---|---:|---:|---:|---:|---:|---:|")
    twins = runs["Python drive and servo"]["wall"]
    for label, r in runs.items():
        print(
            f"| {label} | {r['simulated']:.2f} | {r['wall']:.2f} | {1e6 * r['wall'] / r['steps']:.1f} | "
            f"{1e6 * r['engine'] / r['steps']:.1f} | {r['simulated'] / r['wall']:.1f} | {r['wall'] / twins:.2f} |"
        )
    same = np.array_equal(runs["compiled"]["object"], runs["Python drive and servo"]["object"])
    print(f"the object's last position the same to the bit: {same}")


if __name__ == "__main__":
    main()
