"""Chapter 4's CMA-ES tuning of the discretised force impedance on F3 (Table 4.2, Figs 4.21-4.24).

:func:`tuning` runs CMA-ES over (log10 M_I, log10 K_I) inside :data:`TUNING_BOUNDS`, from the starts and seeds of
:func:`tuning_plan`, each run to cma's own convergence, on the fitness
:func:`~bhgrasp.scenarios.press_fitness.impedance_fitness`, and holds the optima out at F_d = 4, 6, 8 N;
:func:`fingertip_mass_range` is the range of F3's fingertip effective mass that argues the bounds.
"""

from __future__ import annotations

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
    TUNING_DURATION,
    TUNING_FORCE,
    TUNING_SPRING,
    _cached_f3_setup,
    _evaluate,
    impedance_fitness,
)
from bhgrasp.thesis.case import Case

TUNING_BOUNDS = ((1e-4, 0.1), (1.0, TUNING_SPRING))  # (lower, upper) of (M_I [kg], K_I [N/m]); argued in tuning()
TUNING_STARTS = ((0.5, 0.5), (5.0, 5.0), (0.01, 100.0))  # [M_I, K_I]: the thesis' two starts, and a light stiff one
TUNING_SEEDS = (1, 2)
TUNING_SIGMA = 0.5  # [decades] initial step size (thesis sigma = 0.5)
TUNING_TOL_FUN = 1e-4  # [N] cma tolfun: 0.1 mN of mean force error
TUNING_TOL_X = 1e-3  # [decades] cma tolx: 0.23 % of M_I and K_I
TUNING_MAX_EVALUATIONS = 600  # per run at scale 1, cma's maxfevals: a safety cap (the runs converge before)


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


def _pair(values: Any, spec: str = ".4g") -> str:
    return "[" + ", ".join(format(float(v), spec) for v in values) + "]"


def _span(values: Any, spec: str) -> str:
    return f"{format(min(values), spec)} to {format(max(values), spec)}"


def tuning(scale: float = 1.0, executor: Any = None) -> Case:
    """Table 4.2, Figs 4.21-4.24: CMA-ES over (M_I, K_I) run to its own convergence from several starts and seeds.

    Every run searches (log10 M_I, log10 K_I) inside :data:`TUNING_BOUNDS` and stops on cma's criteria
    (``tolfun`` :data:`TUNING_TOL_FUN`, ``tolx`` :data:`TUNING_TOL_X` and cma's defaults) or the safety cap of
    :func:`tuning_plan`; the found optima are then held out at F_d = 4, 6, 8 N.  ``executor`` (default: one process
    pool for all runs; ``"serial"``; or any Executor) evaluates the candidates; results do not depend on it.  Unless
    serial, the runs go side by side (one thread each, all feeding the executor), so that no worker waits for the
    slowest candidate of a generation.
    """
    from concurrent.futures import ThreadPoolExecutor

    from bhgrasp.tuning import cma_es

    case = Case("tuning", "CMA-ES tuning of the discretised force impedance on F3 (Table 4.2, Figs 4.21-4.24)")
    case.header = [
        "start [M_I, K_I]",
        "found [M_I, K_I]",
        "generations",
        "F_d [N]",
        "settling [s] untuned -> tuned",
        "overshoot % untuned -> tuned",
        "mean |error| [N] untuned -> tuned",
    ]
    pairs, cap = tuning_plan(scale)
    lower, upper = np.log10(TUNING_BOUNDS[0]), np.log10(TUNING_BOUNDS[1])
    starts = list(dict.fromkeys(start for start, _ in pairs))
    clock = time.perf_counter()

    def search(pair: tuple[tuple[float, float], int]) -> tuple[Any, ...]:
        (start, seed), began = pair, time.perf_counter()
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

    with executor_for(executor, min(6, os.cpu_count() or 1)) as runner:
        if runner == "serial":
            runs = [search(pair) for pair in pairs]
        else:
            threads = ThreadPoolExecutor(max_workers=len(pairs))
            try:
                runs = [outcome.result() for outcome in parallel_map(search, pairs, threads)]
            finally:  # on an error, shutting the pool down below ends the other searches
                threads.shutdown(wait=False, cancel_futures=True)
        searched = time.perf_counter() - clock
        best = {start: min((r for r in runs if r[0] == start), key=lambda r: r[3].best_fitness) for start in starts}
        thesis = {(0.5, 0.5): (0.0050, 4.7561), (5.0, 5.0): (0.0011, 3.1387)}
        calls: list[tuple[Callable[..., Any], tuple[Any, ...]]] = []
        calls += [(impedance_fitness, (np.log10(best[start][1]),)) for start in starts]
        calls += [(impedance_fitness, (np.log10(found),)) for found in thesis.values()]
        for start in starts:
            untuned, tuned = tuple(best[start][1]), tuple(10.0 ** best[start][3].best)
            for desired in (4.0, 6.0, 8.0):
                calls += [(_evaluate, (untuned, desired)), (_evaluate, (tuned, desired))]
        outcomes = [outcome.result() for outcome in parallel_map(call, calls, runner)]
    wall = time.perf_counter() - clock
    at_start = dict(zip(starts, outcomes[: len(starts)]))
    at_thesis = dict(zip(thesis, outcomes[len(starts) : len(starts) + len(thesis)]))
    held = iter(outcomes[len(starts) + len(thesis) :])

    for start in starts:  # Table 4.2: the best run from each start, held out at F_d = 4, 6, 8 N
        x0, result = best[start][1], best[start][3]
        label = _pair(start, "g") + ("" if np.allclose(x0, start) else f" (clipped to {_pair(x0, 'g')})")
        found = 10.0**result.best
        for desired in (4.0, 6.0, 8.0):
            before, after = next(held), next(held)
            case.table.append(
                [
                    label,
                    f"[{found[0]:.5f}, {found[1]:.4f}]",
                    str(result.generations),
                    f"{desired:g}",
                    f"{before[0].settling:.3f} -> {after[0].settling:.3f}",
                    f"{before[0].overshoot:.1f} -> {after[0].overshoot:.1f}",
                    f"{before[1]:.3f} -> {after[1]:.3f}",
                ]
            )
    case.table += [
        ["[0.5, 0.5] (thesis)", "[0.0050, 4.7561]", "~160 shown, 1000 run", "4, 6, 8", "~0.1", "~1", "-"],
        ["[5, 5] (thesis)", "[0.0011, 3.1387]", "1000 run", "4, 6, 8", "~0.1", "2 - 3", "-"],
    ]

    header = [
        "start [M_I, K_I], seed",
        "found M_I [kg]",
        "found K_I [N/m]",
        "fitness [N] start -> found",
        "generations",
        "evaluations",
        "cma stop()",
    ]
    rows: list[list[str]] = []
    for start, x0, seed, result, _ in runs:
        clipped = "" if np.allclose(x0, start) else f" (clipped to {_pair(x0, 'g')})"
        found = 10.0**result.best
        rows.append(
            [
                f"{_pair(start, 'g')}{clipped}, seed {seed}",
                f"{found[0]:.5f}",
                f"{found[1]:.4f}",
                f"{at_start[start]:.4f} -> {result.best_fitness:.5f}",
                str(result.generations),
                str(result.evaluations),
                str(dict(result.criteria)),
            ]
        )
        case.traces[f"from {_pair(start, 'g')}, seed {seed}"] = (
            np.arange(result.generations),
            result.generation_best,
            None,
        )
    found_all = np.array([10.0 ** r[3].best for r in runs])
    fitness_all = [r[3].best_fitness for r in runs]
    fired: dict[str, int] = {}
    for r in runs:
        for name in r[3].criteria:
            fired[name] = fired.get(name, 0) + 1
    rows.append(
        [
            f"spread over {len(runs)} run(s) (min to max)",
            _span(found_all[:, 0], ".5f"),
            _span(found_all[:, 1], ".4f"),
            _span(fitness_all, ".5f"),
            _span([r[3].generations for r in runs], "d"),
            _span([r[3].evaluations for r in runs], "d"),
            ", ".join(f"{k} x{v}" for k, v in sorted(fired.items())),
        ]
    )
    for start, found in thesis.items():
        rows.append(
            [
                f"thesis Table 4.2, from {_pair(start, 'g')}",
                f"{found[0]:.4f}",
                f"{found[1]:.4f}",
                f"our fitness at it: {at_thesis[start]:.4f}",
                "1000 run",
                "-",
                "-",
            ]
        )
    case.tables.append(
        (
            "Every CMA-ES run: the optimum, its fitness, and the criterion in cma's stop() dictionary that"
            " ended it; their spread; the thesis' optima under our fitness",
            header,
            rows,
        )
    )

    light, heavy = fingertip_mass_range(_cached_f3_setup(TUNING_SPRING).hand, "F3")
    spread = np.ptp(np.log10(found_all), axis=0)
    case.notes += [
        "Thesis: CMA-ES from [0.5, 0.5] and [5, 5] (sigma 0.5, lambda = 4 + 3 ln n, k_e = 500 N/m, 1000 iterations)"
        " found [0.0050, 4.7561] and [0.0011, 3.1387]; F_d = 4, 6, 8 N reached within ~0.1 s of contact, overshoot"
        " ~1 % and 2-3 %.",
        f"Protocol: search in (log10 M_I, log10 K_I), B_I critical for K_I + k_e (our reading of (4.16)/(4.19));"
        f" fitness (4.49) = mean |f_d - f| from first contact over a {TUNING_DURATION:g} s run (contact at ~0.36 s)"
        f" at F_d = {TUNING_FORCE:g} N, K_s = {TUNING_SPRING:g} N/m, the Tustin filter (4.48); sigma0"
        f" {TUNING_SIGMA:g} decades, population 6 (cma's default 4 + 3 ln 2, the thesis' lambda); each run stops on"
        f" cma's own criteria, tolfun {TUNING_TOL_FUN:g} N, tolx {TUNING_TOL_X:g} decades and cma's defaults"
        f" (tolstagnation, tolflatfitness, ...), with maxfevals {cap} as a safety cap (cma stops after the first"
        f" generation past it); the 'cma stop()' column is cma's stop() dictionary.  {len(runs)} run(s): starts"
        f" {', '.join(_pair(s, 'g') for s in starts)} x seeds"
        f" {', '.join(str(seed) for seed in dict.fromkeys(seed for _, seed in pairs))}"
        + ("" if scale == 1.0 else f" (scale {scale:g}: runs ~ scale, cap ~ scale^2)")
        + ".",
        f"Bounds (cma's `bounds`, in log10): M_I in [{TUNING_BOUNDS[0][0]:g}, {TUNING_BOUNDS[1][0]:g}] kg, K_I in"
        f" [{TUNING_BOUNDS[0][1]:g}, {TUNING_BOUNDS[1][1]:g}] N/m.  F3's fingertip effective mass M_x spans"
        f" {light:.3f} - {heavy:.3f} kg over its joint range (eigenvalues of J^-T M J^-1): an impedance mass of 1 kg,"
        " ten times the heaviest, is already an order of magnitude beyond anything the finger can present, so that is"
        " the upper bound (the thesis' second start [5, 5] is clipped onto it); K_I stays below the environment's"
        f" stiffness (K_s = {TUNING_SPRING:g} N/m), the impedance softer than what it touches.  The lower bounds only"
        " keep both positive in log coordinates; they sit far below the stability edge (M_I below ~0.0035 kg: the"
        " contact loop, sqrt((K_I + k_e) / M_I) above ~380 rad/s, rings through the inner loop and the force"
        " chatters, fitness ~f_d / 2 or worse), so the search sees that edge.",
        f"Spread of the optima over the runs: {spread[0]:.4f} decades in M_I, {spread[1]:.4f} in K_I; fitness"
        f" {_span(fitness_all, '.7f')} N: every start and seed finds the same minimum.  The thesis' optimum from"
        f" [0.5, 0.5] is a neighbour of ours (M_I {thesis[(0.5, 0.5)][0]:g} kg against"
        f" {found_all[int(np.argmin(fitness_all)), 0]:.4f}; our fitness there {at_thesis[(0.5, 0.5)]:.4f} N); its"
        f" optimum from [5, 5] lies beyond our finger's stability edge (fitness {at_thesis[(5.0, 5.0)]:.2f} N)."
        f"  Wall time: {searched:.0f} s for the {len(runs)} search(es)"
        f" ({sum(r[3].evaluations for r in runs)} simulations of {TUNING_DURATION:g} s;"
        f" {', '.join(f'{r[4]:.0f}' for r in runs)} s each{'' if runner == 'serial' else ', side by side'}),"
        f" {wall:.0f} s with the held-out runs, on {_workers(runner)}.",
    ]
    return case


__all__ = [
    "TUNING_BOUNDS",
    "TUNING_MAX_EVALUATIONS",
    "TUNING_SEEDS",
    "TUNING_SIGMA",
    "TUNING_STARTS",
    "TUNING_TOL_FUN",
    "TUNING_TOL_X",
    "fingertip_mass_range",
    "tuning",
    "tuning_plan",
]
