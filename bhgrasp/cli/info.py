"""``bhgrasp info``: a hand's joints, limits and link masses."""

from __future__ import annotations

import argparse
from pathlib import Path


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The hand to describe."""
    parser.add_argument("--urdf", type=Path, default=None, help="any hand URDF instead of the packaged Barrett hand")
    parser.add_argument(
        "--mimic",
        choices=["coupled", "independent"],
        default="coupled",
        help="a URDF with <mimic> couplings: mimic joints follow their joint (default), or independent DOFs",
    )


def run(args: argparse.Namespace) -> int:
    """Print the hand's summary."""
    from bhgrasp.model.barrett_hand import BarrettHand
    from bhgrasp.model.hand import Hand

    print((BarrettHand() if args.urdf is None else Hand.from_urdf(args.urdf, mimic=args.mimic)).summary())
    return 0
