"""A sweep of the grasp demo described by a TOML file (``bhgrasp sweep CONFIG.toml``), checked before anything runs.

The file has a ``[sweep]`` table (``output``, ``log``, ``workers``, ``seed``, ``progress``), exactly one of
``[grid]`` (parameter = list of values: every combination) or ``[random]`` (``n`` and parameter = [low, high]:
``n`` uniform draws), and optionally ``[fixed]`` (parameter = value, the same in every case).  Parameters are
those of :func:`~bhgrasp.scenarios.grasp_demo.run_grasp_demo` (:data:`~bhgrasp.scenarios.grasp_demo.SWEEPABLE`).
``docs/sweep.toml`` is an example with every key explained.  Every mistake is an ``InputError`` naming the file,
table and key.
"""

from __future__ import annotations

import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from bhgrasp import sweep
from bhgrasp.errors import InputError
from bhgrasp.scenarios.rollouts import check_grasp_case
from bhgrasp.sweep import describe_case

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover  (Python 3.10)
    import tomli as tomllib

SETTINGS = {"output": str, "log": str, "workers": int, "seed": int, "progress": bool}
TABLES = ("sweep", "grid", "random", "fixed")


@dataclass(frozen=True)
class SweepConfig:
    """A checked sweep: its cases, the output CSV, the JSON-lines log, workers (``None``: all cores), seed."""

    cases: list[dict[str, Any]]
    output: Path
    log: Path
    workers: int | None
    seed: int
    progress: bool


def load_config(path: Path) -> SweepConfig:
    """Read and check a sweep file: names, types and every case's values (before anything runs).

    Raises:
        InputError: Unreadable TOML, an unknown table or key, a value of the wrong type, or a case the grasp demo
            refuses; the message names the file, table and key (or the case).
    """
    try:
        config = tomllib.loads(Path(path).read_text())
    except (OSError, tomllib.TOMLDecodeError) as error:
        raise InputError(f"cannot read the sweep configuration {str(path)!r}: {error}") from error
    unknown = sorted(set(config) - set(TABLES))
    if unknown:
        raise InputError(f"{path}: unknown table [{unknown[0]}]; the tables are [sweep], [grid] or [random], [fixed]")
    if ("grid" in config) == ("random" in config):
        given = "both" if "grid" in config else "neither"
        raise InputError(f"{path}: give exactly one of [grid] or [random] (got {given})")
    settings = _settings(path, config.get("sweep", {}))
    fixed = config.get("fixed", {})
    for table in ("grid", "random", "fixed"):
        for key in config.get(table, {}):
            if key == "n" and table == "random":
                continue
            try:
                check_grasp_case({key: _sample(config[table][key], table)})
            except InputError as error:
                raise InputError(f"{path} [{table}] {key}: {error}") from error
    if "grid" in config:
        axes = config["grid"]
        for key, values in axes.items():
            if not isinstance(values, list) or not values:
                raise InputError(f"{path} [grid] {key}: give a non-empty list of values, got {values!r}")
        design = sweep.grid(**axes)
    else:
        ranges = dict(config["random"])
        n = ranges.pop("n", None)
        if isinstance(n, bool) or not isinstance(n, int) or n < 1:
            raise InputError(f"{path} [random] n: give the number of cases, a positive integer, got {n!r}")
        for key, bounds in ranges.items():
            if not (isinstance(bounds, list) and len(bounds) == 2 and all(_is_number(b) for b in bounds)):
                raise InputError(f"{path} [random] {key}: give [low, high], got {bounds!r}")
        design = sweep.random_design(n, settings["seed"], **ranges)
    clash = sorted(set(fixed) & set(design[0]))
    if clash:
        raise InputError(f"{path} [fixed] {clash[0]}: also varied in the design; give it in one table only")
    cases = [{**fixed, **case} for case in design]
    for index, case in enumerate(cases):
        try:
            check_grasp_case(case)
        except InputError as error:
            raise InputError(f"{path} case {index} ({describe_case(case)}): {error}") from error
    output = Path(settings.get("output", "sweep.csv"))
    log = Path(settings.get("log", output.with_suffix(".jsonl")))
    workers = settings.get("workers", 0) or None
    return SweepConfig(cases, output, log, workers, settings["seed"], settings.get("progress", True))


def _settings(path: Path, table: dict[str, Any]) -> dict[str, Any]:
    settings = {"seed": 0}
    for key, value in table.items():
        kind = SETTINGS.get(key)
        if kind is None:
            raise InputError(f"{path} [sweep] {key}: unknown key; the keys are {', '.join(SETTINGS)}")
        if isinstance(value, bool) != (kind is bool) or not isinstance(value, kind):
            raise InputError(f"{path} [sweep] {key}: give {_KINDS[kind]}, got {value!r}")
        if kind is int and value < 0:
            raise InputError(f"{path} [sweep] {key}: give {_KINDS[int]}, got {value!r}")
        settings[key] = value
    return settings


_KINDS = {str: "a text (in quotes)", int: "an integer >= 0", bool: "true or false"}


def _sample(value: Any, table: str) -> Any:
    """One value a key of ``table`` takes (a grid's first value, a random range's low end)."""
    if table in ("grid", "random") and isinstance(value, list) and value:
        return value[0]
    return value


def _is_number(value: Any) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool)


__all__ = ["SweepConfig", "load_config"]
