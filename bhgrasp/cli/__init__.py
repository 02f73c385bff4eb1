"""The ``bhgrasp`` command: one module per subcommand, each loaded only once it is chosen.

``bhgrasp --help`` and a mistyped command import nothing of the library; ``bhgrasp info`` loads the model, not the
simulator.  Each subcommand module has ``add_arguments(parser)`` (its argparse table) and ``run(args) -> int`` (a few
calls of the library and what they print).  A :class:`~bhgrasp.errors.BhgraspError` (a user mistake or an
infeasible request) ends the command with one line on stderr and status 2.
"""

from __future__ import annotations

import argparse
import importlib
import sys
from collections.abc import Sequence
from typing import NoReturn

from bhgrasp.errors import BhgraspError

# subcommand -> (its module, its line in `bhgrasp --help`)
COMMANDS = {
    "demo": (
        "bhgrasp.cli.demo",
        "the main job: grasp a box of unknown mass, lift it 10 mm and turn it 0.1 rad (headless); prints the pose and "
        "force errors, slip events and time, writes a figure and the trajectory",
    ),
    "tour": ("bhgrasp.cli.tour", "print the hand model, check IK, plot the workspace, simulate a three-finger hold"),
    "info": ("bhgrasp.cli.info", "print a hand's joints, limits and link masses"),
    "tune": (
        "bhgrasp.cli.tune",
        "tune F3's force-based impedance (M_I, K_I) with CMA-ES on the fitness (4.49) of thesis chapter 4",
    ),
    "sweep": (
        "bhgrasp.cli.sweep",
        "run a parameter sweep of the grasp demo from a TOML file (grid or random design, process pool)",
    ),
    "grasp-bench": (
        "bhgrasp.cli.grasp_bench",
        "the grasp benchmark: per object and grasp, approach -> close -> lift 10 cm -> push 10 m N along +-x, +-y, "
        "+-z -> place, on the wrist-mounted BH8-280; prints the success table",
    ),
    "experiments": (
        "bhgrasp.cli.experiments",
        "reproduce a thesis chapter: report (markdown), figures and figures of merit (chapterN.json); compare a run "
        "with the committed results; render the README's results table",
    ),
}


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``bhgrasp`` command."""
    argv = list(sys.argv[1:] if argv is None else argv)
    parser = Parser(prog="bhgrasp", description="Barrett hand modelling, simulation and control.")
    commands = parser.add_subparsers(dest="command", required=True)
    chosen = next((word for word in argv if not word.startswith("-")), None)  # the top level has no option but -h
    for name, (module, summary) in COMMANDS.items():
        command = commands.add_parser(name, help=summary, description=summary, formatter_class=DefaultsHelp)
        if name == chosen:
            importlib.import_module(module).add_arguments(command)
    args = parser.parse_args(argv)
    try:
        return importlib.import_module(COMMANDS[args.command][0]).run(args)
    except BhgraspError as error:
        print(f"bhgrasp: error: {error}", file=sys.stderr)  # one line, no traceback
        return 2


class Parser(argparse.ArgumentParser):
    """argparse whose errors are one line, status 2.

    E.g. ``bhgrasp demo: error: argument --mass: must be a positive number, got '-1' (see bhgrasp demo --help)``.
    """

    def error(self, message: str) -> NoReturn:
        """Exit with status 2 and ``message`` on one line."""
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


class DefaultsHelp(argparse.ArgumentDefaultsHelpFormatter):
    """``--help`` lists each option's default, except for flags and options without one."""

    def _get_help_string(self, action: argparse.Action) -> str:
        if action.default is None or isinstance(action.default, bool):
            return action.help or ""
        return super()._get_help_string(action)


__all__ = ["COMMANDS", "DefaultsHelp", "Parser", "main"]
