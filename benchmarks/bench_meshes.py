"""What a mesh object costs: building it and stepping it on a table, against the primitive box, measured in one run.

- step: one object resting on a table, the hand parked 5 m away, the compiled engine: the primitive 60 x 50 x 50 mm
  box (the baseline), the same box as a mesh (its hull), a 64-sided cylinder mesh, an icosphere of 642 vertices, and
  the household bottle (one hull), banana (4 pieces), mug (19) and bowl (47);
- build: ``bh.household(name)`` (its mesh made by code, its mass properties and hulls; shipped pieces read from disk)
  and the ``Scene`` + ``Simulator`` around it.

Prints the best of ``--repeat`` medians of microseconds per step over ``--steps`` steps after 200 settling steps,
each as a ratio to the primitive box's, the contact points and collision pairs; then the build times.

Usage: ``python benchmarks/bench_meshes.py [--steps 300] [--repeat 3]``.
"""

from __future__ import annotations

import argparse
import platform
import time

import numpy as np
import pinocchio as pin
import trimesh

import bhgrasp as bh
from bhgrasp.model.objects import RigidObject
from bhgrasp.sim import Simulator
from bhgrasp.sim.scene import Scene

PARKED = pin.SE3(np.eye(3), np.array([5.0, 0.0, 0.3]))  # [m] the hand far from everything
BOX = (0.06, 0.05, 0.05)  # [m]


def objects() -> dict[str, RigidObject]:
    """The objects compared, each resting on the table top z = 0 (dropped from 0.5 mm)."""
    lift = pin.SE3(np.eye(3), np.array([0.0, 0.0, 0.0255]))
    result: dict[str, RigidObject] = {
        "box (primitive)": bh.Box(size=BOX, mass=0.3, pose=lift),
        "box as a mesh (hull)": bh.Mesh(trimesh.creation.box(extents=BOX), mass=0.3, pose=lift),
        "cylinder mesh, 64 sides": bh.Mesh(
            trimesh.creation.cylinder(radius=0.033, height=0.1, sections=64),
            mass=0.35,
            pose=pin.SE3(np.eye(3), np.array([0.0, 0.0, 0.0505])),
        ),
        "icosphere, 642 vertices": bh.Mesh(
            trimesh.creation.icosphere(subdivisions=3, radius=0.035),
            mass=0.2,
            pose=pin.SE3(np.eye(3), np.array([0.0, 0.0, 0.0355])),
        ),
    }
    for name in ("bottle", "banana", "mug", "bowl"):
        item = bh.household(name, position=(0.0, 0.0, 0.0005))
        result[f"household {name} ({len(item.pieces)} convex)"] = item
    return result


def step_cost(item: RigidObject, steps: int, repeat: int) -> tuple[float, float, int]:
    """Best median [us] per compiled step, mean contact points, collision pairs."""
    hand = bh.BarrettHand(base_placement=PARKED, gravity=(0.0, 0.0, -9.81))
    simulator = Simulator(Scene(hand, [item], [bh.table()]), dt=1e-3)
    state = simulator.initial_state()
    u = np.zeros(hand.nv)
    for _ in range(200):
        state, _ = simulator.step(state, u)
    medians, contacts = [], []
    for _ in range(repeat):
        times = []
        for _ in range(steps):
            start = time.perf_counter()
            state, info = simulator.step(state, u)
            times.append(time.perf_counter() - start)
            contacts.append(len(info.contacts))
        medians.append(float(np.median(times)))
    return 1e6 * min(medians), float(np.mean(contacts)), len(simulator.scene.pairs)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--steps", type=int, default=300)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    print(f"machine: {platform.processor() or platform.machine()}, {platform.python_version()}")
    rows = {name: step_cost(item, args.steps, args.repeat) for name, item in objects().items()}
    base = rows["box (primitive)"][0]
    print(f"{'object on a table':34} {'us/step':>9} {'/ box':>7} {'contacts':>9} {'pairs':>6}")
    for name, (cost, contacts, pairs) in rows.items():
        print(f"{name:34} {cost:9.1f} {cost / base:7.2f} {contacts:9.1f} {pairs:6d}")
    print(f"{'build (household object, Scene + Simulator)':46} {'object ms':>9} {'scene ms':>9}")
    hand = bh.BarrettHand(base_placement=PARKED)
    for name in ("bottle", "banana", "mug", "bowl"):
        start = time.perf_counter()
        item = bh.household(name)
        made = time.perf_counter()
        Simulator(Scene(hand, [item], [bh.table()]), dt=1e-3)
        built = time.perf_counter()
        print(f"{name:46} {1e3 * (made - start):9.1f} {1e3 * (built - made):9.1f}")


if __name__ == "__main__":
    main()
