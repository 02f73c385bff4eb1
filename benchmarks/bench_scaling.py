"""How the simulator's cost per step grows with contacts, objects and hand DOF, measured in one run.

- contacts: a 1 kg plate resting on n vertex-up cubes (one contact point each; n = 3..20, the fewest that hold a
  plate up), the hand parked 5 m away;
- objects: k boxes resting side by side on a table (about 4 contact points each), k = 1..5;
- DOF: the Barrett (8 joints) and Allegro (16 joints) box-grasp scenes holding the box under the demo's controller
  (same contact law and step);
- the step of each scene with no contact at all (objects lifted clear) as the baseline.

Prints the best of ``--repeat`` medians of the microseconds per physics step over ``--steps`` steps, after 100
settling steps (controller time excluded), the mean number of contact points per step, and a least-squares line
cost = a + b contacts (the linearity check of issue 8).

Usage: ``python benchmarks/bench_scaling.py [--steps 300] [--repeat 3]``.
"""

from __future__ import annotations

import argparse
import platform
import time

import numpy as np
import pinocchio as pin

import bhgrasp as bh
from bhgrasp.controllers.adaptive_grasp import SMCAdaptiveGrasp
from bhgrasp.controllers.motor_commands import MotorCommands
from bhgrasp.controllers.supervisor import GraspSupervisor
from bhgrasp.model.objects import Box, FixedBox, Plane
from bhgrasp.scenarios.allegro_grasp import allegro_box_grasp
from bhgrasp.scenarios.box_grasp import box_grasp
from bhgrasp.sim import Simulator
from bhgrasp.sim.scene import Scene

PARKED = pin.SE3(np.eye(3), np.array([5.0, 0.0, 0.3]))  # [m] the hand far from everything
CUBE = 0.02  # [m] edge of the support cubes


def vertex_up() -> np.ndarray:
    """Rotation taking the cube diagonal (1, 1, 1)/sqrt(3) to +z (a vertex on top)."""
    return pin.Quaternion.FromTwoVectors(np.ones(3) / np.sqrt(3.0), np.array([0.0, 0.0, 1.0])).toRotationMatrix()


def plate_on_cubes(n: int, lifted: float = 0.0) -> Simulator:
    """A 0.3 x 0.3 x 0.01 m, 1 kg plate on n vertex-up cubes on a 0.1 m circle (plate raised by ``lifted``)."""
    hand = bh.BarrettHand(base_placement=PARKED)
    top = 0.5 * CUBE * np.sqrt(3.0)  # [m] centre-to-vertex
    angles = 2.0 * np.pi * np.arange(n) / n
    cubes = [
        FixedBox(size=(CUBE,) * 3, pose=pin.SE3(vertex_up(), np.array([0.1 * np.cos(a), 0.1 * np.sin(a), -top])))
        for a in angles
    ]
    plate = Box(size=(0.3, 0.3, 0.01), mass=1.0, pose=pin.SE3(np.eye(3), np.array([0.0, 0.0, 0.005 + lifted])))
    return Simulator(Scene(hand, [plate], environment=cubes), dt=1e-3)


def boxes_on_table(k: int, lifted: float = 0.0) -> Simulator:
    """A table with ``k`` boxes (0.04 m, 0.1 kg) 0.1 m apart."""
    hand = bh.BarrettHand(base_placement=PARKED)
    boxes = [
        Box(size=(0.04,) * 3, mass=0.1, pose=pin.SE3(np.eye(3), np.array([0.1 * i, 0.0, 0.02 + lifted])))
        for i in range(k)
    ]
    return Simulator(Scene(hand, boxes, environment=[Plane()]), dt=1e-3)


def time_steps(simulator: Simulator, state, torque, steps: int) -> tuple[float, float, object]:
    """Median microseconds per physics step (the controller's time excluded), mean contact count, last state."""
    times, counts = np.empty(steps), np.empty(steps)
    for k in range(steps):
        u = torque(state)
        start = time.perf_counter()
        state, info = simulator.step(state, u)
        times[k] = time.perf_counter() - start
        counts[k] = len(info.contacts)
    return float(np.median(times) * 1e6), float(counts.mean()), state


def settled(simulator: Simulator, torque, steps: int = 100):
    """The state after ``steps`` steps from rest (contacts established)."""
    state = simulator.initial_state(simulator.scene.hand.neutral())
    for _ in range(steps):
        state, _ = simulator.step(state, torque(state))
    return state


def grasp_controller(setup):
    """The demo's supervisor with the SMC-adaptive grasp law, as a function of the state (its own clock)."""
    law = GraspSupervisor(setup.hand, setup.q_contact, SMCAdaptiveGrasp(setup.hand, Box(size=setup.box.size, mass=0.2)),
                          q_close=setup.q_close, fingers=setup.fingers)  # fmt: skip
    if setup.cancel_damping:  # the Allegro scene: cancel the joints' known damping, as the demo does
        law = MotorCommands(law, setup.simulator.actuation.drive)
    return lambda state: law(state.t, state)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=300)
    parser.add_argument("--repeat", type=int, default=3, help="timed runs per scene (continuing), best median kept")
    args = parser.parse_args()
    print(f"{platform.processor() or platform.machine()}, Python {platform.python_version()}, pin {pin.__version__}")

    rows: list[tuple[str, float, float]] = []

    def measure(name: str, simulator: Simulator, torque, state=None) -> None:
        state = settled(simulator, torque) if state is None else state
        best, contacts = np.inf, 0.0
        for _ in range(args.repeat):  # the best of a few medians: this machine's noise comes in bursts
            cost, contacts, state = time_steps(simulator, state, torque, args.steps)
            best = min(best, cost)
        cost = best
        rows.append((name, cost, contacts))
        print(f"{name:<36}{cost:10.1f} us/step{contacts:8.1f} contacts", flush=True)

    idle = lambda sim: lambda state: sim.scene.hand.gravity_torques(state.q)  # noqa: E731
    print("contacts: plate on n vertex-up cubes")
    free = plate_on_cubes(3, lifted=20.0)
    measure("plate, no contact (baseline)", free, idle(free), free.initial_state(free.scene.hand.neutral()))
    for n in (3, 4, 6, 8, 12, 16, 20):
        simulator = plate_on_cubes(n)
        measure(f"plate on {n} cubes", simulator, idle(simulator))
    plate_rows = rows[1:]
    contacts = np.array([r[2] for r in plate_rows])
    costs = np.array([r[1] for r in plate_rows])
    slope, intercept = np.polyfit(contacts, costs, 1)
    residual = np.max(np.abs(costs - (intercept + slope * contacts)) / costs)
    print(f"  line: {intercept:.0f} us + {slope:.1f} us per contact (largest deviation {100 * residual:.1f} %)")

    print("objects: k boxes on a table")
    for k in (1, 2, 3, 4, 5):
        simulator = boxes_on_table(k)
        measure(f"{k} box(es) on the table", simulator, idle(simulator))
    free = boxes_on_table(5, lifted=20.0)
    measure("5 boxes, no contact", free, idle(free), free.initial_state(free.scene.hand.neutral()))

    print("hand DOF: box grasp scenes, the demo's supervisor + SMC-adaptive law (timed from 0.6 s, grasp closed)")
    for name, setup in (("Barrett (8 DOF)", box_grasp(mass=0.2)), ("Allegro (16 DOF)", allegro_box_grasp())):
        simulator, torque = setup.simulator, grasp_controller(setup)
        state = time_steps(simulator, setup.state, torque, 600)[2]
        measure(name, simulator, torque, state)


if __name__ == "__main__":
    main()
