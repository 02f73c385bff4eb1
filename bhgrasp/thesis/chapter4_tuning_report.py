"""The tables and notes of chapter 4's CMA-ES tuning (Table 4.2), from what the tuning ran.

The tuning itself: :func:`~bhgrasp.thesis.chapter4_tuning.tuning`.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any

import numpy as np

from bhgrasp.scenarios.press_fitness import (
    TUNING_BOUNDS,
    TUNING_DURATION,
    TUNING_FORCE,
    TUNING_SIGMA,
    TUNING_SPRING,
    TUNING_TOL_FUN,
    TUNING_TOL_X,
)
from bhgrasp.thesis.case import Case

RUNS_HEADER = [
    "start [M_I, K_I], seed",
    "found M_I [kg]",
    "found K_I [N/m]",
    "fitness [N] start -> found",
    "generations",
    "evaluations",
    "cma stop()",
]  # the table of every run


@dataclass
class TuningRuns:
    """What the tuning ran, for its report.

    Its plan, every search (start, clipped start, seed, result, wall time [s]), the best per start, the thesis'
    optima, the fitness at the starts and at the thesis' optima, the held-out runs (untuned then tuned, per start
    and F_d) and the wall times [s].
    """

    scale: float
    pairs: list[tuple[tuple[float, float], int]]
    cap: int
    starts: list[tuple[float, float]]
    runs: list[tuple[Any, ...]]
    best: dict[tuple[float, float], tuple[Any, ...]]
    thesis: dict[tuple[float, float], tuple[float, float]]
    at_start: dict[tuple[float, float], float]
    at_thesis: dict[tuple[float, float], float]
    held: list[Any]
    searched: float
    wall: float
    workers: str
    serial: bool


def bracketed(values: Any, spec: str = ".4g") -> str:
    """``[a, b]`` of ``values`` formatted with ``spec``."""
    return "[" + ", ".join(format(float(v), spec) for v in values) + "]"


def span_text(values: Any, spec: str) -> str:
    """``min to max`` of ``values`` formatted with ``spec``."""
    return f"{format(min(values), spec)} to {format(max(values), spec)}"


def held_out_table(case: Case, r: TuningRuns) -> None:
    """Table 4.2: the best run from each start, held out at F_d = 4, 6, 8 N, then the thesis' rows."""
    held: Iterator[Any] = iter(r.held)
    for start in r.starts:
        x0, result = r.best[start][1], r.best[start][3]
        label = bracketed(start, "g") + ("" if np.allclose(x0, start) else f" (clipped to {bracketed(x0, 'g')})")
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


def runs_table(case: Case, r: TuningRuns) -> tuple[np.ndarray, list[float]]:
    """Every run's optimum, fitness and stop criterion, their spread and the thesis' optima under our fitness.

    A table and one trace per run; returns the optima (M_I, K_I) and their fitness values.
    """
    rows: list[list[str]] = []
    for start, x0, seed, result, _ in r.runs:
        clipped = "" if np.allclose(x0, start) else f" (clipped to {bracketed(x0, 'g')})"
        found = 10.0**result.best
        rows.append(
            [
                f"{bracketed(start, 'g')}{clipped}, seed {seed}",
                f"{found[0]:.5f}",
                f"{found[1]:.4f}",
                f"{r.at_start[start]:.4f} -> {result.best_fitness:.5f}",
                str(result.generations),
                str(result.evaluations),
                str(dict(result.criteria)),
            ]
        )
        case.traces[f"from {bracketed(start, 'g')}, seed {seed}"] = (
            np.arange(result.generations),
            result.generation_best,
            None,
        )
    found_all = np.array([10.0 ** run[3].best for run in r.runs])
    fitness_all = [run[3].best_fitness for run in r.runs]
    rows += _summary_rows(r, found_all, fitness_all)
    case.tables.append(
        (
            "Every CMA-ES run: the optimum, its fitness, and the criterion in cma's stop() dictionary that"
            " ended it; their spread; the thesis' optima under our fitness",
            RUNS_HEADER,
            rows,
        )
    )
    return found_all, fitness_all


def _summary_rows(r: TuningRuns, found_all: np.ndarray, fitness_all: list[float]) -> list[list[str]]:
    """The runs' spread (min to max) and the thesis' optima under our fitness."""
    rows: list[list[str]] = []
    fired: dict[str, int] = {}
    for run in r.runs:
        for name in run[3].criteria:
            fired[name] = fired.get(name, 0) + 1
    rows.append(
        [
            f"spread over {len(r.runs)} run(s) (min to max)",
            span_text(found_all[:, 0], ".5f"),
            span_text(found_all[:, 1], ".4f"),
            span_text(fitness_all, ".5f"),
            span_text([run[3].generations for run in r.runs], "d"),
            span_text([run[3].evaluations for run in r.runs], "d"),
            ", ".join(f"{k} x{v}" for k, v in sorted(fired.items())),
        ]
    )
    for start, found in r.thesis.items():
        rows.append(
            [
                f"thesis Table 4.2, from {bracketed(start, 'g')}",
                f"{found[0]:.4f}",
                f"{found[1]:.4f}",
                f"our fitness at it: {r.at_thesis[start]:.4f}",
                "1000 run",
                "-",
                "-",
            ]
        )
    return rows


def tuning_notes(
    r: TuningRuns, found_all: np.ndarray, fitness_all: list[float], mass_range: tuple[float, float]
) -> list[str]:
    """The notes: the thesis' protocol and ours, the bounds, the spread of the optima and the wall times.

    ``mass_range``: F3's fingertip effective mass range [kg], which argues the bounds.
    """
    light, heavy = mass_range
    spread = np.ptp(np.log10(found_all), axis=0)
    return [
        "Thesis: CMA-ES from [0.5, 0.5] and [5, 5] (sigma 0.5, lambda = 4 + 3 ln n, k_e = 500 N/m, 1000 iterations)"
        " found [0.0050, 4.7561] and [0.0011, 3.1387]; F_d = 4, 6, 8 N reached within ~0.1 s of contact, overshoot"
        " ~1 % and 2-3 %.",
        f"Protocol: search in (log10 M_I, log10 K_I), B_I critical for K_I + k_e (our reading of (4.16)/(4.19));"
        f" fitness (4.49) = mean |f_d - f| from first contact over a {TUNING_DURATION:g} s run (contact at ~0.36 s)"
        f" at F_d = {TUNING_FORCE:g} N, K_s = {TUNING_SPRING:g} N/m, the Tustin filter (4.48); sigma0"
        f" {TUNING_SIGMA:g} decades, population 6 (cma's default 4 + 3 ln 2, the thesis' lambda); each run stops on"
        f" cma's own criteria, tolfun {TUNING_TOL_FUN:g} N, tolx {TUNING_TOL_X:g} decades and cma's defaults"
        f" (tolstagnation, tolflatfitness, ...), with maxfevals {r.cap} as a safety cap (cma stops after the first"
        f" generation past it); the 'cma stop()' column is cma's stop() dictionary.  {len(r.runs)} run(s): starts"
        f" {', '.join(bracketed(s, 'g') for s in r.starts)} x seeds"
        f" {', '.join(str(seed) for seed in dict.fromkeys(seed for _, seed in r.pairs))}"
        + ("" if r.scale == 1.0 else f" (scale {r.scale:g}: runs ~ scale, cap ~ scale^2)")
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
        f" {span_text(fitness_all, '.7f')} N: every start and seed finds the same minimum.  The thesis' optimum from"
        f" [0.5, 0.5] is a neighbour of ours (M_I {r.thesis[(0.5, 0.5)][0]:g} kg against"
        f" {found_all[int(np.argmin(fitness_all)), 0]:.4f}; our fitness there {r.at_thesis[(0.5, 0.5)]:.4f} N); its"
        f" optimum from [5, 5] lies beyond our finger's stability edge (fitness {r.at_thesis[(5.0, 5.0)]:.2f} N)."
        f"  Wall time: {r.searched:.0f} s for the {len(r.runs)} search(es)"
        f" ({sum(run[3].evaluations for run in r.runs)} simulations of {TUNING_DURATION:g} s;"
        f" {', '.join(f'{run[4]:.0f}' for run in r.runs)} s each{'' if r.serial else ', side by side'}),"
        f" {r.wall:.0f} s with the held-out runs, on {r.workers}.",
    ]


__all__ = ["TuningRuns", "bracketed", "held_out_table", "runs_table", "span_text", "tuning_notes"]
