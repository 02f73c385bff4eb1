"""What a pile of n mixed objects costs: building its scene, settling it, one step at rest, against MuJoCo.

For each n: ``mixed_objects(n, seed=n)`` dropped into a bin of about 0.01 m^2 per object (``drop_pile``, compiled
engine, dt 0.5 ms, the hand parked 1 m above), then at rest: the Scene + Simulator build time and the process's
resident memory it added, the simulated and wall time of the settling, and the median step over ``--steps`` steps.
MuJoCo gets the same shapes, masses and settled poses (free bodies; the bin's boxes static) at the same dt and steps
them the same way (after 200 steps each): the ratio ours / ``mj_step`` is issue 31's second target (<= 2 at 64 objects).

Usage: ``python benchmarks/bench_clutter.py [--sizes 4 8 16 32] [--steps 200]``.
"""

from __future__ import annotations

import argparse
import os
import platform
import time

import numpy as np
import pinocchio as pin

from bhgrasp.model.objects import Box, Capsule, Cylinder, Sphere
from bhgrasp.scenarios.clutter import bin_walls, drop_pile, mixed_objects
from bhgrasp.sim import Simulator
from bhgrasp.sim.scene import Scene


def resident_mb() -> float:
    """This process's resident memory [MB] (Linux /proc)."""
    with open("/proc/self/statm") as statm:
        return int(statm.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 2**20


def mujoco_xml(objects, walls, dt: float) -> str:
    """An MJCF of the settled objects (free bodies, their own masses) and the bin's fixed boxes."""
    bodies = []
    for item in objects:
        x, y, z = item.pose.translation
        q = pin.Quaternion(item.pose.rotation)
        if isinstance(item, Box):
            geom = f'type="box" size="{" ".join(str(0.5 * s) for s in item.size)}"'
        elif isinstance(item, Cylinder):
            geom = f'type="cylinder" size="{item.radius} {0.5 * item.length}"'
        elif isinstance(item, Capsule):
            geom = f'type="capsule" size="{item.radius} {0.5 * item.length}"'
        elif isinstance(item, Sphere):
            geom = f'type="sphere" size="{item.radius}"'
        else:
            raise TypeError(type(item).__name__)
        bodies.append(
            f'<body pos="{x} {y} {z}" quat="{q.w} {q.x} {q.y} {q.z}"><freejoint/>'
            f'<geom {geom} mass="{item.mass}" friction="0.8"/></body>'
        )
    fixed = [
        f'<geom type="box" size="{" ".join(str(0.5 * s) for s in w.size)}" '
        f'pos="{" ".join(str(c) for c in w.pose.translation)}" friction="0.8"/>'
        for w in walls
    ]
    return f'<mujoco><option timestep="{dt}"/><worldbody>{"".join(fixed)}{"".join(bodies)}</worldbody></mujoco>'


def median_step(step, steps: int) -> float:
    """Median wall time [us] of ``step()`` over ``steps`` calls."""
    times = np.empty(steps)
    for k in range(steps):
        start = time.perf_counter()
        step()
        times[k] = time.perf_counter() - start
    return float(np.median(times) * 1e6)


def measure(n: int, steps: int) -> dict:
    """One pile of ``n`` objects: build, settle, step, and MuJoCo's step on the same pile."""
    import mujoco

    side = 0.1 * np.sqrt(n) + 0.1
    walls = bin_walls(inner=(side, side), height=0.15)
    region = (-0.5 * side, -0.5 * side, 0.5 * side, 0.5 * side)
    start = time.perf_counter()
    pile = drop_pile(mixed_objects(n, seed=n), walls, region, seed=n, max_time=10.0)
    settle_wall = time.perf_counter() - start
    before = resident_mb()
    start = time.perf_counter()
    scene = Scene(pile.simulator.scene.hand, pile.objects, environment=walls, environment_touches_hand=False)
    simulator = Simulator(scene, dt=pile.simulator.dt, contact=pile.simulator.law)
    build = time.perf_counter() - start
    memory = resident_mb() - before
    box = {"state": simulator.initial_state()}
    u = np.zeros(scene.nv_hand)

    def ours() -> None:
        box["state"], box["info"] = simulator.step(box["state"], u)

    for _ in range(200):  # the rebuilt scene's contacts take their load again
        ours()
    ours_us = median_step(ours, steps)
    model = mujoco.MjModel.from_xml_string(mujoco_xml(pile.objects, walls, pile.simulator.dt))
    data = mujoco.MjData(model)
    for _ in range(200):  # let MuJoCo's own contacts settle the pile first
        mujoco.mj_step(model, data)
    theirs_us = median_step(lambda: mujoco.mj_step(model, data), steps)
    return {
        "n": n,
        "build_s": build,
        "build_mb": memory,
        "settle_sim_s": pile.settle_time,
        "settle_wall_s": settle_wall,
        "contacts": len(box["info"].contacts),
        "ours_us": ours_us,
        "mujoco_us": theirs_us,
        "mujoco_contacts": int(data.ncon),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[4, 8, 16, 32])
    parser.add_argument("--steps", type=int, default=200)
    args = parser.parse_args()
    print(f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores; compiled engine, dt 0.5 ms")
    print(
        "| objects | build [s] | build [MB] | settled after [s] (wall [s]) | contacts | us / step | mj_step [us] "
        "(contacts) | ours / mj_step |"
    )
    print("|---:|---:|---:|---:|---:|---:|---:|---:|")
    for n in args.sizes:
        r = measure(n, args.steps)
        print(
            f"| {n} | {r['build_s']:.2f} | {r['build_mb']:.0f} | {r['settle_sim_s']:.2f} ({r['settle_wall_s']:.1f}) | "
            f"{r['contacts']} | {r['ours_us']:.0f} | {r['mujoco_us']:.0f} ({r['mujoco_contacts']}) | "
            f"{r['ours_us'] / r['mujoco_us']:.1f} |",
            flush=True,
        )


if __name__ == "__main__":
    main()
