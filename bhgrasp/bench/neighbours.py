"""A benchmark trial among neighbours: mixed objects settled on a table around the object's stand, then the trial.

:func:`settle_neighbours` drops ``count`` objects of :func:`~bhgrasp.scenarios.clutter.mixed_objects` (seeded) over
the table of :func:`~bhgrasp.bench.table.table_around`, clear of the trial's object on its stand, and lets all of
them settle (:func:`~bhgrasp.scenarios.clutter.drop_pile`); :func:`run_among_neighbours` runs the trial's protocol
from there and adds to its record how far each neighbour was moved (:func:`neighbour_displacements`) and how many
were disturbed, moved more than :data:`DISTURBED`.  The trial's own success is scored as alone
(:func:`~bhgrasp.bench.metrics.evaluate`).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from bhgrasp._validation import as_count, as_generator
from bhgrasp.bench.metrics import evaluate
from bhgrasp.bench.protocol import DT, FRICTION, Trial
from bhgrasp.bench.table import TABLE_REACH, Clutter, stand_of, table_around
from bhgrasp.bench.trial import simulate_trial
from bhgrasp.data import Trajectory
from bhgrasp.scenarios.clutter import drop_pile, mixed_objects

DISTURBED = 0.005  # [m] a neighbour moved further than this from where it settled was disturbed


def settle_neighbours(trial: Trial, count: int, seed: Any) -> Clutter:
    """The trial's object on its stand and ``count`` mixed neighbours, settled on the table around it."""
    rng = as_generator(seed, "seed")
    item, table = trial.item, table_around(trial.item)
    reach = TABLE_REACH
    pile = drop_pile(
        mixed_objects(as_count(count, "count"), rng, friction=FRICTION),
        [stand_of(item), *table],
        (-reach, -reach, reach, reach),
        seed=rng,
        placed=[item.body(FRICTION)],
    )
    return Clutter(pile.objects, table)


def neighbour_displacements(trajectory: Trajectory) -> np.ndarray:
    """(neighbours,) each neighbour's (objects 1, 2, ...) farthest distance [m] from its first sample's position."""
    positions = trajectory.object_position[:, 1:]
    return np.max(np.linalg.norm(positions - positions[:1], axis=2), axis=0)


def run_among_neighbours(
    trial: Trial, count: int, seed: Any, dt: float = DT, record_every: int = 40, duration: float | None = None
) -> dict:
    """The trial's record (:func:`~bhgrasp.bench.metrics.evaluate`) among ``count`` settled neighbours.

    It adds ``neighbours`` (their names), ``neighbour_moved`` (each one's farthest displacement [m]) and
    ``neighbours_disturbed`` (how many moved more than :data:`DISTURBED`).  ``duration`` [s] cuts the protocol short.
    """
    clutter = settle_neighbours(trial, count, seed)
    trajectory, hand = simulate_trial(trial, dt, record_every, duration, clutter)
    record = evaluate(trial, trajectory, hand)
    moved = neighbour_displacements(trajectory)
    record["neighbours"] = [item.name for item in clutter.objects[1:]]
    record["neighbour_moved"] = moved.tolist()
    record["neighbours_disturbed"] = int(np.sum(moved > DISTURBED))
    return record


__all__ = ["DISTURBED", "neighbour_displacements", "run_among_neighbours", "settle_neighbours"]
