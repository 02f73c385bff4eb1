"""A benchmark trial among neighbours: mixed objects settled on a table around the object's stand, then the trial.

:func:`settle_neighbours` drops ``count`` objects of :func:`~bhgrasp.scenarios.clutter.mixed_objects` (seeded) over
the table of :func:`~bhgrasp.bench.table.table_around`, clear of the trial's object on its stand, and lets all of
them settle (:func:`~bhgrasp.scenarios.clutter.drop_pile`); :func:`run_among_neighbours` runs the trial's protocol
from there and adds to its record how far each neighbour was moved (:func:`neighbour_displacements`) and how many
were disturbed, moved more than :data:`~bhgrasp.bench.protocol.DISTURBED`.  The trial's own success is scored as alone
(:func:`~bhgrasp.bench.metrics.evaluate`).
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np

from bhgrasp._validation import as_generator, as_int
from bhgrasp.bench.heading import clearest_heading
from bhgrasp.bench.height import TABLE_REACH
from bhgrasp.bench.metrics import evaluate
from bhgrasp.bench.protocol import APPROACH, DISTURBED, DT, FRICTION, STAND, Trial
from bhgrasp.bench.table import Clutter, floor_below, stand_of, table_around
from bhgrasp.bench.trial import contact_law, setup, simulate_trial
from bhgrasp.data import Trajectory
from bhgrasp.errors import InputError, UnreachableError
from bhgrasp.model.hand import Hand
from bhgrasp.scenarios.clutter import drop_pile, mixed_objects

RAISE, HIGHEST = 0.01, 0.3  # [m] the open hand's start rises in these steps, at most this far above the grasp


def settle_neighbours(trial: Trial, count: int, seed: Any, dt: float = DT) -> Clutter:
    """The trial's object on its stand and ``count`` mixed neighbours, settled on the table around it.

    Settled under the trial's own contact law and step, so that the trial starts from rest.  The hand turns about
    the object's axis away from the neighbours (:func:`~bhgrasp.bench.heading.clearest_heading`).  The open hand starts
    :data:`~bhgrasp.bench.protocol.APPROACH` above its grasp, or higher, in :data:`RAISE` steps, until it touches no
    neighbour (:attr:`~bhgrasp.bench.table.Clutter.approach`); it still comes down in the protocol's
    :data:`~bhgrasp.bench.protocol.CLOSE_AT`, so faster the higher it starts (0.08 m/s on average from 8 cm, against
    0.05 m/s alone).  The trial stands flush with the table (``Trial.table`` is set here).

    Raises:
        UnreachableError: The open hand would start inside the table or the stand (a low object), or no start up
            to :data:`HIGHEST` clears the neighbours.
    """
    rng = as_generator(seed, "seed")
    trial = dataclasses.replace(trial, table=True)
    item, table = trial.item, (*table_around(trial.item), floor_below())
    objects = mixed_objects(as_int(count, "count", 1), rng, friction=FRICTION)
    region = (-TABLE_REACH, -TABLE_REACH, TABLE_REACH, TABLE_REACH)
    environment = [stand_of(item), *table]
    pile = drop_pile(objects, environment, region, seed=rng, placed=[item.body(FRICTION)], dt=dt, contact=contact_law())
    heading, _ = clearest_heading(trial, pile.objects[1:])
    return raised(trial, Clutter(pile.objects, table, APPROACH, heading), dt)


def raised(trial: Trial, clutter: Clutter, dt: float = DT) -> Clutter:
    """``clutter`` with the open hand's start raised from its ``approach`` in :data:`RAISE` steps to touch no neighbour.

    Raises:
        InputError: A start above :data:`HIGHEST`.
        UnreachableError: As :func:`settle_neighbours`.
    """
    if clutter.approach > HIGHEST:
        raise InputError(f"the open hand starts at most {HIGHEST} m above its grasp, got approach {clutter.approach!r}")
    fixed = {STAND, *(part.name for part in clutter.table)}
    names = {item.name for item in clutter.objects[1:]}
    touched: list[tuple[str, str]] = []
    for approach in np.arange(clutter.approach, HIGHEST + 1e-9, RAISE):
        start = dataclasses.replace(clutter, approach=round(float(approach), 6))
        simulator, state, hand, _ = setup(trial, dt, start, start_check="off")
        links = {frame.name for frame in hand.model.frames}
        below = [p for p in simulator.check_start(state) if fixed & set(p.bodies) and links & set(p.bodies)]
        if below:
            raise UnreachableError(f"no trial among neighbours: the open hand starts {below[0].message}")
        touched = [(a, b) for a, b in state.contact_bodies if {a, b} & links and {a, b} & names]
        if not touched:  # the open hand touches no neighbour at its start
            return start
    raise UnreachableError(
        f"no trial among neighbours: {HIGHEST:.2f} m above its grasp the open hand still touches {touched[0]}"
    )


def peak_force_on(trajectory: Trajectory, hand: Hand, names: list[str]) -> float:
    """The hand's peak contact force [N] on the bodies ``names`` (a hand link body a, a named body b)."""
    links = {frame.name for frame in hand.model.frames}
    bodies = trajectory.pair_bodies[trajectory.contact_pair]
    on = np.array([a in links and b in names for a, b in bodies], dtype=bool)
    return float((np.linalg.norm(trajectory.contact_force, axis=1) * on).max(initial=0.0))


def neighbour_displacements(trajectory: Trajectory) -> np.ndarray:
    """(neighbours,) each neighbour's (objects 1, 2, ...) farthest distance [m] from its first sample's position."""
    positions = trajectory.object_position[:, 1:]
    return np.max(np.linalg.norm(positions - positions[:1], axis=2), axis=0)


def run_among_neighbours(
    trial: Trial, count: int, seed: Any, dt: float = DT, record_every: int = 40, duration: float | None = None
) -> dict:
    """The trial's record (:func:`~bhgrasp.bench.metrics.evaluate`) among ``count`` settled neighbours.

    The trial stands flush with the table (``Trial.table``: the height rule keeps the fingers off all of it).  The
    record adds ``neighbours`` (their names), ``heading`` (the hand's turn about the object's axis [rad]),
    ``peak_neighbour_force`` (the hand's peak contact force on any of them [N]: against
    :data:`~bhgrasp.bench.protocol.FORCE_LIMIT` it says whether the hand stayed in its envelope there too),
    ``neighbour_moved`` (each one's farthest displacement [m]) and ``neighbours_disturbed`` (how many moved more than
    :data:`DISTURBED`).  ``duration`` [s] cuts the protocol short.

    Raises:
        UnreachableError: As :func:`settle_neighbours` (the benchmark counts the trial failed with its message).
    """
    trial = dataclasses.replace(trial, table=True)  # the height rule keeps the fingers off the whole table
    clutter = settle_neighbours(trial, count, seed, dt)
    trajectory, hand = simulate_trial(trial, dt, record_every, duration, clutter)
    record = evaluate(trial, trajectory, hand, clutter.heading)
    moved = neighbour_displacements(trajectory)
    names = [item.name for item in clutter.objects[1:]]
    record["neighbours"] = names
    record["heading"] = clutter.heading
    record["peak_neighbour_force"] = peak_force_on(trajectory, hand, names)
    record["neighbour_moved"] = moved.tolist()
    record["neighbours_disturbed"] = int(np.sum(moved > DISTURBED))
    return record


__all__ = [
    "HIGHEST",
    "RAISE",
    "neighbour_displacements",
    "peak_force_on",
    "raised",
    "run_among_neighbours",
    "settle_neighbours",
]
