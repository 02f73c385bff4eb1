"""``bhgrasp grasp-bench``: the grasp benchmark on the wrist-mounted BH8-280, its report and its comparison."""

from __future__ import annotations

import argparse
import json
import math
import sys

from bhgrasp.cli import arguments as checked

# bhgrasp.bench.objects.SETS, checked equal by the tests
SETS = ("development", "held-out", "held-out-2", "held-out-3", "held-out-4", "held-out-5", "meshes")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Which trials, and where their results go."""
    add = parser.add_argument
    add(
        "--object",
        dest="objects",
        action="append",
        type=checked.bench_object,
        default=None,
        metavar="KIND:DIMS:MASS",
        help="box:0.06x0.05x0.05:0.3 (edges, m), cylinder:0.033x0.10:0.35 (radius x height), sphere:0.035:0.2 "
        "(radius); masses in kg; ':mesh' after one simulates it as a mesh; mesh:PATH:MASS a mesh file [m], "
        "household:mug:0.118 a household object; repeatable (default: the built-in sets, see --set)",
    )
    add(
        "--set",
        dest="sets",
        action="append",
        choices=SETS,
        default=None,
        help="a built-in object set: development (the protocol's constants were chosen on it), held-out (fixed "
        "before tuning), held-out-2 to held-out-5 (each fixed before any of its trials ran) or meshes (the "
        "development set as meshes, a mug and a bottle); repeatable; with --object, added to those",
    )
    add(
        "--grasp",
        dest="grasps",
        action="append",
        choices=("power", "precision"),
        default=None,
        help="repeatable (default: both)",
    )
    add(
        "--actuation",
        dest="actuations",
        action="append",
        choices=("barrett", "full"),
        default=None,
        help="repeatable (default: barrett, the real 4-motor hand)",
    )
    add(
        "--spread",
        dest="spreads",
        action="append",
        type=checked.spread_angle,
        default=None,
        metavar="RAD",
        help="run every trial at this pre-shape spread [rad, 0 to pi] instead of its grasp's own (0 for boxes, "
        "pi/3 for spheres and cylinders); repeatable",
    )
    add(
        "--neighbours",
        type=checked.positive_int,
        default=0,
        metavar="N",
        help="run each trial among N mixed household-sized objects dropped and settled on a table flush with its "
        "stand; the report counts the neighbours each trial disturbed (moved over 5 mm) (default: alone)",
    )
    add("--neighbour-seed", type=checked.seed, default=None, metavar="S", help="seed of the neighbours (default 0)")
    add("--json", type=checked.output_file, default=None, help="write the trials here")
    add("--report", type=checked.output_file, default=None, help="write the markdown report")
    add(
        "--compare",
        type=checked.existing_file,
        default=None,
        help="check the trials against this committed JSON (exit 1 on a difference)",
    )
    add("--workers", type=checked.positive_int, default=None, help="processes (default: cores)")


def run(args: argparse.Namespace) -> int:
    """Run the trials, print the summary, write JSON and report; with ``--compare``, status 1 on a difference."""
    from bhgrasp.bench import report, runs
    from bhgrasp.errors import InputError

    if args.neighbour_seed is not None and not args.neighbours:
        raise InputError(f"--neighbour-seed {args.neighbour_seed} seeds neighbours: give their number, --neighbours N")
    seed = args.neighbour_seed or 0
    from bhgrasp.bench.objects import SETS as OBJECT_SETS

    names = list(dict.fromkeys(args.sets or [])) if args.sets or args.objects else list(OBJECT_SETS)
    objects = [*(args.objects or []), *(item for name in names for item in OBJECT_SETS[name])]
    sets = [*([""] * len(args.objects or [])), *(name for name in names for _ in OBJECT_SETS[name])]
    grasps, actuations = args.grasps or ["power", "precision"], args.actuations or ["barrett"]
    spreads = f" x spreads {args.spreads}" if args.spreads else ""
    count = len(objects) * len(grasps) * len(actuations) * len(args.spreads or [None])
    print(f"grasp benchmark: {count} trials ({len(objects)} objects x {grasps} x {actuations}{spreads}), 18 s each ...")
    lines = TrialLines(count)
    trials, walls = runs.run_bench(
        objects,
        grasps,
        actuations,
        workers=args.workers,
        spreads=args.spreads,
        sets=sets,
        on_row=lines.print,
        neighbours=args.neighbours,
        neighbour_seed=seed,
    )
    print("\n".join(report.summary_lines(trials, walls, spreads=bool(args.spreads))))
    if args.json is not None:
        report.write_json(trials, args.json)
    if args.report is not None:
        args.report.write_text(report.markdown(trials, command(args)))
    if args.compare is None:
        return 0
    problems = report.compare(trials, json.loads(args.compare.read_text())["trials"])
    for problem in problems:
        print(f"  differs: {problem}", file=sys.stderr)
    print(f"compared {len(trials)} trials with {args.compare}: {len(problems)} difference(s)")
    return 1 if problems else 0


class TrialLines:
    """Prints a line per finished trial, at once (a run of 52 trials takes minutes): its outcome and wall time."""

    def __init__(self, total: int) -> None:
        self.total, self.done = total, 0

    def print(self, row: dict) -> None:
        """The line of a finished sweep row (:func:`bhgrasp.bench.runs.run_bench`'s ``on_row``)."""
        self.done += 1
        print(self.line(row), flush=True)

    def line(self, row: dict) -> str:
        """``[done/total] object grasp actuation, spread: outcome, wall time``."""
        if row["status"] != "ok":
            outcome = f"error: {row['error']}"
        elif row["success"]:
            outcome = "strict success" if row["strict_success"] else "success"
        else:
            outcome = "failure (reason below)"
        spread = f", spread {math.degrees(row['spread']):.0f} deg" if row.get("spread") is not None else ""
        label = f"{row['name']} {row['grasp']} {row['actuation']}{spread}"
        return f"  [{self.done}/{self.total}] {label}: {outcome}, {row['wall_time']:.1f} s"


def command(args: argparse.Namespace) -> str:
    """The ``bhgrasp grasp-bench`` command line that makes this report (without ``--workers`` and ``--compare``)."""
    parts = [
        "bhgrasp grasp-bench",
        *(f"--object {item.spec}" for item in args.objects or []),
        *(f"--set {name}" for name in args.sets or []),
        *(f"--grasp {grasp}" for grasp in args.grasps or []),
        *(f"--actuation {actuation}" for actuation in args.actuations or []),
        *(f"--spread {spread:g}" for spread in args.spreads or []),
        *([f"--neighbours {args.neighbours} --neighbour-seed {args.neighbour_seed or 0}"] if args.neighbours else []),
    ]
    parts += [f"--{name} {getattr(args, name)}" for name in ("json", "report") if getattr(args, name) is not None]
    return " ".join(parts)
