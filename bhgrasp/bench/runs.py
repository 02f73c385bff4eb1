"""The grasp benchmark's runs: its trials on the sweep executor, alone on their stands or among neighbours.

Every object x grasp x actuation (x spread) trial runs through :func:`~bhgrasp.sweep.run_sweep`
(:func:`run_bench`); with ``neighbours``, each among that many mixed objects settled around its stand
(:mod:`~bhgrasp.bench.neighbours`, seeded by ``neighbour_seed``).  A trial that raises (e.g.
:class:`~bhgrasp.errors.SimulationDiverged`) is a failed trial whose ``failure`` is the error; the sweep goes on.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Sequence
from typing import Any

from bhgrasp.bench.neighbours import run_among_neighbours
from bhgrasp.bench.objects import BenchObject
from bhgrasp.bench.protocol import GRASPS, Trial
from bhgrasp.bench.report import METRICS, OUTCOMES, STOP
from bhgrasp.bench.trial import run_trial
from bhgrasp.sweep import run_sweep

# a trial among neighbours adds these to its record
NEIGHBOURS = ("heading", "neighbours_disturbed", "max_neighbour_moved", "peak_neighbour_force")
CLUTTER = ("neighbours", "neighbour_seed")  # ... and says among how many, from which seed


def bench_rollout(parameters: dict[str, Any], seed: int) -> dict[str, Any]:
    """One trial as a sweep rollout (deterministic: ``seed`` is unused)."""
    item = dataclasses.replace(BenchObject.parse(parameters["spec"]), name=parameters["name"])
    trial = Trial(item, parameters["grasp"], parameters["actuation"], parameters.get("spread"))
    if not parameters.get("neighbours"):
        record = run_trial(trial)
    else:
        record = run_among_neighbours(trial, parameters["neighbours"], parameters["neighbour_seed"])
        record["max_neighbour_moved"] = max(record.pop("neighbour_moved"))
        del record["neighbours"]  # their names: the count and seed make them again
    return {key: value for key, value in record.items() if key not in parameters and key != "object"}


def run_bench(
    objects: Sequence[BenchObject],
    grasps: Sequence[str] = GRASPS,
    actuations: Sequence[str] = ("barrett",),
    workers: int | None = None,
    progress: bool = False,
    executor: Any = None,
    spreads: Sequence[float] | None = None,
    sets: Sequence[str] | None = None,
    on_row: Callable[[dict[str, Any]], None] | None = None,
    neighbours: int = 0,
    neighbour_seed: int = 0,
) -> tuple[list[dict[str, Any]], list[float]]:
    """Every trial of ``objects`` x ``grasps`` x ``actuations`` (a process pool of ``workers``).

    ``spreads`` [rad]: run every trial at each of these pre-shape spreads instead of its grasp's own
    (:attr:`~bhgrasp.bench.protocol.Trial.spread`).  ``sets``: each object's set name (default ``""``).
    ``on_row``: called with each trial's sweep row as it finishes (:func:`~bhgrasp.sweep.run_sweep`).
    ``neighbours``: each trial among this many mixed objects settled around its stand, seeded by ``neighbour_seed``
    (:func:`~bhgrasp.bench.neighbours.run_among_neighbours`; its record adds :data:`NEIGHBOURS`).
    Returns the trial records and each trial's wall time [s] (kept apart: records repeat bit for bit, times not).
    """
    labels = [""] * len(objects) if sets is None else list(sets)
    if len(labels) != len(objects):
        raise ValueError(f"`sets` names {len(labels)} sets for {len(objects)} objects")
    design = [
        {"name": o.name, "spec": o.spec, "set": label, "grasp": g, "actuation": a}
        for a in actuations
        for o, label in zip(objects, labels)
        for g in grasps
    ]
    if spreads:
        design = [{**case, "spread": float(spread)} for case in design for spread in spreads]
    if neighbours:
        design = [{**case, "neighbours": neighbours, "neighbour_seed": neighbour_seed} for case in design]
    for case in design:  # refuse bad cases before running
        Trial(BenchObject.parse(case["spec"]), case["grasp"], case["actuation"], case.get("spread"))
    table = run_sweep(
        bench_rollout,
        design,
        executor=executor or ("serial" if workers == 1 else None),
        workers=workers,
        progress=progress,
        on_row=on_row,
    )
    trials, walls = [], []
    for row in table.to_dict("records"):
        trial = {key: row[key] for key in ("spec", "set", "grasp", "actuation", *(CLUTTER if neighbours else ()))}
        trial["object"] = row["name"]
        if row["status"] == "ok":
            named = ("spread", "opening", *OUTCOMES, *METRICS, "most_loaded_joint", "need_joint", *STOP, "failure")
            trial.update({key: row[key] for key in named})
            trial.update({key: row[key] for key in NEIGHBOURS if neighbours})
            if neighbours:  # a count (the table's column is float where an errored trial left it empty)
                trial["neighbours_disturbed"] = int(trial["neighbours_disturbed"])
        else:
            trial.update(
                spread=row.get("spread"),
                opening=row.get("opening"),
                success=False,
                strict_success=False,
                placed=False,
                inside_envelope=None,
                gripped=False,
                most_loaded_joint=None,
                need_joint=None,
                **dict.fromkeys(STOP),
                failure=row["error"],
                **dict.fromkeys(METRICS),
                **dict.fromkeys(NEIGHBOURS if neighbours else ()),
            )
        trials.append({key: _plain(value) for key, value in trial.items()})
        walls.append(row["wall_time"])
    return trials, walls


def _plain(value: Any) -> Any:
    """JSON-ready: numpy scalars to Python, NaN to None."""
    if hasattr(value, "item"):
        value = value.item()
    if isinstance(value, float) and math.isnan(value):
        return None
    return value


__all__ = ["CLUTTER", "NEIGHBOURS", "bench_rollout", "run_bench"]
