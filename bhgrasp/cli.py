"""Command line: ``bhgrasp demo`` (the main job: a grasp, headless), ``tour``, ``experiments`` and ``info``."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from bhgrasp.errors import BhgraspError
from bhgrasp.experiments.grasp_demo import CONTROLLERS


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``bhgrasp`` command."""
    parser = argparse.ArgumentParser(prog="bhgrasp", description="Barrett hand modelling, simulation and control.")
    commands = parser.add_subparsers(dest="command", required=True)
    demo = commands.add_parser(
        "demo",
        help="the main job: grasp a box of unknown mass, lift it 10 mm and turn it 0.1 rad (headless); "
        "prints the pose and force errors, slip events and time, writes a figure and the trajectory",
    )
    demo.add_argument("--output", type=Path, default=Path("bhgrasp_demo"), help="folder for figure and trajectory")
    demo.add_argument("--controller", choices=CONTROLLERS, default="smc-adaptive", help="object-space controller")
    demo.add_argument("--mass", type=float, default=0.6, help="true box mass [kg]")
    demo.add_argument("--estimate", type=float, default=0.3, help="mass the controller starts from [kg]")
    demo.add_argument(
        "--distribution", choices=["qp", "pinv"], default="qp", help="contact forces: friction-cone QP or G^+ (5.45)"
    )
    demo.add_argument("--duration", type=float, default=3.0, help="simulated time [s]")
    demo.add_argument(
        "--html", type=Path, default=None, help="also write the MeshCat replay as one self-contained HTML file"
    )
    tour = commands.add_parser(
        "tour", help="print the hand model, check IK, plot the workspace, simulate a three-finger hold"
    )
    tour.add_argument("--output", type=Path, default=Path("bhgrasp_tour"), help="folder for the figure")
    tour.add_argument("--samples", type=int, default=20_000, help="workspace samples per finger")
    tour.add_argument("--seed", type=int, default=0, help="random seed of the workspace sampling")
    tour.add_argument("--hold", type=float, default=1.0, help="simulated duration of the grasp hold [s]")
    commands.add_parser("info", help="print the hand summary only")
    experiments = commands.add_parser("experiments", help="reproduce a thesis chapter: report (markdown) and figures")
    experiments.add_argument(
        "chapter",
        choices=["ch3", "ch4", "ch5"],
        help="ch3: joint-space control (CTC, SMC, ASMC, HOSM); ch4: force control; ch5: grasping and manipulation",
    )
    experiments.add_argument("--output", type=Path, default=Path("docs/results"), help="folder for report and figures")
    experiments.add_argument(
        "--scale", type=float, default=1.0, help="multiply every case's duration (e.g. 0.5 for a quick look)"
    )
    experiments.add_argument("--no-figures", action="store_true", help="write the report only")
    args = parser.parse_args(argv)
    try:
        return _run(args)
    except BhgraspError as error:  # a user mistake or an infeasible request: one line, no traceback
        print(f"bhgrasp: error: {error}", file=sys.stderr)
        return 2


def _run(args: argparse.Namespace) -> int:
    if args.command == "experiments":
        return _experiments(args.chapter, args.output, args.scale, not args.no_figures)
    if args.command == "info":
        from bhgrasp import BarrettHand

        print(BarrettHand().summary())
        return 0
    if args.command == "demo":
        return _grasp_demo(args)
    return _tour(args.output, args.samples, args.seed, args.hold)


def _grasp_demo(args: argparse.Namespace) -> int:
    from bhgrasp import BarrettHand
    from bhgrasp.experiments.grasp_demo import run_grasp_demo, save_demo

    print(f"simulating {args.duration:g} s: approach, squeeze, lift and turn a {args.mass:g} kg box ...")
    result = run_grasp_demo(args.mass, args.estimate, args.controller, args.duration, distribution=args.distribution)
    print(result.summary())
    for path in save_demo(result, BarrettHand(), args.output):
        print(f"wrote {path}")
    if args.html is not None:
        from bhgrasp.viz import SceneViewer

        viewer = SceneViewer(result.scene)
        try:
            viewer.replay(result.trajectory)
            print(f"wrote {viewer.save_html(args.html)} (MeshCat replay; opens offline)")
        finally:
            viewer.close()
    return 0


def _tour(output: Path, samples: int, seed: int, duration: float) -> int:
    import bhgrasp as bh
    from bhgrasp.experiments.chapter2 import workspace_table

    hand = bh.BarrettHand()
    print(hand.summary())
    q = hand.configuration(F1_spread=np.pi / 3, F1_proximal=1.0, F2_proximal=1.0, F3_proximal=1.0)
    print("\nfingertip positions [m] in frame W at a tripod pose (spread 60 deg, proximal 57.3 deg):")
    for finger, position in zip(hand.fingers, hand.fingertip_positions(q)):
        print(f"  {finger}: {np.array2string(position, precision=4, floatmode='fixed', suppress_small=True)}")
    target = hand.fingertip_positions(q)[2]
    solution = bh.finger_ik(hand, "F3", target)
    print(f"closed-form IK of F3 back from that point: {np.round(solution.angles, 6)} rad")
    print("\nworkspace bounds in the thesis' axes (Table 2.2; see bhgrasp.experiments.chapter2):")
    for row in workspace_table(hand, samples, seed):
        print(row.format())
    figure_path = _plot_workspace(hand, output, samples, seed)
    print(f"\nworkspace figure: {figure_path}")
    _hold(duration)
    return 0


def _experiments(chapter: str, output: Path, scale: float, figures: bool) -> int:
    import time

    if not (np.isfinite(scale) and scale > 0.0):
        print(f"bhgrasp: error: --scale must be a positive number, got {scale}", file=sys.stderr)
        return 2
    start = time.perf_counter()
    if chapter == "ch3":
        from bhgrasp.experiments.chapter3 import run_chapter3

        cases = run_chapter3(output, scale=scale, figures=figures)
        runs = sum(len(case.runs) for case in cases)
        print(f"{chapter}: {len(cases)} cases, {runs} runs in {time.perf_counter() - start:.1f} s")
        print(f"report: {output / 'chapter3.md'}")
        return 0
    if chapter == "ch5":
        from bhgrasp.experiments.chapter5 import run_chapter5

        cases = run_chapter5(output, scale=scale, figures=figures)
        runs = sum(len(case.runs) for case in cases)
        print(f"{chapter}: {len(cases)} cases, {runs} runs in {time.perf_counter() - start:.1f} s")
        print(f"report: {output / 'chapter5.md'}")
        return 0
    from bhgrasp.experiments.chapter4 import run_chapter4

    cases = run_chapter4(output, scale=scale, figures=figures)
    print(f"{chapter}: {len(cases)} cases in {time.perf_counter() - start:.1f} s")
    print(f"report: {output / 'chapter4.md'}")
    return 0


def _hold(duration: float) -> None:
    """Simulate the reference three-finger hold and report contacts and creep."""
    from bhgrasp.experiments.hold import BOX_MASS, reference_hold

    hold = reference_hold(dt=2e-3)
    print(f"\nsimulating a {duration:g} s three-finger hold of a {BOX_MASS} kg box (implicit contacts, dt 2 ms) ...")
    trajectory = hold.simulator.run(hold.controller, duration, state=hold.state, progress=False)
    last = trajectory.contacts_at(len(trajectory) - 1)
    for (link, _), force, sticking in zip(last["bodies"], last["force"], last["sticking"]):
        state = "sticks" if sticking else "slides"
        print(f"  {link:<16} force on box {np.array2string(force, precision=3, suppress_small=True)} N, {state}")
    position = trajectory.object_position[:, 0]
    half = len(position) // 2
    creep = np.linalg.norm(position[-1] - position[half]) / (trajectory.t[-1] - trajectory.t[half])
    print(f"  box sag {1e3 * (hold.box_height - position[-1, 2]):.3f} mm, creep {creep * 1e6:.3g} um/s")


def _plot_workspace(hand, output: Path, samples: int, seed: int) -> Path:
    import matplotlib

    matplotlib.use("Agg")  # headless: write a file, open no window
    import matplotlib.pyplot as plt

    from bhgrasp.ik import workspace

    output.mkdir(parents=True, exist_ok=True)
    figure, axes = plt.subplots(1, 2, figsize=(11, 5), constrained_layout=True)
    colours = {"F1": "tab:blue", "F2": "tab:orange", "F3": "tab:green"}
    for finger in hand.fingers:
        points = workspace(hand, finger, samples, rng=seed).points
        axes[0].scatter(points[:, 0], points[:, 1], s=0.3, alpha=0.3, color=colours[finger], label=finger)
        axes[1].scatter(points[:, 1], points[:, 2], s=0.3, alpha=0.3, color=colours[finger], label=finger)
    axes[0].set(xlabel="x [m]", ylabel="y [m]", title="top view (palm plane)", aspect="equal")
    axes[1].set(xlabel="y [m]", ylabel="z [m] (palm normal)", title="side view", aspect="equal")
    for ax in axes:
        ax.legend(markerscale=20)
        ax.grid(True, alpha=0.3)
    figure.suptitle(f"Barrett BH8-280 fingertip workspace ({samples} samples per finger, seed {seed})")
    path = output / "workspace.png"
    figure.savefig(path, dpi=120)
    plt.close(figure)
    return path


if __name__ == "__main__":
    sys.exit(main())
