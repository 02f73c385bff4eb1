"""Instructions per simulator step and per grasp-law call, counted by valgrind's callgrind: deterministic.

Wall-clock times on a shared machine wander (up to 2x within minutes here); instruction counts do not.  Each case
runs twice under ``valgrind --tool=callgrind``, with ``short`` and ``long`` repetitions after the same set-up, and
the difference divided by ``long - short`` is the cost of one repetition (imports and set-up cancel).  Cases:

- ``free``: a plate falling freely next to the parked Barrett hand (no contact: the baseline);
- ``plate:N``: the plate resting on N vertex-up cubes (N contact points; :mod:`bench_scaling`'s scene);
- ``hold``: the reference hold of ``bench_sim.py`` (3 fingertip contacts);
- ``smc``: one SMC-adaptive + QP call of the grasp law on a held box (the state captured once, natively).

Prints millions of instructions per repetition and the ratio to ``free``.  Needs valgrind (Debian's package).
Usage: ``python benchmarks/bench_instructions.py [--cases free plate:3 plate:20 hold smc] [--short 10 --long 110]``.
"""

from __future__ import annotations

import argparse
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent


def run_case(case: str, repetitions: int, state_file: Path) -> None:
    """The measured program: set ``case`` up, then repeat its unit ``repetitions`` times."""
    sys.path.insert(0, str(HERE))
    from bench_scaling import plate_on_cubes, settled

    if case == "smc":
        law, state = grasp_law(state_file)
        for _ in range(3 + repetitions):
            law(1.0, state)
        return
    if case == "hold":
        from bhgrasp.experiments.hold import reference_hold

        hold = reference_hold()
        simulator, state = hold.simulator, hold.state

        def torque(current):
            return hold.controller(current.t, current)
    else:
        simulator = plate_on_cubes(int(case.split(":")[1])) if case.startswith("plate:") else plate_on_cubes(3, 20.0)

        def torque(current):
            return simulator.scene.hand.gravity_torques(current.q)

        state = settled(simulator, torque, 100)
    for _ in range(20 + repetitions):
        state, _ = simulator.step(state, torque(state))


def grasp_law(state_file: Path):
    """An SMC-adaptive grasp law and the held-box state saved by :func:`save_grasp_state` (npz, no pickle)."""
    import pinocchio as pin

    from bhgrasp.controllers.adaptive_grasp import SMCAdaptiveGrasp
    from bhgrasp.experiments.box_grasp import BOX_SIZE
    from bhgrasp.hand import BarrettHand
    from bhgrasp.objects import Box
    from bhgrasp.state import State

    data = np.load(state_file)
    state = State(float(data["t"]), data["q"], data["v"], (pin.SE3(data["pose"]),), data["twists"], data["points"],
                  data["normals"], data["forces"], tuple(map(tuple, data["bodies"].tolist())), data["scene_q"],
                  data["scene_v"])  # fmt: skip
    law = SMCAdaptiveGrasp(BarrettHand(), Box(size=BOX_SIZE, mass=0.6))
    law.reset(state)
    return law, state


def save_grasp_state(path: Path) -> None:
    """Run the grasp demo's supervisor to a held box (1 s) and save the sensed state there."""
    from bhgrasp.controllers.adaptive_grasp import SMCAdaptiveGrasp
    from bhgrasp.controllers.supervisor import GraspSupervisor
    from bhgrasp.experiments.box_grasp import box_grasp
    from bhgrasp.objects import Box

    setup = box_grasp(mass=0.6)
    law = SMCAdaptiveGrasp(setup.hand, Box(size=setup.box.size, mass=0.6))
    supervisor = GraspSupervisor(setup.hand, setup.q_contact, law)
    captured = {}

    def capture(t, sensed):
        if t >= 1.0:
            captured.setdefault("state", sensed)
        return supervisor(t, sensed)

    setup.simulator.run(capture, 1.01, state=setup.state)
    s = captured["state"]
    np.savez(path, t=s.t, q=s.q, v=s.v, pose=s.object_poses[0].homogeneous, twists=s.object_twists,
             points=s.contact_points, normals=s.contact_normals, forces=s.contact_forces, scene_q=s.scene_q,
             scene_v=s.scene_v, bodies=np.array(s.contact_bodies, dtype=str))  # fmt: skip


def instructions(case: str, repetitions: int, state_file: Path) -> int:
    """Instructions callgrind collected for the whole measured program."""
    command = ["valgrind", "--tool=callgrind", "--callgrind-out-file=/dev/null", sys.executable, __file__,
               "--run", case, str(repetitions), str(state_file)]  # fmt: skip
    result = subprocess.run(command, capture_output=True, text=True, check=True)
    match = re.search(r"Collected : (\d+)", result.stderr)
    if match is None:
        raise RuntimeError(f"no instruction count from callgrind for {case!r}:\n{result.stderr[-2000:]}")
    return int(match.group(1))


def main() -> None:
    if len(sys.argv) == 5 and sys.argv[1] == "--run":
        run_case(sys.argv[2], int(sys.argv[3]), Path(sys.argv[4]))
        return
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", nargs="+", default=["free", "plate:3", "plate:20", "hold", "smc"])
    parser.add_argument("--short", type=int, default=10)
    parser.add_argument("--long", type=int, default=110)
    args = parser.parse_args()
    if shutil.which("valgrind") is None:
        print("valgrind not installed (apt-get install valgrind): no instruction counts")
        return
    with tempfile.TemporaryDirectory() as folder:
        state_file = Path(folder) / "grasp_state.npz"
        if "smc" in args.cases:
            save_grasp_state(state_file)
        costs = {}
        for case in args.cases:
            counts = [instructions(case, n, state_file) for n in (args.short, args.long)]
            costs[case] = (counts[1] - counts[0]) / (args.long - args.short)
            ratio = f"{costs[case] / costs['free']:8.2f}" if "free" in costs else ""
            print(f"{case:<12}{costs[case] / 1e6:10.3f} M instructions per repetition{ratio}", flush=True)


if __name__ == "__main__":
    main()
