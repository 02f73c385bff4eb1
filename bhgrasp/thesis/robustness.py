"""Robustness of the SMC-adaptive grasp to what its controller does not know: a seeded Monte-Carlo table.

Each scenario of :data:`SCENARIOS` adds one uncertainty of :mod:`bhgrasp.scenarios.uncertainty` (sensor noise or
delay, joint friction, a torque limit, a wrong friction coefficient, with and without a friction margin), or all of
them, to the grasp demo
(:func:`~bhgrasp.scenarios.grasp_demo.run_grasp_demo`: grasp, squeeze, lift 10 mm and turn 0.1 rad about x).
Every scenario runs the same :data:`SAMPLES` boxes, their masses drawn uniformly in :data:`MASS_RANGE` (the
controller starts at :data:`ESTIMATE`), with the same per-run noise seeds, on the sweep executor
(:func:`~bhgrasp.sweep.run_sweep`); same seed, same bits on any executor.

A run succeeds when the box ends within :data:`SUCCESS` of its reference (true pose, not the sensed one) with no
sliding contact sample after the grasp closed (the target for motions).  A run that raises (e.g. the
fingers never close) counts as a failure and is reported.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from bhgrasp.scenarios.demo_result import MU_ASSUMED
from bhgrasp.scenarios.rollouts import check_grasp_case, grasp_rollout
from bhgrasp.sweep import random_design, run_sweep
from bhgrasp.thesis.case import Case

SAMPLES = 12  # runs per scenario
DURATION = 3.0  # [s] each run
MASS_RANGE = (0.2, 1.0)  # [kg] box masses, uniform
ESTIMATE = 0.5  # [kg] the controller's initial mass
SEED = 17  # the sweep's seed: the masses' design and every run's noise seed
SUCCESS = (0.5e-3, 5e-3)  # [m], [rad] true final error (with zero slip samples)
MARGIN = 0.3
"""The friction margin of the ``mu_margin`` scenario (GraspOptions.friction_margin): a true mu 20 % below the assumed
one needs a margin above 0.2 (at 0.2 the QP's cones are the true cone, nothing left for the force loop's error: 10
of 12 runs held); 0.3 leaves 12.5 % of the true cone.  Chosen on this table's 12 boxes, not tuned further.  Cones
alone are not enough: the QP at mu 0.4 without the grip reflex still let the heavier boxes slide at a true 0.48."""
ALL = {
    "pose_noise": (2e-4, 2e-3),
    "twist_noise": (2e-3, 2e-2),
    "force_noise": 0.1,
    "sensor_noise": (1e-4, 5e-3),
    "delay": 0.002,
    "joint_friction": 0.01,
    "joint_damping": 0.1,
    "torque_limit": 1.5,
    "friction": 0.6,
}
"""The combined scenario: each uncertainty at a level a real set-up has (a tracker of 0.2 mm / 2 mrad, a 2 ms bus,
friction a fifth of the hold torques, a true mu equal to the assumed one's)."""
SCENARIOS: dict[str, tuple[str, dict[str, Any]]] = {
    "exact": ("exact sensors and plant", {}),
    "pose_noise": ("object pose noise 0.5 mm / 5 mrad", {"pose_noise": (5e-4, 5e-3)}),
    "twist_noise": ("object twist noise 5 mm/s / 50 mrad/s", {"twist_noise": (5e-3, 5e-2)}),
    "force_noise": ("contact force noise 0.2 N", {"force_noise": 0.2}),
    "joint_noise": ("joint noise 1e-4 rad / 5e-3 rad/s", {"sensor_noise": (1e-4, 5e-3)}),
    "delay": ("measurement delay 5 ms", {"delay": 0.005}),
    "joint_friction": ("joint friction 0.02 N m + 0.1 N m s/rad", {"joint_friction": 0.02, "joint_damping": 0.1}),
    "torque_limit": ("joint torque limit 0.75 N m", {"torque_limit": 0.75}),
    "wrong_mu": (f"true mu 0.5 (assumed {MU_ASSUMED})", {"friction": 0.5}),
    "mu_margin": (
        f"true mu 0.48, 20 % below the assumed {MU_ASSUMED}, friction margin {100 * MARGIN:.0f} %",
        {"friction": 0.48, "friction_margin": MARGIN},
    ),
    "all": ("all at milder levels (see notes)", ALL),
}


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
    """A scenario's figures: success [%], true final errors (mean, max) [mm, mrad], slip, force and mass errors."""
    done = runs[runs["status"] == "ok"] if "status" in runs else runs
    if len(done) == 0:  # every run raised: no metric columns
        names = (
            "mean_error_mm",
            "max_error_mm",
            "mean_rotation_mrad",
            "max_rotation_mrad",
            "mean_slip_events",
            "mean_force_error_pct",
            "mean_mass_error_pct",
        )
        return {"success_pct": 0.0, "failed_runs": float(len(runs)), **dict.fromkeys(names, float("nan"))}
    position = 1e3 * done["true_position_error"].to_numpy(dtype=float)
    rotation = 1e3 * done["true_rotation_error"].to_numpy(dtype=float)
    slip = done["slip_events"].to_numpy(dtype=float)
    good = (position < 1e3 * SUCCESS[0]) & (rotation < 1e3 * SUCCESS[1]) & (slip == 0)
    mass_error = 100 * np.abs(done["mass_estimate"].to_numpy(dtype=float) / done["mass"].to_numpy(dtype=float) - 1)
    return {
        "success_pct": 100.0 * float(np.sum(good)) / len(runs),
        "failed_runs": float(len(runs) - len(done)),
        "mean_error_mm": _mean(position),
        "max_error_mm": _max(position),
        "mean_rotation_mrad": _mean(rotation),
        "max_rotation_mrad": _max(rotation),
        "mean_slip_events": _mean(slip),
        "mean_force_error_pct": _mean(100 * done["force_error"].to_numpy(float)),
        "mean_mass_error_pct": _mean(mass_error),
    }


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
        "success [%]",
        "true final error mean / max [mm]",
        "rotation mean / max [mrad]",
        "slip samples (mean)",
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
                f"{figures['success_pct']:.0f}",
                f"{figures['mean_error_mm']:.3f} / {figures['max_error_mm']:.3f}",
                f"{figures['mean_rotation_mrad']:.2f} / {figures['max_rotation_mrad']:.2f}",
                f"{figures['mean_slip_events']:.1f}",
                f"{figures['mean_force_error_pct']:.2f}",
                f"{figures['mean_mass_error_pct']:.2f}",
                f"{figures['failed_runs']:.0f}",
            ]
        )
        case.values.update({f"{key}/{name}": value for name, value in figures.items()})
    low, high = MASS_RANGE
    case.notes += [
        f"{samples} runs per scenario: box masses uniform in {low}-{high} kg (one seeded design, seed {SEED}, the same "
        f"boxes and noise seeds in every scenario), the controller starting at {ESTIMATE} kg; SMC-adaptive law, QP "
        f"forces (mu {MU_ASSUMED} assumed, 0.8 true unless the scenario says).  Module "
        "`bhgrasp.thesis.robustness`.",
        f"Success: the true final pose within {1e3 * SUCCESS[0]:g} mm and {1e3 * SUCCESS[1]:g} mrad of the "
        "requested one and no sliding contact sample after the grasp closed.  Errors are the object's true pose "
        "against the requested motion, not what the sensors report; force error: largest |measured - commanded| / "
        "commanded normal force over the fingers 0.5 s after the move (true forces).",
        "Noise is Gaussian, independent per reading and control step (1 ms): pose on the object's position and "
        "rotation vector, twist on its linear and angular velocity, force on each contact force component, joint "
        "on the encoders; the delay makes every reading that much older.  Friction and the torque limit act on "
        "every joint of the simulated hand; the controller's model has neither.",
        "The combined scenario: pose 0.2 mm / 2 mrad, twist 2 mm/s / 20 mrad/s, force 0.1 N, joints 1e-4 rad / "
        "5e-3 rad/s, delay 2 ms, joint friction 0.01 N m + 0.1 N m s/rad, torque limit 1.5 N m, true mu 0.6.",
        *limits(summaries),
    ]
    return case


def limits(summaries: dict[str, dict[str, float]]) -> list[str]:
    """What the table shows the controller is sensitive to, in words with the table's numbers."""
    lines = []
    pose, friction, mu = (summaries.get(key) for key in ("pose_noise", "joint_friction", "wrong_mu"))
    others = [
        summaries[key]["mean_error_mm"]
        for key in ("twist_noise", "force_noise", "joint_noise", "delay")
        if key in summaries
    ]
    if pose is not None and others:
        lines.append(
            f"Object pose noise reaches the contact forces through the object-space feedback (force error "
            f"{pose['mean_force_error_pct']:.1f} % on average, {pose['mean_slip_events']:.0f} sliding samples per "
            f"run), where noise on the twist, the contact forces or the encoders and a delay leave the mean pose "
            f"error at or below {max(others):.3f} mm."
        )
    if friction is not None:
        lines.append(
            f"Joint friction, absent from the controller's model, is learnt as object mass (mass estimate "
            f"{friction['mean_mass_error_pct']:.0f} % off on average) while the pose error stays at "
            f"{friction['mean_error_mm']:.2f} mm: the adaptive law fits the parameters it has, not the true ones."
        )
    if mu is not None:
        lines.append(
            f"A true mu below the assumed one leaves no friction in reserve when the box leaves its pedestal and "
            f"the fingers meet a load the mass estimate does not yet know: the heavier boxes slide "
            f"({mu['mean_slip_events']:.0f} sliding samples per run, rotation errors up to "
            f"{mu['max_rotation_mrad']:.0f} mrad); cones below the true mu alone do not prevent it "
            "(bhgrasp.thesis.robustness.MARGIN)."
        )
    margin = summaries.get("mu_margin")
    if margin is not None:
        lines.append(
            f"With a friction margin (GraspOptions.friction_margin = {MARGIN:g}: the QP's cones at "
            f"{1 - MARGIN:g} mu and each contact's normal force raised to its measured tangential load / "
            f"({1 - MARGIN:g} mu)) a true mu 20 % below the assumed one holds in {margin['success_pct']:.0f} % of the "
            f"runs ({margin['mean_slip_events']:.1f} sliding samples per run)."
        )
    return lines


__all__ = [
    "ALL",
    "ESTIMATE",
    "MARGIN",
    "MASS_RANGE",
    "SAMPLES",
    "SCENARIOS",
    "SEED",
    "SUCCESS",
    "design",
    "limits",
    "robustness",
    "run_scenarios",
    "summarise",
]
