"""Parameter sweeps: a grid or seeded random design, one seeded rollout per case, on any executor.

A *rollout* is a top-level (picklable) function ``rollout(parameters: dict, seed: int) -> dict[str, float]`` that
returns per-case metrics.  :func:`run_sweep` runs it for every case of a design through any
:class:`concurrent.futures.Executor`: a local process pool by default, or a Dask cluster unchanged
(``distributed.Client(...).get_executor()``).  Every finished case is appended at once to a JSON-lines log; a case
that raises is recorded with ``status = "failed"`` and its error, and never stops the sweep.  Running again with the
same log skips the cases already in it (resume after an interruption).  The result is a pandas DataFrame, one row per
case: ``case``, ``seed``, the parameters, ``status``, ``error``, ``wall_time`` [s] and the metrics.

Rollouts of the built-in scenes (the grasp demo with any of its parameters varied, the reference hold batched) are
in :mod:`bhgrasp.scenarios.rollouts`.
"""

from __future__ import annotations

import functools
import itertools
import json
from collections.abc import Callable, Iterable, Mapping, Sequence
from concurrent.futures import Executor
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

import numpy as np

from bhgrasp.errors import InputError
from bhgrasp.parallel import Outcome, describe_error, executor_for, parallel_map, progress_bar

Rollout = Callable[[dict[str, Any], int], Mapping[str, Any]]
RESERVED = ("case", "seed", "status", "error", "wall_time")


@dataclass(frozen=True)
class BatchedRollout:
    """A rollout that runs many cases in one call (e.g. on a :class:`~bhgrasp.sim.batch.BatchSimulator`).

    Attributes:
        function: Top-level ``(parameters_list, seeds) -> metrics_list``, one metrics dict per case, in order.
        size: Cases per call (the executor receives ``ceil(cases / size)`` tasks).
    """

    function: Callable[[list[dict[str, Any]], list[int]], Sequence[Mapping[str, Any]]]
    size: int = 64

    def __post_init__(self) -> None:
        if isinstance(self.size, bool) or not isinstance(self.size, int) or self.size < 1:
            raise InputError(f"`size` must be a positive integer (cases per call), got {self.size!r}")


def grid(**axes: Sequence[Any]) -> list[dict[str, Any]]:
    """Every combination of the given values (a full factorial design), in ``itertools.product`` order."""
    if not axes:
        raise InputError("`grid` needs at least one parameter axis, e.g. grid(mass=[0.2, 0.5])")
    for name, values in axes.items():
        if isinstance(values, str) or not isinstance(values, Iterable) or len(list(values)) == 0:
            raise InputError(f"axis {name!r} must be a non-empty list of values, got {values!r}")
    names = list(axes)
    return [dict(zip(names, combination)) for combination in itertools.product(*(list(axes[n]) for n in names))]


def random_design(n: int, seed: int, **ranges: tuple[float, float]) -> list[dict[str, float]]:
    """``n`` cases drawn uniformly in each ``(low, high)`` range, from a seeded generator."""
    if int(n) < 1:
        raise InputError(f"`n` must be a positive integer, got {n}")
    if not ranges:
        raise InputError("`random_design` needs at least one range, e.g. mass=(0.2, 1.0)")
    rng = np.random.default_rng(seed)
    bounds = {}
    for name, value in ranges.items():
        low, high = (float(v) for v in value)
        if not (np.isfinite(low) and np.isfinite(high) and low <= high):
            raise InputError(f"range {name!r} must be finite (low, high) with low <= high, got {value!r}")
        bounds[name] = (low, high)
    return [{name: float(rng.uniform(low, high)) for name, (low, high) in bounds.items()} for _ in range(int(n))]


def case_seeds(n: int, seed: int) -> list[int]:
    """Independent per-case seeds from one sweep seed (numpy SeedSequence spawning)."""
    return [int(child.generate_state(1)[0]) for child in np.random.SeedSequence(seed).spawn(n)]


def run_sweep(
    rollout: Rollout | BatchedRollout,
    design: Sequence[Mapping[str, Any]],
    *,
    seed: int = 0,
    log: str | Path | None = None,
    executor: Executor | Literal["serial"] | None = None,
    workers: int | None = None,
    progress: bool = False,
    check: Callable[[dict[str, Any]], None] | None = None,
    on_row: Callable[[dict[str, Any]], None] | None = None,
):
    """Run ``rollout`` on every case of ``design``; returns a pandas DataFrame (one row per case, case order).

    Args:
        rollout: Top-level function ``(parameters, seed) -> metrics`` (must pickle for a process pool or Dask), or
            a :class:`BatchedRollout` that runs ``size`` cases per call.
        design: The cases' parameter dicts (:func:`grid`, :func:`random_design`, or any list).
        seed: Sweep seed; case ``i`` gets ``case_seeds(len(design), seed)[i]``.
        log: JSON-lines file that receives each finished case; cases already in it are skipped (resume).
        executor: ``None`` (a local process pool of ``workers`` processes, default the CPU count), ``"serial"``
            (in this process), or any ``concurrent.futures.Executor`` such as a Dask ``Client.get_executor()``.
        workers: Processes of the default pool.
        progress: Show a tqdm progress bar.
        check: Called with every case's parameters before anything runs (e.g.
            :func:`~bhgrasp.scenarios.rollouts.check_grasp_case`); an ``InputError`` it raises stops the sweep at once,
            naming the case.
        on_row: Called with each case's row as it finishes (completion order; not for rows resumed from the log).

    Raises:
        InputError: A case uses a reserved column name or fails ``check``; the log belongs to another sweep (other
            case count, seeds or parameters).
    """
    import pandas as pd

    cases = [dict(case) for case in design]
    if not cases:
        raise InputError("`design` has no cases")
    for index, case in enumerate(cases):
        clash = [name for name in case if name in RESERVED]
        if clash:
            raise InputError(f"case {index} uses reserved column names {clash}; rename the parameters")
        if check is not None:
            try:
                check(dict(case))
            except InputError as error:
                raise InputError(f"case {index} ({describe_case(case)}): {error}") from error
    seeds = case_seeds(len(cases), seed)
    path = None if log is None else Path(log)
    rows = _read_log(path, cases, seeds) if path is not None else {}
    todo = [i for i in range(len(cases)) if i not in rows]
    bar = progress_bar(len(cases), "sweep", "case", initial=len(rows), enabled=progress)
    if isinstance(rollout, BatchedRollout):
        function, batch = functools.partial(_call_batch, rollout.function), rollout.size
    else:
        function, batch = functools.partial(_call, rollout), None
    try:
        with executor_for(executor, workers) as runner:
            items = [(cases[i], seeds[i]) for i in todo]
            for outcome in parallel_map(function, items, runner, batch=batch, ordered=False):
                if outcome.lost:  # the executor broke: nothing is logged for the case, a rerun resumes it
                    raise outcome.error
                index = todo[outcome.index]
                rows[index] = _row(index, cases[index], seeds[index], outcome)
                if path is not None:
                    _append(path, rows[index])
                if on_row is not None:
                    on_row(rows[index])
                bar.update(1)
    finally:
        bar.close()
    return pd.DataFrame([rows[i] for i in sorted(rows)])


def _call(rollout: Rollout, item: tuple[dict[str, Any], int]) -> dict[str, Any]:
    """One case's metrics (runs in a worker, or here)."""
    parameters, seed = item
    return dict(rollout(dict(parameters), seed))


def _call_batch(function: Callable, items: list[tuple[dict[str, Any], int]]) -> list[dict[str, Any]]:
    """A batched rollout's cases' metrics, in order (runs in a worker, or here)."""
    return [dict(metrics) for metrics in function([dict(case) for case, _ in items], [seed for _, seed in items])]


def _row(index: int, parameters: dict[str, Any], seed: int, outcome: Outcome) -> dict[str, Any]:
    """Case ``index``'s row: its parameters, ``status``, ``error``, metrics and ``wall_time``."""
    row: dict[str, Any] = {"case": index, "seed": seed, **parameters}
    if outcome.error is not None:
        row.update(status="failed", error=describe_error(outcome.error))
    else:
        clash = [name for name in outcome.value if name in RESERVED or name in parameters]
        if clash:
            row.update(status="failed", error=f"rollout returned reserved or parameter names {clash}")
        else:
            row.update(status="ok", error="", **{k: _plain(v) for k, v in outcome.value.items()})
    row["wall_time"] = outcome.wall_time
    return row


def _plain(value: Any) -> Any:
    """JSON-friendly scalars (numpy numbers to Python numbers)."""
    return value.item() if isinstance(value, np.generic) else value


def describe_case(case: Mapping[str, Any]) -> str:
    """A case's parameters as ``name=value, ...`` for an error message."""
    return ", ".join(f"{name}={value!r}" for name, value in case.items())


def _read_log(path: Path, cases: list[dict[str, Any]], seeds: list[int]) -> dict[int, dict[str, Any]]:
    """Rows already in the log, checked against this sweep: the same case count, seeds and every parameter.

    A row is the case it names only if its parameters are this case's (as JSON keeps them): a changed fixed
    parameter or design never reuses stale rows.
    """
    n = len(cases)
    rows: dict[int, dict[str, Any]] = {}
    if not path.exists():
        return rows
    for number, line in enumerate(path.read_text().splitlines(), start=1):
        if not line.strip():
            continue
        try:
            row = json.loads(line)
            case = int(row["case"])
        except (ValueError, KeyError, TypeError) as error:
            raise InputError(f"{path}:{number} is not a sweep log line ({error})") from error
        if not 0 <= case < n or row.get("seed") != seeds[case]:
            raise InputError(f"{path} belongs to another sweep (case {case}, seed {row.get('seed')}); use a new log")
        expected = json.loads(json.dumps({name: _plain(value) for name, value in cases[case].items()}))
        logged = {name: row.get(name) for name in expected}
        if logged != expected:
            changed = [name for name in expected if logged[name] != expected[name]]
            raise InputError(
                f"{path} belongs to another sweep: its case {case} has "
                f"{describe_case({k: logged[k] for k in changed})}, this sweep's has "
                f"{describe_case({k: expected[k] for k in changed})}; use a new log (or delete it)"
            )
        rows[case] = row
    return rows


def _append(path: Path, row: dict[str, Any]) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    with path.open("a") as stream:
        stream.write(json.dumps(row) + "\n")
        stream.flush()


__all__ = [
    "BatchedRollout",
    "case_seeds",
    "describe_case",
    "grid",
    "random_design",
    "run_sweep",
]
