"""Instructions per simulator step and per grasp-law call, counted by valgrind's callgrind: deterministic.

Wall-clock times on a shared machine wander (up to 2x within minutes here); instruction counts do not.  Each case
runs twice under ``valgrind --tool=callgrind``, with ``short`` and ``long`` repetitions after the same set-up, and
the difference divided by ``long - short`` is the cost of one repetition (imports and set-up cancel).  The measured
program runs with ``OPENBLAS_NUM_THREADS=1`` and ``PYTHONHASHSEED=0``: callgrind counts every thread, and OpenBLAS's
idle workers spin for a while after each call, as long as the machine lets them; salted string hashes change dict
probing.  Unpinned, two identical runs differed by ~3 % of a 200-step difference; pinned, by 0.01 %.  Cases:

- ``free``: a plate falling freely next to the parked Barrett hand (no contact: the baseline);
- ``plate:N``: the plate resting on N vertex-up cubes (N contact points; :mod:`bench_scaling`'s scene);
- ``hold``: the reference hold of ``bench_sim.py`` (3 fingertip contacts);
- ``smc``: one SMC-adaptive + QP call of the grasp law on a held box (the state captured once, natively).

The simulator cases are counted for each engine of ``--engine`` (``compiled``: the C++ step of ``bhgrasp._core``;
``python``: the reference engine on the same scene; ``both``, the default); ``smc`` does not step and is counted once.
Prints millions of instructions per repetition, the ratio to ``free`` on the same engine, the ratio python / compiled
per case, and, given two or more ``plate:N`` cases, the least-squares cost per contact point of each engine.  Needs
valgrind (Debian's package).
Usage: ``python benchmarks/bench_instructions.py [--cases free plate:3 plate:20 hold smc] [--engine both]
[--short 10 --long 110]``.
"""

from __future__ import annotations

import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent


def run_case(case: str, engine: str, repetitions: int, state_file: Path) -> None:
    """The measured program: set ``case`` up on ``engine``, then repeat its unit ``repetitions`` times."""
    sys.path.insert(0, str(HERE))
    from bench_scaling import plate_on_cubes, settled

    if case == "smc":
        law, state = grasp_law(state_file)
        for _ in range(3 + repetitions):
            law(1.0, state)
        return
    if case == "hold":
        from bhgrasp.scenarios.hold import reference_hold

        hold = reference_hold()
        simulator, state = hold.simulator, hold.state

        def torque(current):
            return hold.controller(current.t, current)
    else:
        simulator = plate_on_cubes(int(case.split(":")[1])) if case.startswith("plate:") else plate_on_cubes(3, 20.0)
        hand = simulator.scene.hand

        def torque(current):
            return hand.gravity_torques(current.q)

    if engine == "python":
        simulator = python_twin(simulator)
    if case != "hold":
        state = settled(simulator, torque, 100)
    for _ in range(20 + repetitions):
        state, _ = simulator.step(state, torque(state))


def python_twin(simulator):
    """The same scene, contact law and actuation on the python (reference) engine."""
    from bhgrasp.sim import Simulator

    return Simulator(simulator.scene, dt=simulator.dt, contact=simulator.law, actuation=simulator.actuation,
                     integrator=simulator.integrator, engine="python")  # fmt: skip


def grasp_law(state_file: Path):
    """An SMC-adaptive grasp law and the held-box state saved by :func:`save_grasp_state` (npz, no pickle)."""
    import pinocchio as pin

    from bhgrasp.controllers.adaptive_grasp import SMCAdaptiveGrasp
    from bhgrasp.data import State
    from bhgrasp.model.barrett_hand import BarrettHand
    from bhgrasp.model.objects import Box
    from bhgrasp.scenarios.box_grasp import BOX_SIZE

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
    from bhgrasp.model.objects import Box
    from bhgrasp.scenarios.box_grasp import box_grasp

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


def instructions(case: str, engine: str, repetitions: int, state_file: Path) -> int:
    """Instructions callgrind collected for the whole measured program."""
    command = ["valgrind", "--tool=callgrind", "--callgrind-out-file=/dev/null", sys.executable, __file__,
               "--run", case, engine, str(repetitions), str(state_file)]  # fmt: skip
    environment = {**os.environ, "OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "PYTHONHASHSEED": "0"}
    result = subprocess.run(command, capture_output=True, text=True, check=True, env=environment)
    match = re.search(r"Collected : (\d+)", result.stderr)
    if match is None:
        raise RuntimeError(f"no instruction count from callgrind for {case!r} ({engine}):\n{result.stderr[-2000:]}")
    return int(match.group(1))


def main() -> None:
    if len(sys.argv) == 6 and sys.argv[1] == "--run":
        run_case(sys.argv[2], sys.argv[3], int(sys.argv[4]), Path(sys.argv[5]))
        return
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", nargs="+", default=["free", "plate:3", "plate:20", "hold", "smc"])
    parser.add_argument("--engine", choices=["compiled", "python", "both"], default="both")
    parser.add_argument("--short", type=int, default=10)
    parser.add_argument("--long", type=int, default=110)
    args = parser.parse_args()
    if shutil.which("valgrind") is None:
        print("valgrind not installed (apt-get install valgrind): no instruction counts")
        return
    engines = ["compiled", "python"] if args.engine == "both" else [args.engine]
    print(f"{'case':<12}{'engine':<10}{'M instructions per repetition':>31}{'x free':>8}{'python/compiled':>17}")
    with tempfile.TemporaryDirectory() as folder:
        state_file = Path(folder) / "grasp_state.npz"
        if "smc" in args.cases:
            save_grasp_state(state_file)
        costs: dict[tuple[str, str], float] = {}
        for case in args.cases:
            for engine in ["-"] if case == "smc" else engines:  # the grasp law does not step: no engine
                counts = [instructions(case, engine, n, state_file) for n in (args.short, args.long)]
                cost = costs[case, engine] = (counts[1] - counts[0]) / (args.long - args.short)
                free = costs.get(("free", engine))
                ratio = f"{cost / free:8.2f}" if free else f"{'':8}"
                compiled = costs.get((case, "compiled"))
                twin = f"{cost / compiled:17.2f}" if engine == "python" and compiled else ""
                print(f"{case:<12}{engine:<10}{cost / 1e6:31.3f}{ratio}{twin}".rstrip(), flush=True)
    for engine in engines:  # cost = a + b contacts over the plate cases (one contact point per cube)
        plates = [(int(case.split(":")[1]), cost) for (case, e), cost in costs.items() if e == engine and
                  case.startswith("plate:")]  # fmt: skip
        if len(plates) >= 2:
            contacts, cost = np.array(plates, dtype=float).T
            slope, intercept = np.polyfit(contacts, cost, 1)
            worst = np.max(np.abs(intercept + slope * contacts - cost) / cost)
            print(f"{engine}: {intercept / 1e6:.3f} M + {slope / 1e6:.4f} M instructions per contact point "
                  f"(plates {', '.join(str(int(n)) for n in contacts)}; largest deviation {worst:.1%})")  # fmt: skip


if __name__ == "__main__":
    main()
