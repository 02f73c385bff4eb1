"""Robustness of the SMC-adaptive grasp to what its controller does not know: a seeded Monte-Carlo table.

Each scenario of :data:`~bhgrasp.thesis.robustness_scenarios.SCENARIOS` adds one uncertainty of
:mod:`bhgrasp.scenarios.uncertainty` (sensor noise or delay, a slow late tracker, joint friction, a torque limit, a
wrong friction coefficient, with and without a friction margin and the pose estimated from the encoders), or
several, to the grasp demo (:func:`~bhgrasp.scenarios.grasp_demo.run_grasp_demo`: grasp, squeeze, lift 10 mm and
turn 0.1 rad about x).  Every scenario runs the same ``SAMPLES`` boxes, their masses drawn uniformly in
``MASS_RANGE`` (the controller starts at ``ESTIMATE``), with the same per-run noise seeds, on the sweep executor
(:func:`~bhgrasp.sweep.run_sweep`); same seed, same bits on any executor.

A run succeeds when the box ends within ``SUCCESS`` of its reference (true pose, not the sensed one) and no link
slid farther than ``SLIDE`` on it after the grasp closed (:func:`~bhgrasp.grasp.metrics.sliding_distances`); the
stricter count of runs with no contact sample at the Coulomb limit is kept beside it (``strict_success_pct``).  A
run that raises (e.g. the fingers never close) counts as a failure and is reported.  Success rates come with their
Wilson score interval (:func:`success_interval`).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from scipy.stats import norm

from bhgrasp.scenarios.rollouts import check_grasp_case, grasp_rollout
from bhgrasp.sweep import random_design, run_sweep
from bhgrasp.thesis.case import Case
from bhgrasp.thesis.robustness_notes import robustness_notes
from bhgrasp.thesis.robustness_scenarios import (
    CONFIDENCE,
    DURATION,
    ESTIMATE,
    MASS_RANGE,
    SAMPLES,
    SCENARIOS,
    SEED,
    SLIDE,
    SUCCESS,
)


def design(scenario: dict[str, Any], duration: float, samples: int = SAMPLES) -> list[dict[str, Any]]:
    """The scenario's runs: ``samples`` masses (one seeded design for every scenario) with its uncertainty."""
    masses = random_design(samples, SEED, mass=MASS_RANGE)
    return [{**case, "estimate": ESTIMATE, "duration": duration, **scenario} for case in masses]


def run_scenarios(
    duration: float = 3.0, executor: Any = None, scenarios: dict | None = None, samples: int = SAMPLES
) -> dict[str, Any]:
    """Every scenario's sweep (a pandas DataFrame each, one row per run), by key of :data:`SCENARIOS`."""
    chosen = SCENARIOS if scenarios is None else scenarios
    runs = {}
    for key, (_, parameters) in chosen.items():
        cases = design(parameters, duration, samples)
        runs[key] = run_sweep(grasp_rollout, cases, seed=SEED, executor=executor, check=check_grasp_case)
    return runs


def summarise(runs) -> dict[str, float]:
    """A scenario's figures: success [%], true final errors (mean, max) [mm, mrad], slip, force and mass errors.

    Also ``strict_success_pct`` (no contact sample at the Coulomb limit instead of the slide bound),
    ``lightest_failure_kg`` (the lightest box that failed) and ``unfinished_runs``: runs whose motion was still under
    way when the run ended (the grasp closed late).
    """
    done = runs[runs["status"] == "ok"] if "status" in runs else runs
    if len(done) == 0:  # every run raised: no metric columns
        names = (
            "mean_error_mm",
            "max_error_mm",
            "mean_rotation_mrad",
            "max_rotation_mrad",
            "mean_slip_events",
            "mean_slide_mm",
            "max_slide_mm",
            "mean_force_error_pct",
            "mean_mass_error_pct",
            "unfinished_runs",
        )
        low, high = success_interval(0, len(runs))
        return {
            "success_pct": 0.0,
            "success_low_pct": 100.0 * low,
            "success_high_pct": 100.0 * high,
            "strict_success_pct": 0.0,
            "lightest_failure_kg": _lightest(runs, runs.index[:0]),
            **_hold_torques(runs, runs.index[:0]),
            "failed_runs": float(len(runs)),
            **dict.fromkeys(names, float("nan")),
        }
    position = 1e3 * done["true_position_error"].to_numpy(dtype=float)
    rotation = 1e3 * done["true_rotation_error"].to_numpy(dtype=float)
    slip = done["slip_events"].to_numpy(dtype=float)
    slide = 1e3 * done["slide"].to_numpy(dtype=float)
    within = (position < 1e3 * SUCCESS[0]) & (rotation < 1e3 * SUCCESS[1])
    good = within & (slide <= 1e3 * SLIDE)
    mass_error = 100 * np.abs(done["mass_estimate"].to_numpy(dtype=float) / done["mass"].to_numpy(dtype=float) - 1)
    low, high = success_interval(int(np.sum(good)), len(runs))
    return {
        "success_pct": 100.0 * float(np.sum(good)) / len(runs),
        "success_low_pct": 100.0 * low,
        "success_high_pct": 100.0 * high,
        "failed_runs": float(len(runs) - len(done)),
        "mean_error_mm": _mean(position),
        "max_error_mm": _max(position),
        "mean_rotation_mrad": _mean(rotation),
        "max_rotation_mrad": _max(rotation),
        "mean_slip_events": _mean(slip),
        "mean_slide_mm": _mean(slide),
        "max_slide_mm": _max(slide),
        "strict_success_pct": 100.0 * float(np.sum(within & (slip == 0))) / len(runs),
        "lightest_failure_kg": _lightest(runs, done.index[good]),
        **_hold_torques(runs, done.index[good]),
        "mean_force_error_pct": _mean(100 * done["force_error"].to_numpy(float)),
        "mean_mass_error_pct": _mean(mass_error),
        "unfinished_runs": float(np.sum(done["motion_end"].to_numpy(float) > done["duration"].to_numpy(float))),
    }


def success_interval(successes: int, runs: int, confidence: float = CONFIDENCE) -> tuple[float, float]:
    """The Wilson score interval (fractions) of a success rate ``successes`` / ``runs`` at ``confidence``.

    (p + z^2 / 2n +- z sqrt(p (1 - p) / n + z^2 / 4n^2)) / (1 + z^2 / n), z the normal quantile; it stays in [0, 1]
    and is not empty at 0 or n successes (Wilson 1927; Brown, Cai & DasGupta 2001 recommend it for small n).
    """
    if runs <= 0:
        return float("nan"), float("nan")
    z = float(norm.ppf(0.5 + confidence / 2.0))
    p, n = successes / runs, float(runs)
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z * np.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    low = 0.0 if successes == 0 else max(0.0, centre - half)  # exact at the ends (round-off aside)
    high = 1.0 if successes == runs else min(1.0, centre + half)
    return float(low), float(high)


def _lightest(runs, succeeded) -> float:
    """The lightest box [kg] whose run failed (raised, or missed a bound); NaN if none did (or no masses).

    ``succeeded``: the index (of ``runs``) of the runs that succeeded.
    """
    if "mass" not in runs:
        return float("nan")
    failed = runs["mass"][~runs.index.isin(succeeded)].to_numpy(float)
    return float(np.min(failed)) if len(failed) else float("nan")


def _hold_torques(runs, succeeded) -> dict[str, float]:
    """The least peak joint torques [N m] the runs' final grasps need to hold their boxes at rest (NaN: none).

    ``hold_torque_success_max_nm``: the largest over the runs that succeeded, ``hold_torque_failure_min_nm`` the
    smallest over those that failed but ran, both inside the cones the controller commands;
    ``hold_torque_true_mu_max_nm``: the largest over every run that ran, inside the true friction's cones
    (:func:`~bhgrasp.scenarios.rollouts.final_hold_torque`; ``inf`` where the fingers let go).  Under a torque
    limit, also how many runs needed more than it (``over_torque_limit_runs``) and how many failed above it and
    within it (``over_torque_limit_failures``, ``within_torque_limit_failures``).
    """
    if "hold_torque" not in runs:
        return dict.fromkeys(HOLD_TORQUES, float("nan"))
    ran = (runs["status"] == "ok").to_numpy() if "status" in runs else np.ones(len(runs), dtype=bool)
    won = runs.index.isin(succeeded)
    need, true_mu = runs["hold_torque"].to_numpy(float), runs["hold_torque_true_mu"].to_numpy(float)
    figures = {
        "hold_torque_success_max_nm": _max(need[won]),
        "hold_torque_failure_min_nm": _min(need[ran & ~won]),
        "hold_torque_true_mu_max_nm": _max(true_mu[ran]),
    }
    if "torque_limit" in runs:
        over = ran & (need > runs["torque_limit"].to_numpy(float))
        figures["over_torque_limit_runs"] = float(np.sum(over))
        figures["over_torque_limit_failures"] = float(np.sum(over & ~won))
        figures["within_torque_limit_failures"] = float(np.sum(ran & ~over & ~won))
    return figures


HOLD_TORQUES = ("hold_torque_success_max_nm", "hold_torque_failure_min_nm", "hold_torque_true_mu_max_nm")


def _min(values: np.ndarray) -> float:
    return float(np.min(values)) if len(values) else float("nan")


def _mean(values: np.ndarray) -> float:
    return float(np.mean(values)) if len(values) else float("nan")


def _max(values: np.ndarray) -> float:
    return float(np.max(values)) if len(values) else float("nan")


def robustness(scale: float = 1.0, executor: Any = None):
    """The chapter-5 case: the Monte-Carlo table of :data:`SCENARIOS`.

    ``scale`` < 1 (a reduced run) shortens each run and runs that fraction of :data:`SAMPLES` (at least 2).
    """
    header = [
        "scenario",
        f"success [%] ({100 * CONFIDENCE:.0f} % interval)",
        "strict success [%]",
        "true final error mean / max [mm]",
        "rotation mean / max [mrad]",
        "slip samples (mean)",
        "farthest slide mean / max [mm]",
        "force error (mean) [%]",
        "mass estimate error (mean) [%]",
        "failed runs",
    ]
    case = Case("robustness", "Robustness: what the controller does not know (seeded Monte-Carlo)", "-", header)
    samples = SAMPLES if scale >= 1.0 else max(2, round(SAMPLES * scale))
    summaries = {}
    for key, frame in run_scenarios(DURATION * scale, executor, samples=samples).items():
        figures = summaries[key] = summarise(frame)
        case.table.append(
            [
                SCENARIOS[key][0],
                f"{figures['success_pct']:.0f} ({figures['success_low_pct']:.0f}-{figures['success_high_pct']:.0f})",
                f"{figures['strict_success_pct']:.0f}",
                f"{figures['mean_error_mm']:.3f} / {figures['max_error_mm']:.3f}",
                f"{figures['mean_rotation_mrad']:.2f} / {figures['max_rotation_mrad']:.2f}",
                f"{figures['mean_slip_events']:.1f}",
                f"{figures['mean_slide_mm']:.3f} / {figures['max_slide_mm']:.3f}",
                f"{figures['mean_force_error_pct']:.2f}",
                f"{figures['mean_mass_error_pct']:.2f}",
                f"{figures['failed_runs']:.0f}",
            ]
        )
        case.values.update({f"{key}/{name}": value for name, value in figures.items()})
    case.notes += robustness_notes(samples, DURATION * scale, summaries)
    return case


__all__ = ["design", "robustness", "run_scenarios", "success_interval", "summarise"]
