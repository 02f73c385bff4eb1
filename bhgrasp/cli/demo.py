"""``bhgrasp demo``: the main job, a grasp of a box of unknown mass, lifted and turned (headless by default)."""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from bhgrasp.cli import arguments as checked
from bhgrasp.scenarios.grasp_controllers import ADAPTATIONS, CONTROLLERS
from bhgrasp.scenarios.grasp_demo import HANDS, grasp_scene, run_grasp_demo, save_demo


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The demo's options."""
    add = parser.add_argument
    add("--output", type=checked.output_folder, default=Path("bhgrasp_demo"), help="folder for figure and trajectory")
    add(
        "--hand",
        choices=HANDS,
        default="barrett",
        help="the Barrett hand, or the Allegro hand of example-robot-data (the `hands` extra)",
    )
    add("--controller", choices=CONTROLLERS, default="smc-adaptive", help="object-space controller")
    add(
        "--adaptation",
        choices=ADAPTATIONS,
        default="thesis",
        help="smc-adaptive's object estimate: the thesis' law (5.52), or composite (+ the measured contact wrench)",
    )
    add("--mass", type=checked.positive_float, default=0.6, help="true box mass [kg]")
    add("--estimate", type=checked.positive_float, default=0.3, help="mass the controller starts from [kg]")
    add("--distribution", choices=["qp", "pinv"], default="qp", help="contact forces: friction-cone QP or G^+ (5.45)")
    add("--duration", type=checked.positive_float, default=3.0, help="simulated time [s]")
    add(
        "--html",
        type=checked.output_file,
        default=None,
        help="also write the MeshCat replay as one self-contained HTML file (in an existing folder)",
    )
    add("--viz", action="store_true", help="show the run live in MeshCat (a server on 127.0.0.1; open the printed URL)")
    add(
        "--serve",
        type=checked.nonnegative_float,
        default=None,
        help="with --viz: keep the replay served this many seconds after the run (default: end with the run)",
    )
    add("--wait", action="store_true", help="with --viz: keep the replay served until Enter or Ctrl-C")


def run(args: argparse.Namespace) -> int:
    """Run the demo, print its summary, write its figure, trajectory and (``--html``) replay."""
    print(f"simulating {args.duration:g} s: approach, squeeze, lift and turn a {args.mass:g} kg box ...")
    viewer = None
    if args.viz:
        from bhgrasp.viz import SceneViewer

        viewer = SceneViewer(grasp_scene(args.hand, args.mass).simulator.scene)
        print(f"MeshCat: {viewer.url}", flush=True)
    try:
        result = run_grasp_demo(
            args.mass,
            args.estimate,
            args.controller,
            args.duration,
            distribution=args.distribution,
            viewer=viewer,
            hand=args.hand,
            adaptation=args.adaptation,
        )
        print(result.summary())
        if viewer is not None:
            viewer.replay(result.trajectory)
            if args.wait or args.serve is not None:
                _serve(viewer.url, None if args.wait else args.serve)
            else:
                print("the live view ends with the run: --wait or --serve SECONDS keeps its replay up", flush=True)
    finally:
        if viewer is not None:
            viewer.close()
    for path in save_demo(result, result.scene.hand, args.output):
        print(f"wrote {path}")
    if args.html is not None:
        from bhgrasp.viz import save_replay

        print(f"wrote {save_replay(result.scene, result.trajectory, args.html)} (MeshCat replay; opens offline)")
    return 0


def _serve(url: str, seconds: float | None) -> None:
    """Keep the MeshCat server (and its replay) up for ``seconds``, or until Enter / Ctrl-C."""
    print(f"replay at {url}", flush=True)
    if seconds is not None:
        time.sleep(max(seconds, 0.0))
        return
    try:
        input("press Enter to quit ")
    except (EOFError, KeyboardInterrupt):
        pass
