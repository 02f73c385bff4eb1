"""Chapter 3's sliding-mode cases: SMC / ASMC on the planar finger and the BH8-280, HOSM / HOSMA on F3.

Each a :class:`~bhgrasp.thesis.case.Case` with its error table (:func:`add_run` files a run under its name).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from bhgrasp import metrics
from bhgrasp.model.barrett_hand import BarrettHand
from bhgrasp.model.planar import thesis_two_link_finger
from bhgrasp.motion.trajectories import Sinusoid, SmoothStep
from bhgrasp.scenarios.joint_tracking import (
    MASS_ERROR,
    SLIDING,
    Run,
    controller,
    f3_case,
    simulate,
)
from bhgrasp.thesis.case import Case


def add_run(case: Case, run: Run) -> None:
    """Add ``run`` to ``case.runs``, under its name (and "(noise)" when its sensors were noisy)."""
    case.runs[f"{run.name} (noise)" if run.noise else run.name] = run


def _sliding_table(case: Case, runs: list[Run], scale_of: Callable[[Run], np.ndarray | None] = lambda r: None):
    case.header = ["controller", "noise", "joint", "max error %", "RMS error %", "final error %", "chattering [N m/s]"]
    for run in runs:
        error = run.tracking(scale_of(run))
        chatter = run.chattering()
        for k, label in enumerate(run.labels):
            final = 100 * error.final_abs[k] / _scale(error, k)
            case.table.append(
                [
                    run.name,
                    "yes" if run.noise else "no",
                    label,
                    f"{error.max_percent[k]:.3f}",
                    f"{error.rms_percent[k]:.3f}",
                    f"{final:.4f}",
                    f"{chatter[k]:.3g}",
                ]
            )
            key = f"{'noise' if run.noise else 'clean'}/{run.name}/{label.replace(' ', '_')}"
            case.values.update(
                {
                    f"{key}/max_error_pct": error.max_percent[k],
                    f"{key}/rms_error_pct": error.rms_percent[k],
                    f"{key}/final_error_pct": final,
                    f"{key}/chattering_Nm_per_s": chatter[k],
                }
            )


def _scale(error: metrics.TrackingError, k: int) -> float:
    return float(error.max_abs[k] / error.max_percent[k] * 100.0) if error.max_percent[k] > 0 else np.nan


def planar_sinusoid(scale: float = 1.0) -> Case:
    """Table 3.2 and Figs 3.12-3.16, 3.26-3.28: SMC, ASMC, HOSM-A, HOSMA-A on the 2-link planar finger."""
    plant = thesis_two_link_finger()
    nominal = plant.perturbed(1.0 - MASS_ERROR)
    case = Case("planar", "SMC, ASMC, HOSM and HOSMA on the planar finger, sinusoid (Table 3.2, Figs 3.12-3.28)")
    centre = np.array([-0.6, 0.9])
    reference = Sinusoid(centre, np.array([0.5, 0.4]), 0.5)
    duration = 4.0 * scale
    for noise in (False, True):
        for name in ("SMC", "ASMC", "HOSM-A", "HOSMA-A"):
            traj = simulate(plant, lambda n=name: controller(n, nominal, reference, duration), centre, duration, noise)
            add_run(case, Run(name, noise, traj, (0, 1), ("q1", "q2")))
    _sliding_table(case, list(case.runs.values()))
    case.notes += [
        "Thesis (Table 3.2): SMC e_q1 0.1-0.5 %, e_q2 2-5 %; ASMC e_q1 0.01-0.05 %, e_q2 0.05-0.5 %; Fig 3.26: max"
        " error SMC ~4 %, HOSM ~1.1 %, HOSMA ~1 %; with noise HOSMA q1 3 %, q2 2 %.",
        "Percentages are of the reference's range (2 x amplitude).  The finger is the thesis' planar 2-link finger"
        " (l = 0.05/0.05 m, m = 0.0579/0.0342 kg point masses) with a nominal model 30 % too light; the reference is"
        " q_d = (-0.6, 0.9) + (0.5, 0.4) sin(pi t) rad (the thesis gives no amplitude or frequency).",
    ]
    return case


def barrett_smc_asmc(scale: float = 1.0) -> Case:
    """Figs 3.17-3.23: SMC vs ASMC on the whole Barrett hand (spread 25 deg, q2 = 25 deg, q3 = 35 deg)."""
    plant = BarrettHand()
    nominal = plant.perturbed(1.0 - MASS_ERROR)
    case = Case("barrett", "SMC vs ASMC on the Barrett hand (Figs 3.17-3.23)")
    q0 = plant.neutral()
    qf = q0.copy()
    for finger in plant.fingers:
        qf[plant.joint_index(f"{finger}_proximal")] = np.radians(25.0)
        qf[plant.joint_index(f"{finger}_distal")] = np.radians(35.0)
    qf[[plant.joint_index("F1_spread"), plant.joint_index("F2_spread")]] = np.radians(25.0)
    reference = SmoothStep(q0, qf, 0.3)
    duration = 3.0 * scale
    for name in ("SMC", "ASMC"):
        traj = simulate(plant, lambda n=name: controller(n, nominal, reference, duration), q0, duration, False)
        add_run(case, Run(name, False, traj, tuple(range(plant.nv)), plant.joint_names))
    case.header = ["controller", "joint", "overshoot %", "settling 2 % [s]", "RMS error %", "chattering [N m/s]"]
    for run in case.runs.values():
        response = metrics.step_response(run.trajectory.t, run.trajectory.q, qf, start=q0)
        error, chatter = run.tracking(), run.chattering()
        for k, label in enumerate(run.labels):
            case.table.append(
                [
                    run.name,
                    label,
                    f"{response.overshoot_percent[k]:.2f}",
                    f"{response.settling_time[k]:.2f}",
                    f"{error.rms_percent[k]:.3f}",
                    f"{chatter[k]:.3g}",
                ]
            )
            case.values.update(
                {
                    f"{run.name}/{label}/overshoot_pct": response.overshoot_percent[k],
                    f"{run.name}/{label}/settling_s": response.settling_time[k],
                    f"{run.name}/{label}/rms_error_pct": error.rms_percent[k],
                    f"{run.name}/{label}/chattering_Nm_per_s": chatter[k],
                }
            )
    case.notes += [
        "Thesis: SMC overshoot 5-15 %, ASMC 1-8 %, settling within 2 s.  Reference: smooth step (5.36), a = 0.3 s;"
        " nominal model 30 % too light; lambda = 17 as the thesis.",
    ]
    return case


def f3_hosm(scale: float = 1.0) -> Case:
    """Table 3.3 and Figs 3.29-3.37: HOSM and HOSMA A, B, C on finger F3, with and without noise (plus CTC/SMC/ASMC)."""
    hand = BarrettHand()
    case = Case(
        "f3",
        "HOSM and HOSMA A, B, C on finger F3, with and without noise (Table 3.3, Fig 3.34)",
        figure_title="Finger F3, nominal model 30 % too light: CTC, SMC, ASMC, HOSM and HOSMA A, B, C "
        "(Table 3.3, Fig 3.34)",
        figure_groups=(("CTC", "SMC", "ASMC"), SLIDING[2::2], SLIDING[3::2]),
    )
    for noise in (False, True):
        for name in ("CTC", *SLIDING):
            add_run(case, f3_case(name, noise, 3.0 * scale, hand))
    _sliding_table(case, list(case.runs.values()))
    rms, chatter = uncertainty_ranking(case)
    for name in rms:
        case.values[f"noise/{name}/mean_rms_error_pct"] = rms[name]
        case.values[f"noise/{name}/chattering_relative_to_SMC"] = chatter[name] / chatter["SMC"]
    case.notes += [
        "Thesis (Table 3.3): HOSM e_max 8 % with noise, 5 % without, e_min 1-2 %; HOSMA ~4.5 % either way, e_min"
        " 0.5-1.5 %; abstract: SMC 15 %, HOSM 8 %, HOSMA 5 %.  Our 'final error' is the thesis' e_min analogue.",
        "Reference: quintic rest-to-rest in 1.5 s from (2.9, 2.9) deg to (45, 15) deg, lambda = 8 (thesis); errors are"
        " % of the step.",
    ]
    return case


def uncertainty_ranking(f3: Case) -> tuple[dict[str, float], dict[str, float]]:
    """Per controller of the F3 case's noisy runs: mean RMS error [% of step] and chattering [N m/s] of q2, q3."""
    noisy = {run.name: run for run in f3.runs.values() if run.noise}
    rms = {name: float(np.mean(run.tracking().rms_percent)) for name, run in noisy.items()}
    chatter = {name: float(np.mean(run.chattering())) for name, run in noisy.items()}
    return rms, chatter


__all__ = ["add_run", "barrett_smc_asmc", "f3_hosm", "planar_sinusoid", "uncertainty_ranking"]
