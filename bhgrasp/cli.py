"""Command line: ``bhgrasp demo`` (the main job: a grasp, headless), ``tour``, ``experiments`` and ``info``."""

from __future__ import annotations

import argparse
import functools
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import NoReturn

import numpy as np

from bhgrasp import _arguments as checked
from bhgrasp.errors import BhgraspError, InputError
from bhgrasp.scenarios.grasp_controllers import ADAPTATIONS, CONTROLLERS
from bhgrasp.scenarios.grasp_demo import HANDS


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``bhgrasp`` command."""
    parser = _Parser(prog="bhgrasp", description="Barrett hand modelling, simulation and control.")
    commands = parser.add_subparsers(dest="command", required=True)
    commands.add_parser = functools.partial(commands.add_parser, formatter_class=_DefaultsHelp)  # defaults in --help
    demo = commands.add_parser(
        "demo",
        help="the main job: grasp a box of unknown mass, lift it 10 mm and turn it 0.1 rad (headless); "
        "prints the pose and force errors, slip events and time, writes a figure and the trajectory",
    )
    demo.add_argument(
        "--output", type=checked.output_folder, default=Path("bhgrasp_demo"), help="folder for figure and trajectory"
    )
    demo.add_argument(
        "--hand",
        choices=HANDS,
        default="barrett",
        help="the Barrett hand, or the Allegro hand of example-robot-data (the `hands` extra)",
    )
    demo.add_argument("--controller", choices=CONTROLLERS, default="smc-adaptive", help="object-space controller")
    demo.add_argument(
        "--adaptation", choices=ADAPTATIONS, default="thesis",
        help="smc-adaptive's object estimate: the thesis' law (5.52), or composite (+ the measured contact wrench)",
    )  # fmt: skip
    demo.add_argument("--mass", type=checked.positive_float, default=0.6, help="true box mass [kg]")
    demo.add_argument(
        "--estimate", type=checked.positive_float, default=0.3, help="mass the controller starts from [kg]"
    )
    demo.add_argument(
        "--distribution", choices=["qp", "pinv"], default="qp", help="contact forces: friction-cone QP or G^+ (5.45)"
    )
    demo.add_argument("--duration", type=checked.positive_float, default=3.0, help="simulated time [s]")
    demo.add_argument(
        "--html",
        type=checked.output_file,
        default=None,
        help="also write the MeshCat replay as one self-contained HTML file (in an existing folder)",
    )
    demo.add_argument(
        "--viz", action="store_true", help="show the run live in MeshCat (a server on 127.0.0.1; open the printed URL)"
    )
    demo.add_argument(
        "--serve",
        type=checked.nonnegative_float,
        default=None,
        help="with --viz: keep the replay served this many seconds after the run (default: end with the run)",
    )
    demo.add_argument("--wait", action="store_true", help="with --viz: keep the replay served until Enter or Ctrl-C")
    tour = commands.add_parser(
        "tour", help="print the hand model, check IK, plot the workspace, simulate a three-finger hold"
    )
    tour.add_argument(
        "--output", type=checked.output_folder, default=Path("bhgrasp_tour"), help="folder for the figure"
    )
    tour.add_argument("--samples", type=checked.positive_int, default=20_000, help="workspace samples per finger")
    tour.add_argument("--seed", type=checked.seed, default=0, help="random seed of the workspace sampling")
    tour.add_argument(
        "--hold", type=checked.positive_float, default=1.0, help="simulated duration of the grasp hold [s]"
    )
    info = commands.add_parser("info", help="print a hand's joints, limits and link masses")
    info.add_argument("--urdf", type=Path, default=None, help="any hand URDF instead of the packaged Barrett hand")
    info.add_argument(
        "--mimic", choices=["coupled", "independent"], default="coupled",
        help="a URDF with <mimic> couplings: mimic joints follow their joint (default), or independent DOFs",
    )  # fmt: skip
    tune = commands.add_parser(
        "tune", help="tune F3's force-based impedance (M_I, K_I) with CMA-ES on the fitness (4.49) of thesis chapter 4"
    )
    tune.add_argument("--generations", type=checked.positive_int, default=10, help="CMA-ES generations")
    tune.add_argument("--population", type=checked.at_least_two, default=8, help="candidates per generation")
    tune.add_argument("--seed", type=checked.seed, default=0, help="CMA-ES seed")
    tune.add_argument("--force", type=checked.positive_float, default=6.0, help="desired contact force [N]")
    tune.add_argument("--serial", action="store_true", help="evaluate in this process instead of a process pool")
    sweep = commands.add_parser(
        "sweep", help="run a parameter sweep of the grasp demo from a TOML file (grid or random design, process pool)"
    )
    sweep.add_argument(
        "config", type=Path, help="TOML: [sweep] output, log, workers, seed; [grid] or [random]; [fixed]"
    )
    bench = commands.add_parser("bench", help="run benchmarks/*.py of a source checkout (ratios, see BENCHMARKS.md)")
    bench.add_argument("--quick", action="store_true", help="a few repetitions only (a smoke run)")
    bench_grasp = commands.add_parser(
        "grasp-bench",
        help="the grasp benchmark: per object and grasp, approach -> close -> lift 10 cm -> push 10 m N "
        "along +-x, +-y, +-z -> place, on the wrist-mounted BH8-280; prints the success table",
    )
    bench_grasp.add_argument(
        "--object", dest="objects", action="append", type=checked.bench_object, default=None, metavar="KIND:DIMS:MASS",
        help="box:0.06x0.05x0.05:0.3 (edges, m), cylinder:0.033x0.10:0.35 (radius x height), sphere:0.035:0.2 "
        "(radius); masses in kg; repeatable (default: both built-in sets, see --set)",
    )  # fmt: skip
    bench_grasp.add_argument(
        "--set",
        dest="sets",
        action="append",
        choices=("development", "held-out"),
        default=None,
        help="a built-in object set: development (the protocol's constants were chosen on it) or held-out (fixed "
        "before tuning); repeatable; with --object, added to those",
    )
    bench_grasp.add_argument("--grasp", dest="grasps", action="append", choices=("power", "precision"), default=None,
                             help="repeatable (default: both)")  # fmt: skip
    bench_grasp.add_argument("--actuation", dest="actuations", action="append", choices=("barrett", "full"),
                             default=None, help="repeatable (default: barrett, the real 4-motor hand)")  # fmt: skip
    bench_grasp.add_argument("--spread", dest="spreads", action="append", type=checked.spread_angle, default=None,
                             metavar="RAD", help="run every trial at this pre-shape spread [rad, 0 to pi] instead of "
                             "its grasp's own (0 for boxes and the cylinders' power grasp, 0.45 for the rest); "
                             "repeatable")  # fmt: skip
    bench_grasp.add_argument("--json", type=checked.output_file, default=None, help="write the trials here")
    bench_grasp.add_argument("--report", type=checked.output_file, default=None, help="write the markdown report")
    bench_grasp.add_argument("--compare", type=checked.existing_file, default=None,
                             help="check the trials against this committed JSON (exit 1 on a difference)")  # fmt: skip
    bench_grasp.add_argument("--workers", type=checked.positive_int, default=None, help="processes (default: cores)")
    experiments = commands.add_parser(
        "experiments",
        help="reproduce a thesis chapter: report (markdown), figures and figures of merit (chapterN.json); compare "
        "a run with the committed results; render the README's results table",
    )
    experiments.add_argument(
        "chapter",
        choices=["ch3", "ch4", "ch5", "all", "compare", "readme-table"],
        help="ch3: joint-space control (CTC, SMC, ASMC, HOSM); ch4: force control; ch5: grasping and "
        "manipulation; all: the three; compare FOLDER: check a run's chapterN.json against --reference (exit 1 "
        "with a table of every value outside tolerance, missing or extra); readme-table: print the README's "
        "'Results at a glance' table rendered from --reference (with --readme: rewrite it there)",
    )
    experiments.add_argument("folder", nargs="?", type=Path, default=None, help="compare: the new run's folder")
    experiments.add_argument(
        "--output",
        type=checked.output_folder,
        default=Path("bhgrasp_experiments"),
        help="folder for report, figures and chapterN.json (one holding a chapterN.json is refused without --force)",
    )
    experiments.add_argument(
        "--force",
        action="store_true",
        help="replace the chapterN.json, report and figures already in --output (e.g. the committed docs/results)",
    )
    experiments.add_argument(
        "--reference", type=Path, default=Path("docs/results"), help="compare, readme-table: the committed results"
    )
    experiments.add_argument(
        "--readme",
        type=Path,
        default=None,
        help="rewrite this README's results table from the chapterN.json in --output (after a run) or --reference",
    )
    experiments.add_argument(
        "--scale",
        type=checked.positive_float,
        default=1.0,
        help="multiply every case's duration (e.g. 0.5 for a quick look)",
    )
    experiments.add_argument("--no-figures", action="store_true", help="write the report only")
    args = parser.parse_args(argv)
    try:
        return _run(args)
    except BhgraspError as error:  # a user mistake or an infeasible request: one line, no traceback
        print(f"bhgrasp: error: {error}", file=sys.stderr)
        return 2


class _Parser(argparse.ArgumentParser):
    """argparse whose errors are one line, status 2.

    E.g. ``bhgrasp demo: error: argument --mass: must be a positive number, got '-1' (see bhgrasp demo --help)``.
    """

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


class _DefaultsHelp(argparse.ArgumentDefaultsHelpFormatter):
    """``--help`` lists each option's default, except for flags and options without one."""

    def _get_help_string(self, action: argparse.Action) -> str:
        if action.default is None or isinstance(action.default, bool):
            return action.help or ""
        return super()._get_help_string(action)


def _run(args: argparse.Namespace) -> int:
    if args.command == "experiments":
        if args.chapter in ("compare", "readme-table"):
            return _results(args)
        if args.folder is not None:
            raise InputError(f"`bhgrasp experiments {args.chapter}` takes no folder; use --output")
        chapters = ("ch3", "ch4", "ch5") if args.chapter == "all" else (args.chapter,)
        existing = [args.output / f"chapter{chapter[2:]}.json" for chapter in chapters]
        existing = [str(path) for path in existing if path.exists()]
        if existing and not args.force:
            raise InputError(
                f"{', '.join(existing)} already exist(s) (a committed result?); pass --force to replace, or choose "
                "another --output"
            )
        for chapter in chapters:
            status = _experiments(chapter, args.output, args.scale, not args.no_figures)
            if status:
                return status
        if args.readme is not None:
            _readme(args.readme, args.output)
        return 0
    if args.command == "info":
        from bhgrasp import BarrettHand, Hand

        print((BarrettHand() if args.urdf is None else Hand.from_urdf(args.urdf, mimic=args.mimic)).summary())
        return 0
    if args.command == "tune":
        return _tune(args)
    if args.command == "sweep":
        return _sweep(args.config)
    if args.command == "bench":
        return _bench(args.quick)
    if args.command == "demo":
        return _grasp_demo(args)
    if args.command == "grasp-bench":
        return _grasp_bench(args)
    return _tour(args.output, args.samples, args.seed, args.hold)


def _tune(args: argparse.Namespace) -> int:
    import numpy as np

    from bhgrasp import tuning
    from bhgrasp.scenarios.press_fitness import impedance_fitness
    from bhgrasp.thesis.chapter4_tuning import TUNING_BOUNDS, TUNING_TOL_FUN, TUNING_TOL_X

    lower, upper = (np.log10(bound) for bound in TUNING_BOUNDS)  # physical bounds, argued in chapter 4
    print(f"tuning log10 (M_I [kg], K_I [N/m]) of F3's impedance for f_d = {args.force:g} N within "
          f"M_I {10**lower[0]:g}-{10**upper[0]:g} kg, K_I {10**lower[1]:g}-{10**upper[1]:g} N/m ...")  # fmt: skip
    result = tuning.cma_es(
        functools.partial(impedance_fitness, force=args.force), x0=[-1.0, 1.5], sigma0=0.5,
        seed=args.seed, max_generations=args.generations, population=args.population, bounds=(lower, upper),
        tol_fun=TUNING_TOL_FUN, tol_x=TUNING_TOL_X, executor="serial" if args.serial else None,
        progress=sys.stderr.isatty(),  # a bar over generations on a terminal; logs stay clean
    )  # fmt: skip
    mass, stiffness = 10.0**result.best
    print(f"best M_I = {mass:.4g} kg, K_I = {stiffness:.4g} N/m: mean force error {result.best_fitness:.4f} N")
    print(f"{result.generations} generations, {result.evaluations} simulations; cma stopped on {result.criteria}")
    return 0


def _sweep(config_path: Path) -> int:
    from bhgrasp import sweep
    from bhgrasp.scenarios.rollouts import check_grasp_case, grasp_rollout
    from bhgrasp.sweep_config import load_config

    config = load_config(config_path)  # every key and case checked: nothing runs on a mistake
    executor = "serial" if config.workers == 1 else None
    print(f"sweep: {len(config.cases)} cases, log {config.log}, {config.workers or 'all'} worker(s)")
    table = sweep.run_sweep(grasp_rollout, config.cases, seed=config.seed, log=config.log, executor=executor,
                            workers=config.workers, progress=config.progress, check=check_grasp_case)  # fmt: skip
    config.output.parent.mkdir(parents=True, exist_ok=True)
    table.to_csv(config.output, index=False)
    failed = table[table["status"] != "ok"]
    print(f"wrote {config.output}: {len(table)} cases, {len(failed)} failed")
    if len(failed):
        for error, rows in failed.groupby("error"):
            print(f"  {len(rows)} case(s) {sorted(rows['case'].tolist())[:10]} failed: {error}", file=sys.stderr)
        return 1
    return 0


BENCH_QUICK = {
    "bench_batch.py": ["--steps", "10", "--sizes", "8"],
    "bench_hand.py": ["--repeat", "200"],
    "bench_sim.py": ["--duration", "0.05"],
    "bench_control.py": ["--repeat", "50"],
    "bench_qp.py": ["--cycles", "50"],
    "bench_sweep.py": ["--cases", "2", "--duration", "0.8"],
    "bench_scaling.py": ["--steps", "20"],
    "bench_instructions.py": ["--cases", "free", "--engine", "compiled", "--short", "2", "--long", "12"],
}


def _bench(quick: bool) -> int:
    import subprocess

    folder = Path(__file__).resolve().parents[1] / "benchmarks"
    scripts = sorted(folder.glob("bench_*.py"))
    if not scripts:
        raise InputError(f"no benchmarks at {folder}: `bhgrasp bench` runs from a source checkout (pip install -e .)")
    for script in scripts:
        print(f"== {script.name}", flush=True)
        extra = BENCH_QUICK.get(script.name, []) if quick else []
        status = subprocess.run([sys.executable, str(script), *extra], check=False).returncode
        if status:
            print(f"bhgrasp: error: {script.name} exited with {status}", file=sys.stderr)
            return status
    return 0


def _grasp_bench(args: argparse.Namespace) -> int:
    import json

    from bhgrasp.bench import report as bench_report
    from bhgrasp.bench.objects import SETS

    names = list(dict.fromkeys(args.sets or [])) if args.sets or args.objects else list(SETS)
    objects = [*(args.objects or []), *(item for name in names or [] for item in SETS[name])]
    sets = [*([""] * len(args.objects or [])), *(name for name in names or [] for _ in SETS[name])]
    grasps, actuations = args.grasps or ["power", "precision"], args.actuations or ["barrett"]
    spreads = f" x spreads {args.spreads}" if args.spreads else ""
    count = len(objects) * len(grasps) * len(actuations) * len(args.spreads or [None])
    print(f"grasp benchmark: {count} trials ({len(objects)} objects x {grasps} x {actuations}{spreads}), 18 s each ...")
    trials, walls = bench_report.run_bench(objects, grasps, actuations, workers=args.workers,
                                           progress=sys.stderr.isatty(), spreads=args.spreads, sets=sets)  # fmt: skip
    for group in bench_report.groups(trials):
        for actuation, (ok, strict, total) in bench_report.success_rates(trials, group).items():
            print(f"{f'{group} set, ' if group else ''}{actuation}: {ok}/{total} succeed ({strict} strict)")
    for trial in trials:
        if not trial["success"]:
            at = f" at spread {trial['spread']:g} rad" if args.spreads else ""
            print(f"  {trial['object']} {trial['grasp']} {trial['actuation']}{at}: {trial['failure']}")
    print(f"wall time per trial: {min(walls):.1f}-{max(walls):.1f} s")
    if args.json is not None:
        bench_report.write_json(trials, args.json)
    if args.report is not None:
        args.report.write_text(bench_report.markdown(trials, _bench_command(args)))
    if args.compare is not None:
        reference = json.loads(args.compare.read_text())["trials"]
        problems = bench_report.compare(trials, reference)
        for problem in problems:
            print(f"  differs: {problem}", file=sys.stderr)
        print(f"compared {len(trials)} trials with {args.compare}: {len(problems)} difference(s)")
        return 1 if problems else 0
    return 0


def _bench_command(args: argparse.Namespace) -> str:
    """The ``bhgrasp grasp-bench`` command line that makes this report (without ``--workers`` and ``--compare``)."""
    parts = ["bhgrasp grasp-bench", *(f"--object {item.spec}" for item in args.objects or []),
             *(f"--set {name}" for name in args.sets or []),
             *(f"--grasp {grasp}" for grasp in args.grasps or []),
             *(f"--actuation {actuation}" for actuation in args.actuations or []),
             *(f"--spread {spread:g}" for spread in args.spreads or [])]  # fmt: skip
    parts += [f"--{name} {getattr(args, name)}" for name in ("json", "report") if getattr(args, name) is not None]
    return " ".join(parts)


def _grasp_demo(args: argparse.Namespace) -> int:
    from bhgrasp.scenarios.grasp_demo import grasp_scene, run_grasp_demo, save_demo

    print(f"simulating {args.duration:g} s: approach, squeeze, lift and turn a {args.mass:g} kg box ...")
    viewer = None
    if args.viz:
        from bhgrasp.viz import SceneViewer

        viewer = SceneViewer(grasp_scene(args.hand, args.mass).simulator.scene)
        print(f"MeshCat: {viewer.url}", flush=True)
    try:
        result = run_grasp_demo(args.mass, args.estimate, args.controller, args.duration,
                                distribution=args.distribution, viewer=viewer, hand=args.hand,
                                adaptation=args.adaptation)  # fmt: skip
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
        from bhgrasp.viz import SceneViewer

        viewer = SceneViewer(result.scene, quiet=True)  # its server ends with this command: no address to print
        try:
            viewer.replay(result.trajectory)
            print(f"wrote {viewer.save_html(args.html)} (MeshCat replay; opens offline)")
        finally:
            viewer.close()
    return 0


def _serve(url: str, seconds: float | None) -> None:
    """Keep the MeshCat server (and its replay) up for ``seconds``, or until Enter / Ctrl-C."""
    import time

    print(f"replay at {url}", flush=True)
    if seconds is not None:
        time.sleep(max(seconds, 0.0))
        return
    try:
        input("press Enter to quit ")
    except (EOFError, KeyboardInterrupt):
        pass


def _tour(output: Path, samples: int, seed: int, duration: float) -> int:
    import bhgrasp as bh
    from bhgrasp.thesis.chapter2 import workspace_table

    hand = bh.BarrettHand()
    print(hand.summary())
    q = hand.configuration(F1_spread=np.pi / 3, F1_proximal=1.0, F2_proximal=1.0, F3_proximal=1.0)
    print("\nfingertip positions [m] in frame W at a tripod pose (spread 60 deg, proximal 57.3 deg):")
    for finger, position in zip(hand.fingers, hand.fingertip_positions(q)):
        print(f"  {finger}: {np.array2string(position, precision=4, floatmode='fixed', suppress_small=True)}")
    target = hand.fingertip_positions(q)[2]
    solution = bh.finger_ik(hand, "F3", target)
    print(f"closed-form IK of F3 back from that point: {np.round(solution.angles, 6)} rad")
    print("\nworkspace bounds in the thesis' axes (Table 2.2; see bhgrasp.thesis.chapter2):")
    for row in workspace_table(hand, samples, seed):
        print(row.format())
    figure_path = _plot_workspace(hand, output, samples, seed)
    print(f"\nworkspace figure: {figure_path}")
    _hold(duration)
    return 0


def _experiments(chapter: str, output: Path, scale: float, figures: bool) -> int:
    import importlib
    import time

    number = chapter[2:]
    module = importlib.import_module(f"bhgrasp.thesis.chapter{number}")
    start = time.perf_counter()
    cases = getattr(module, f"run_chapter{number}")(output, scale=scale, figures=figures, progress=sys.stderr.isatty())
    runs = sum(len(getattr(case, "runs", ())) for case in cases)
    counted = f", {runs} runs" if runs else ""
    print(f"{chapter}: {len(cases)} cases{counted} in {time.perf_counter() - start:.1f} s")
    print(f"report: {output / f'chapter{number}.md'}")
    from bhgrasp.thesis.results import write_results

    print(f"figures of merit: {write_results(output, int(number), cases, scale)}")
    return 0


def _results(args: argparse.Namespace) -> int:
    """``experiments compare FOLDER`` and ``experiments readme-table``."""
    from bhgrasp.thesis import results

    if args.chapter == "compare":
        if args.folder is None:
            raise InputError("`bhgrasp experiments compare` needs the folder of a run (its chapterN.json)")
        ok, report = results.compare_folders(args.folder, args.reference)
        print(report)
        return 0 if ok else 1
    if args.folder is not None:
        raise InputError("`bhgrasp experiments readme-table` takes no folder; use --reference")
    if args.readme is None:
        print(results.render_readme_table(args.reference), end="")
    else:
        _readme(args.readme, args.reference)
    return 0


def _readme(readme: Path, folder: Path) -> None:
    from bhgrasp.thesis.results import update_readme

    try:
        changed = update_readme(readme, folder)
    except (OSError, ValueError, KeyError, StopIteration) as error:
        raise InputError(f"cannot render {readme}'s results table from {folder}: {error!r}") from error
    print(f"{readme}: results table {'rewritten' if changed else 'already up to date'}")


def _hold(duration: float) -> None:
    """Simulate the reference three-finger hold and report contacts and creep."""
    from bhgrasp.scenarios.hold import BOX_MASS, reference_hold

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
    output.mkdir(parents=True, exist_ok=True)
    path = output / "workspace.png"
    _workspace_figure(hand, samples, seed).savefig(path, dpi=120)
    return path


def _workspace_figure(hand, samples: int, seed: int):
    """The tour's workspace figure (:func:`bhgrasp.plots.workspace_figure`) of ``samples`` tips per finger."""
    from bhgrasp.model.ik import workspace
    from bhgrasp.plots import workspace_figure

    points = {finger: workspace(hand, finger, samples, rng=seed).points for finger in hand.fingers}
    return workspace_figure(points, f"Barrett BH8-280 fingertip workspace ({samples} samples per finger, seed {seed})")


if __name__ == "__main__":
    sys.exit(main())
