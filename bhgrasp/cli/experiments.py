"""``bhgrasp experiments``: a thesis chapter reproduced, compared with the committed results, or tabulated."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from bhgrasp.cli import arguments as checked
from bhgrasp.errors import InputError

CHAPTERS = ("ch3", "ch4", "ch5")  # bhgrasp.thesis.runner.CHAPTERS, checked equal by the tests


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Which chapter, or which comparison, and where."""
    add = parser.add_argument
    add(
        "chapter",
        choices=[*CHAPTERS, "all", "compare", "readme-table"],
        help="ch3: joint-space control (CTC, SMC, ASMC, HOSM); ch4: force control; ch5: grasping and "
        "manipulation; all: the three; compare FOLDER: check a run's chapterN.json against --reference (exit 1 "
        "with a table of every value outside tolerance, missing or extra); readme-table: print the README's "
        "'Results at a glance' table rendered from --reference (with --readme: rewrite it there)",
    )
    add("folder", nargs="?", type=Path, default=None, help="compare: the new run's folder")
    add(
        "--output",
        type=checked.output_folder,
        default=Path("bhgrasp_experiments"),
        help="folder for report, figures and chapterN.json (one holding a chapterN.json is refused without --force)",
    )
    add(
        "--force",
        action="store_true",
        help="replace the chapterN.json, report and figures already in --output (e.g. the committed docs/results)",
    )
    add("--reference", type=Path, default=Path("docs/results"), help="compare, readme-table: the committed results")
    add(
        "--readme",
        type=Path,
        default=None,
        help="rewrite this README's results table from the chapterN.json in --output (after a run) or --reference",
    )
    add(
        "--scale",
        type=checked.positive_float,
        default=1.0,
        help="multiply every case's duration (e.g. 0.5 for a quick look)",
    )
    add("--no-figures", action="store_true", help="write the report only")


def run(args: argparse.Namespace) -> int:
    """Run the chapter(s) (refusing to overwrite results without ``--force``), or compare, or tabulate."""
    if args.chapter == "compare":
        return _compare(args)
    if args.chapter == "readme-table":
        return _readme_table(args)
    if args.folder is not None:
        raise InputError(f"`bhgrasp experiments {args.chapter}` takes no folder; use --output")
    from bhgrasp.thesis.runner import run_chapter

    chapters = CHAPTERS if args.chapter == "all" else (args.chapter,)
    existing = [args.output / f"chapter{chapter[2:]}.json" for chapter in chapters]
    existing = [str(path) for path in existing if path.exists()]
    if existing and not args.force:
        raise InputError(
            f"{', '.join(existing)} already exist(s) (a committed result?); pass --force to replace, or choose "
            "another --output"
        )
    for chapter in chapters:
        print(run_chapter(chapter, args.output, args.scale, not args.no_figures, progress=sys.stderr.isatty()))
    if args.readme is not None:
        _rewrite_readme(args.readme, args.output)
    return 0


def _compare(args: argparse.Namespace) -> int:
    from bhgrasp.thesis.results import compare_folders

    if args.folder is None:
        raise InputError("`bhgrasp experiments compare` needs the folder of a run (its chapterN.json)")
    ok, report = compare_folders(args.folder, args.reference)
    print(report)
    return 0 if ok else 1


def _readme_table(args: argparse.Namespace) -> int:
    from bhgrasp.thesis.readme_rows import render_readme_table

    if args.folder is not None:
        raise InputError("`bhgrasp experiments readme-table` takes no folder; use --reference")
    if args.readme is None:
        print(render_readme_table(args.reference), end="")
    else:
        _rewrite_readme(args.readme, args.reference)
    return 0


def _rewrite_readme(readme: Path, folder: Path) -> None:
    from bhgrasp.thesis.readme_rows import update_readme

    try:
        changed = update_readme(readme, folder)
    except (OSError, ValueError, KeyError, StopIteration) as error:
        raise InputError(f"cannot render {readme}'s results table from {folder}: {error!r}") from error
    print(f"{readme}: results table {'rewritten' if changed else 'already up to date'}")
