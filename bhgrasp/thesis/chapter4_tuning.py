"""Chapter 4's CMA-ES tuning of the discretised force impedance on F3 (Table 4.2, Figs 4.21-4.24).

:func:`tuning` runs CMA-ES over (log10 M_I, log10 K_I) inside :data:`TUNING_BOUNDS`, from the starts and seeds of
:func:`tuning_plan`, each run to cma's own convergence, on the fitness
:func:`~bhgrasp.scenarios.press_fitness.impedance_fitness`, and holds the optima out at F_d = 4, 6, 8 N;
:func:`fingertip_mass_range` is the range of F3's fingertip effective mass that argues the bounds.
"""

from __future__ import annotations

import functools
import os
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from bhgrasp.controllers.workspace import workspace_dynamics
from bhgrasp.errors import InputError
from bhgrasp.model.hand import Hand
from bhgrasp.parallel import call, executor_for, parallel_map
from bhgrasp.scenarios.press_fitness import (
    TUNING_BOUNDS,
    TUNING_SIGMA,
    TUNING_SPRING,
    TUNING_TOL_FUN,
    TUNING_TOL_X,
    cached_f3_setup,
    evaluate_press,
    impedance_fitness,
)
from bhgrasp.thesis.case import Case
from bhgrasp.thesis.chapter4_tuning_report import TuningRuns, held_out_table, runs_table, tuning_notes

TUNING_STARTS = ((0.5, 0.5), (5.0, 5.0), (0.01, 100.0))  # [M_I, K_I]: the thesis' two starts, and a light stiff one
TUNING_SEEDS = (1, 2)
TUNING_MAX_EVALUATIONS = 600  # per run at scale 1, cma's maxfevals: a safety cap (the runs converge before)

TABLE_HEADER = (
    "start [M_I, K_I]",
    "found [M_I, K_I]",
    "generations",
    "F_d [N]",
    "settling [s] untuned -> tuned",
    "overshoot % untuned -> tuned",
    "mean |error| [N] untuned -> tuned",
)  # Table 4.2's columns


def fingertip_mass_range(hand: Hand, finger: str, samples: int = 25) -> tuple[float, float]:
    """Smallest and largest eigenvalue [kg] of the fingertip's effective mass M_x over a grid of the finger's joints.

    The other joints stay at zero; configurations within 0.05 rad of the distal joint's stretched limit (singular)
    are skipped.
    """
    index = hand.finger_indices(finger)
    lower, upper = hand.lower[index], hand.upper[index]
    lower[-1] = max(lower[-1], 0.05)
    grids = np.meshgrid(*[np.linspace(lo, hi, samples) for lo, hi in zip(lower, upper)], indexing="ij")
    values: list[float] = []
    for angles in np.stack([g.ravel() for g in grids], axis=1):
        q = np.zeros(hand.nq)
        q[index] = angles
        try:
            values += list(np.linalg.eigvalsh(workspace_dynamics(hand, q, np.zeros(hand.nv), finger).mass))
        except InputError:
            continue
    return float(min(values)), float(max(values))


def tuning_plan(scale: float) -> tuple[list[tuple[tuple[float, float], int]], int]:
    """The (start, seed) runs and the per-run evaluation cap at ``scale``: runs ~ scale, cap ~ scale^2.

    Scale 1: every start with every seed (6 runs), 600 evaluations each at most; a smaller scale runs fewer of
    them (at least one) with a smaller cap (at least two generations), never none.
    """
    pairs = [(start, seed) for seed in TUNING_SEEDS for start in TUNING_STARTS]
    count = min(len(pairs), max(1, round(len(pairs) * scale)))
    return pairs[:count], max(12, round(TUNING_MAX_EVALUATIONS * scale**2))


def _workers(executor: Any) -> str:
    """Who evaluates on ``executor``, for the report."""
    if executor == "serial":
        return "this process"
    workers = getattr(executor, "_max_workers", None)  # concurrent.futures' pools
    return "the given executor" if workers is None else f"{workers} worker(s)"


def _search(pair: tuple[tuple[float, float], int], runner: Any, bounds: tuple, cap: int) -> tuple[Any, ...]:
    """One CMA-ES search from ``pair`` = (start, seed) within ``bounds`` (log10).

    Returns (start, clipped start, seed, result, wall time [s]).
    """
    from bhgrasp.tuning import cma_es

    (start, seed), began = pair, time.perf_counter()
    lower, upper = bounds
    x0 = np.clip(np.log10(start), lower, upper)
    result = cma_es(
        impedance_fitness,
        x0,
        TUNING_SIGMA,
        seed=seed,
        max_generations=100_000,
        bounds=(lower, upper),
        executor=runner,
        tol_fun=TUNING_TOL_FUN,
        tol_x=TUNING_TOL_X,
        max_evaluations=cap,
    )
    return start, 10.0**x0, seed, result, time.perf_counter() - began


def _held_out_calls(starts: list, best: dict, thesis: dict) -> list[tuple[Callable[..., Any], tuple[Any, ...]]]:
    """The held-out runs: the fitness at each start and at the thesis' optima, then each start's best.

    Each start's best untuned and tuned at F_d = 4, 6, 8 N.
    """
    calls: list[tuple[Callable[..., Any], tuple[Any, ...]]] = []
    calls += [(impedance_fitness, (np.log10(best[start][1]),)) for start in starts]
    calls += [(impedance_fitness, (np.log10(found),)) for found in thesis.values()]
    for start in starts:
        untuned, tuned = tuple(best[start][1]), tuple(10.0 ** best[start][3].best)
        for desired in (4.0, 6.0, 8.0):
            calls += [(evaluate_press, (untuned, desired)), (evaluate_press, (tuned, desired))]
    return calls


def tuning(scale: float = 1.0, executor: Any = None) -> Case:
    """Table 4.2, Figs 4.21-4.24: CMA-ES over (M_I, K_I) run to its own convergence from several starts and seeds.

    Every run searches (log10 M_I, log10 K_I) inside ``TUNING_BOUNDS`` and stops on cma's criteria (``tolfun``
    ``TUNING_TOL_FUN``, ``tolx`` ``TUNING_TOL_X`` and cma's defaults; :mod:`bhgrasp.scenarios.press_fitness`) or the
    safety cap of :func:`tuning_plan`; the found optima are then held out at F_d = 4, 6, 8 N.  ``executor`` (default:
    one process pool for all runs; ``"serial"``; or any Executor) evaluates the candidates; results do not depend on it.
    Unless serial, the runs go side by side (one thread each, all feeding the executor), so that no worker waits for the
    slowest candidate of a generation.
    """
    from concurrent.futures import ThreadPoolExecutor

    case = Case("tuning", "CMA-ES tuning of the discretised force impedance on F3 (Table 4.2, Figs 4.21-4.24)")
    case.header = list(TABLE_HEADER)
    pairs, cap = tuning_plan(scale)
    lower, upper = np.log10(TUNING_BOUNDS[0]), np.log10(TUNING_BOUNDS[1])
    starts = list(dict.fromkeys(start for start, _ in pairs))
    clock = time.perf_counter()

    search = functools.partial(_search, bounds=(lower, upper), cap=cap)
    with executor_for(executor, min(6, os.cpu_count() or 1)) as runner:
        if runner == "serial":
            runs = [search(pair, runner) for pair in pairs]
        else:
            threads = ThreadPoolExecutor(max_workers=len(pairs))
            try:
                searches = functools.partial(search, runner=runner)
                runs = [outcome.result() for outcome in parallel_map(searches, pairs, threads)]
            finally:  # on an error, shutting the pool down below ends the other searches
                threads.shutdown(wait=False, cancel_futures=True)
        searched = time.perf_counter() - clock
        best = {start: min((r for r in runs if r[0] == start), key=lambda r: r[3].best_fitness) for start in starts}
        thesis = {(0.5, 0.5): (0.0050, 4.7561), (5.0, 5.0): (0.0011, 3.1387)}
        calls = _held_out_calls(starts, best, thesis)
        outcomes = [outcome.result() for outcome in parallel_map(call, calls, runner)]
    wall = time.perf_counter() - clock
    held = outcomes[len(starts) + len(thesis) :]
    at_start = dict(zip(starts, outcomes[: len(starts)]))
    at_thesis = dict(zip(thesis, outcomes[len(starts) : len(starts) + len(thesis)]))
    report = TuningRuns(
        scale,
        pairs,
        cap,
        starts,
        runs,
        best,
        thesis,
        at_start,
        at_thesis,
        held,
        searched,
        wall,
        _workers(runner),
        runner == "serial",
    )
    held_out_table(case, report)
    found_all, fitness_all = runs_table(case, report)
    mass_range = fingertip_mass_range(cached_f3_setup(TUNING_SPRING).hand, "F3")
    case.notes += tuning_notes(report, found_all, fitness_all, mass_range)
    return case


__all__ = [
    "TUNING_MAX_EVALUATIONS",
    "TUNING_SEEDS",
    "TUNING_STARTS",
    "fingertip_mass_range",
    "tuning",
    "tuning_plan",
]
