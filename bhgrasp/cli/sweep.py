"""``bhgrasp sweep``: a parameter sweep of the grasp demo from a TOML file, its table written as CSV."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The sweep file."""
    parser.add_argument(
        "config", type=Path, help="TOML: [sweep] output, log, workers, seed; [grid] or [random]; [fixed]"
    )


def run(args: argparse.Namespace) -> int:
    """Run every case of the file (resuming from its log); status 1 if a case failed."""
    from bhgrasp.scenarios.rollouts import check_grasp_case, grasp_rollout
    from bhgrasp.sweep import run_sweep
    from bhgrasp.sweep_config import load_config

    config = load_config(args.config)  # every key and case checked: nothing runs on a mistake
    executor = "serial" if config.workers == 1 else None
    print(f"sweep: {len(config.cases)} cases, log {config.log}, {config.workers or 'all'} worker(s)")
    table = run_sweep(
        grasp_rollout,
        config.cases,
        seed=config.seed,
        log=config.log,
        executor=executor,
        workers=config.workers,
        progress=config.progress,
        check=check_grasp_case,
    )
    config.output.parent.mkdir(parents=True, exist_ok=True)
    table.to_csv(config.output, index=False)
    failed = table[table["status"] != "ok"]
    print(f"wrote {config.output}: {len(table)} cases, {len(failed)} failed")
    if len(failed):
        for error, rows in failed.groupby("error"):
            print(f"  {len(rows)} case(s) {sorted(rows['case'].tolist())[:10]} failed: {error}", file=sys.stderr)
        return 1
    return 0
