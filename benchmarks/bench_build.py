"""What a scene of many objects costs to build and to step, against MuJoCo on the same boxes.

For each n: n 3 cm boxes of 0.1 kg in a square grid, 5 cm apart, resting on a table (``bh.table()``), the hand parked
beside them.  Ours: the ``Scene`` and the compiled ``Simulator`` built (wall time, resident memory each added; no
start check, ``start_check="off"``: the boxes rest on the table as placed), then the median step over ``--steps``
steps.  MuJoCo: the same boxes as free bodies on a plane, ``MjModel.from_xml_string`` + ``MjData`` (wall time) and
the median ``mj_step``.  Targets: 64 objects built in <= 1 s and <= 200 MB, 400 objects built and stepped, a step
within 2x ``mj_step``.

Usage: ``python benchmarks/bench_build.py [--sizes 64 400] [--steps 3]``.
"""

from __future__ import annotations

import argparse
import os
import platform
import time

import numpy as np
import pinocchio as pin
from bench_clutter import median_step, resident_mb  # this folder's (a script's own folder is on its path)

import bhgrasp as bh
from bhgrasp.model.objects import Box, table
from bhgrasp.sim import Simulator
from bhgrasp.sim.scene import Scene

EDGE, MASS, PITCH = 0.03, 0.1, 0.05  # [m], [kg], [m]


def grid(n: int) -> list[np.ndarray]:
    """Centres of n boxes resting on z = 0 in a square grid beside the hand."""
    side = int(np.ceil(np.sqrt(n)))
    return [np.array([0.4 + PITCH * (i % side), PITCH * (i // side) - 0.5, 0.5 * EDGE]) for i in range(n)]


def ours(n: int, steps: int) -> dict:
    boxes = [Box(size=(EDGE,) * 3, mass=MASS, pose=pin.SE3(np.eye(3), centre)) for centre in grid(n)]
    before, start = resident_mb(), time.perf_counter()
    scene = Scene(bh.BarrettHand(), boxes, [table()])
    scene_s, scene_mb = time.perf_counter() - start, resident_mb() - before
    before, start = resident_mb(), time.perf_counter()
    simulator = Simulator(scene, engine="compiled", start_check="off", dt=5e-4)
    simulator_s, simulator_mb = time.perf_counter() - start, resident_mb() - before
    box = {"state": simulator.initial_state()}
    u = np.zeros(scene.nv_hand)

    def step() -> None:
        box["state"], box["info"] = simulator.step(box["state"], u)

    step_us = median_step(step, steps)
    return {
        "nv": scene.nv,
        "pairs": len(scene.pairs),
        "scene": (scene_s, scene_mb),
        "simulator": (simulator_s, simulator_mb),
        "step_us": step_us,
        "contacts": len(box["info"].contacts),
    }


def mujoco_side(n: int, steps: int) -> dict:
    import mujoco

    bodies = "".join(
        f'<body pos="{x} {y} {z}"><freejoint/><geom type="box" size="{0.5 * EDGE} {0.5 * EDGE} {0.5 * EDGE}" '
        f'mass="{MASS}"/></body>'
        for x, y, z in grid(n)
    )
    world = f'<worldbody><geom type="plane" size="5 5 0.1"/>{bodies}</worldbody>'
    xml = f'<mujoco><option timestep="0.0005"/>{world}</mujoco>'
    start = time.perf_counter()
    model = mujoco.MjModel.from_xml_string(xml)
    data = mujoco.MjData(model)
    build_s = time.perf_counter() - start
    mujoco.mj_step(model, data)
    return {
        "build_s": build_s,
        "step_us": median_step(lambda: mujoco.mj_step(model, data), max(steps, 20)),
        "contacts": int(data.ncon),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[64, 400])
    parser.add_argument("--steps", type=int, default=3)
    args = parser.parse_args()
    print(f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores; compiled engine, dt 0.5 ms")
    print(
        "| boxes | nv | pairs | Scene [s] / [MB] | Simulator [s] / [MB] | MuJoCo build [s] | ours / MuJoCo build | "
        "step [us] (contacts) | mj_step [us] (contacts) | ours / mj_step |"
    )
    print("|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for n in args.sizes:
        r, m = ours(n, args.steps), mujoco_side(n, args.steps)
        build = r["scene"][0] + r["simulator"][0]
        print(
            f"| {n} | {r['nv']} | {r['pairs']} | {r['scene'][0]:.2f} / {r['scene'][1]:.0f} | "
            f"{r['simulator'][0]:.2f} / {r['simulator'][1]:.0f} | {m['build_s']:.3f} | {build / m['build_s']:.0f} | "
            f"{r['step_us']:.0f} ({r['contacts']}) | {m['step_us']:.0f} ({m['contacts']}) | "
            f"{r['step_us'] / m['step_us']:.1f} |",
            flush=True,
        )


if __name__ == "__main__":
    main()
