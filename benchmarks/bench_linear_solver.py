"""The implicit step's linear solvers, dense and sparse, as a scene grows; the sparse step against MuJoCo's.

Scenes as ``bench_build.py``'s: n 3 cm boxes of 0.1 kg resting on a table in a grid, the Barrett hand beside them,
the compiled engine at dt 0.5 ms; each box rests on 4 contact points.  First table: the median step with
``linear_solver="dense"`` and ``"sparse"`` for small n, where the two cross (``SimulatorSettings``' ``SPARSE_FROM``,
the size from which ``"auto"`` goes sparse, was set from it).  Second table: the sparse step and ``mj_step`` for n up
to 500 boxes (12 to 2,000 contacts); the line a + b contacts fitted to the sparse step (least relative residuals), its
largest deviation, and the exponent p of cost ~ contacts^p.

Usage: ``python benchmarks/bench_linear_solver.py [--small 1 2 4 ...] [--large 3 25 ...] [--steps 20]``.
"""

from __future__ import annotations

import argparse
import os
import platform

import numpy as np
import pinocchio as pin
from bench_build import EDGE, MASS, grid, mujoco_side  # this folder's (a script's own folder is on its path)
from bench_clutter import median_step

import bhgrasp as bh
from bhgrasp.model.objects import Box, table
from bhgrasp.sim import Simulator
from bhgrasp.sim.scene import Scene
from bhgrasp.sim.settings import SPARSE_FROM


def step_us(n: int, linear_solver: str, steps: int) -> tuple[float, int, int]:
    """Median step [us] of n boxes with a linear solver; the scene's nv and its contacts."""
    boxes = [Box(size=(EDGE,) * 3, mass=MASS, pose=pin.SE3(np.eye(3), centre)) for centre in grid(n)]
    scene = Scene(bh.BarrettHand(), boxes, [table()])
    simulator = Simulator(scene, engine="compiled", start_check="off", dt=5e-4, linear_solver=linear_solver)
    box = {"state": simulator.initial_state()}
    u = np.zeros(scene.nv_hand)

    def step() -> None:
        box["state"], box["info"] = simulator.step(box["state"], u)

    for _ in range(3):  # contacts made, work arrays sized
        step()
    return median_step(step, steps), scene.nv, len(box["info"].contacts)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--small", type=int, nargs="+", default=[1, 2, 4, 6, 8, 10, 12, 16, 24])
    parser.add_argument("--large", type=int, nargs="+", default=[3, 10, 25, 50, 100, 200, 300, 400, 500])
    parser.add_argument("--steps", type=int, default=20)
    args = parser.parse_args()
    print(f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores; compiled engine, dt 0.5 ms")
    print(f"\nDense and sparse (auto goes sparse from nv = {SPARSE_FROM}):\n")
    print("| boxes | nv | contacts | dense [us] | sparse [us] | sparse / dense |")
    print("|---:|---:|---:|---:|---:|---:|")
    for n in args.small:
        dense, nv, contacts = step_us(n, "dense", args.steps)
        sparse, _, _ = step_us(n, "sparse", args.steps)
        print(f"| {n} | {nv} | {contacts} | {dense:.0f} | {sparse:.0f} | {sparse / dense:.2f} |", flush=True)
    print("\nThe sparse step against mj_step:\n")
    print("| boxes | nv | contacts | sparse step [us] | mj_step [us] (contacts) | ours / mj_step |")
    print("|---:|---:|---:|---:|---:|---:|")
    counts, costs = [], []
    for n in args.large:
        ours, nv, contacts = step_us(n, "sparse", args.steps)
        theirs = mujoco_side(n, args.steps)
        counts.append(contacts)
        costs.append(ours)
        print(
            f"| {n} | {nv} | {contacts} | {ours:.0f} | {theirs['step_us']:.0f} ({theirs['contacts']}) | "
            f"{ours / theirs['step_us']:.1f} |",
            flush=True,
        )
    if len(counts) >= 2:
        contacts, cost = np.array(counts, float), np.array(costs)
        slope, intercept = np.polyfit(contacts, cost, 1, w=1.0 / cost)  # least relative residuals
        deviation = np.max(np.abs(cost - (intercept + slope * contacts)) / cost)
        exponent = np.polyfit(np.log(contacts), np.log(cost), 1)[0]
        print(
            f"\nline (least relative residuals): {intercept:.0f} us + {slope:.2f} us per contact, largest deviation "
            f"{100 * deviation:.0f} %; cost ~ contacts^{exponent:.2f}; {(cost / contacts).min():.2f}-"
            f"{(cost / contacts).max():.2f} us per contact"
        )


if __name__ == "__main__":
    main()
