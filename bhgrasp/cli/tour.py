"""``bhgrasp tour``: the hand model, IK, the workspace (figure and the thesis' Table 2.2) and a three-finger hold."""

from __future__ import annotations

import argparse
from pathlib import Path

from bhgrasp.cli import arguments as checked


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The tour's output, sampling and hold."""
    parser.add_argument(
        "--output", type=checked.output_folder, default=Path("bhgrasp_tour"), help="folder for the figure"
    )
    parser.add_argument("--samples", type=checked.positive_int, default=20_000, help="workspace samples per finger")
    parser.add_argument("--seed", type=checked.seed, default=0, help="random seed of the workspace sampling")
    parser.add_argument(
        "--hold", type=checked.positive_float, default=1.0, help="simulated duration of the grasp hold [s]"
    )


def run(args: argparse.Namespace) -> int:
    """Print each part of the tour and write the workspace figure."""
    from bhgrasp.model.barrett_hand import BarrettHand
    from bhgrasp.scenarios import tour
    from bhgrasp.thesis.chapter2 import workspace_table

    hand = BarrettHand()
    print(hand.summary())
    print("\n" + "\n".join(tour.tripod_lines(hand)))
    print("\nworkspace bounds in the thesis' axes (Table 2.2; see bhgrasp.thesis.chapter2):")
    for row in workspace_table(hand, args.samples, args.seed):
        print(row.format())
    print(f"\nworkspace figure: {tour.save_workspace_figure(hand, args.output, args.samples, args.seed)}")
    print()
    for line in tour.hold_lines(args.hold):
        print(line, flush=True)
    return 0
