"""Argument types of the command line: each checks one flag's value before anything runs.

argparse reports a failed check as ``bhgrasp demo: error: argument --samples: must be a positive integer, got
'0'`` and exits with status 2, so every mistake is named by its flag and caught before a simulation starts.
"""

from __future__ import annotations

import argparse
import math
import tempfile
from pathlib import Path


def positive_int(text: str) -> int:
    """An integer >= 1."""
    return _integer(text, 1, "a positive integer")


def at_least_two(text: str) -> int:
    """An integer >= 2 (e.g. a CMA-ES population)."""
    return _integer(text, 2, "an integer >= 2")


def seed(text: str) -> int:
    """A random seed: an integer >= 0."""
    return _integer(text, 0, "an integer >= 0")


def _integer(text: str, minimum: int, expected: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be {expected}, got {text!r}") from None
    if value < minimum:
        raise argparse.ArgumentTypeError(f"must be {expected}, got {text!r}")
    return value


def positive_float(text: str) -> float:
    """A finite number > 0."""
    value = _number(text, "a positive number")
    if value <= 0.0:
        raise argparse.ArgumentTypeError(f"must be a positive number, got {text!r}")
    return value


def nonnegative_float(text: str) -> float:
    """A finite number >= 0."""
    value = _number(text, "a number >= 0")
    if value < 0.0:
        raise argparse.ArgumentTypeError(f"must be a number >= 0, got {text!r}")
    return value


def spread_angle(text: str) -> float:
    """A BH8-280 spread angle [rad], 0 to pi."""
    value = _number(text, "an angle in [0, pi] rad")
    if not 0.0 <= value <= math.pi:
        raise argparse.ArgumentTypeError(f"must be an angle in [0, pi] rad (the spread's range), got {text!r}")
    return value


def output_folder(text: str) -> Path:
    """A folder to write into: an existing writable folder, or a new one inside an existing writable folder."""
    path = Path(text)
    if path.exists():
        if not path.is_dir():
            raise argparse.ArgumentTypeError(f"{text!r} exists and is not a folder")
        if not _writable(path):
            raise argparse.ArgumentTypeError(f"the folder {text!r} is not writable")
        return path
    _writable_parent(path, text)
    return path


def output_file(text: str) -> Path:
    """A file to write, in an existing writable folder (no folders are created for it)."""
    path = Path(text)
    if path.is_dir():
        raise argparse.ArgumentTypeError(f"{text!r} is a folder; give a file name, e.g. {str(path / 'replay.html')!r}")
    _writable_parent(path, text)
    return path


def _writable_parent(path: Path, text: str) -> None:
    parent = path.parent if str(path.parent) else Path(".")
    if not parent.is_dir():
        raise argparse.ArgumentTypeError(f"the folder {str(parent)!r} of {text!r} does not exist")
    if not _writable(parent):
        raise argparse.ArgumentTypeError(f"the folder {str(parent)!r} of {text!r} is not writable")


def _writable(folder: Path) -> bool:
    """Whether a file can be created in ``folder`` (tried: permissions miss read-only and virtual file systems)."""
    try:
        with tempfile.TemporaryDirectory(dir=folder):
            return True
    except OSError:
        return False


def _number(text: str, expected: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be {expected}, got {text!r}") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"must be {expected}, got {text!r}")
    return value


def bench_object(text: str):
    """A grasp-benchmark object, ``KIND:DIMS:MASS`` (:class:`~bhgrasp.bench.objects.BenchObject`)."""
    from bhgrasp.bench.objects import BenchObject
    from bhgrasp.errors import InputError

    try:
        return BenchObject.parse(text)
    except InputError as error:
        raise argparse.ArgumentTypeError(str(error)) from None


def existing_file(text: str) -> Path:
    """A file that exists (to read)."""
    path = Path(text)
    if not path.is_file():
        raise argparse.ArgumentTypeError(f"no such file: {text!r}")
    return path
