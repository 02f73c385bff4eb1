"""Thesis chapter 3 reproduced: computed torque, SMC/ASMC and HOSM/HOSMA on our hand models.

Every case runs the fully actuated hand (one torque per joint, as the thesis) in free space on the simulator at
dt = 1 ms (control at the same rate), and measures it with :mod:`bhgrasp.metrics`.  Choices the thesis leaves
open (all documented in the report that :func:`write_report` produces):

* Joint angles are ours (URDF zero = fingers flat).  The thesis' CTC case starts at (2.46 deg, 40 deg) = our 0
  (Table 3.1: the CAD offsets of the proximal and distal links), so its targets 45/55 deg become 42.54/15 deg;
  our distal limit is 48 deg.  The later cases' targets (25/35 deg, 45/15 deg) are feasible as stated and are
  used as our angles.
* Model error: the controllers' nominal model underestimates every link's mass and inertia by 30 %
  (``hand.perturbed(0.7)``); CTC cases use the exact model, as the thesis does.
* Sensor noise ("with noise" cases): Gaussian, sigma_q = 1e-4 rad, sigma_v = 5e-3 rad/s, seed 3.
* Robust gains are sized from that 30 % error bound along the reference (:func:`sliding_gains`), K_s = 40 [1/s]
  x diag M and gamma = 3000 (relative to parameter scales): the thesis' K = 220 N m, lambda = 0.03 or W = 0.0015
  belong to its own, heavier model and would be meaningless here.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from bhgrasp import metrics
from bhgrasp.controllers import (
    ComputedTorque,
    WorkspaceComputedTorque,
)
from bhgrasp.model.barrett_hand import BarrettHand
from bhgrasp.motion.trajectories import SmoothStep, exponential_approach
from bhgrasp.scenarios.joint_tracking import (
    MASS_ERROR,
    NOISE,
    SEED,
    Run,
    simulate,
)
from bhgrasp.thesis.case import Case, case_progress
from bhgrasp.thesis.chapter3_sliding import add_run, barrett_smc_asmc, f3_hosm, planar_sinusoid, uncertainty_ranking

START_OFFSET = np.radians(1.0)  # CTC cases start 1 deg above the joint stops at 0


# ---------------------------------------------------------------------------------------------------- cases
def ctc_steps(scale: float = 1.0) -> Case:
    """Figs 3.3-3.6: CTC (Kp 400, Kv 160, exact model) on smooth joint steps and fingertip CTC on Cartesian ones."""
    hand = BarrettHand()
    case = Case("ctc", "Computed torque on the Barrett hand (Figs 3.3-3.10)")
    q0 = np.where(hand.lower == 0.0, START_OFFSET, 0.0)  # just off the stops, which CTC does not model
    qf = q0.copy()
    for finger in hand.fingers:
        qf[hand.joint_index(f"{finger}_proximal")] = np.radians(45.0 - 2.46)
        qf[hand.joint_index(f"{finger}_distal")] = np.radians(55.0 - 40.0)
    duration = 4.0 * scale
    step = SmoothStep(q0, qf, 0.5)
    traj = simulate(hand, lambda: ComputedTorque(hand, step), q0, duration, False)
    joints = tuple(i for i in range(hand.nv) if qf[i] != q0[i])
    add_run(case, Run("CTC joint steps", False, traj, joints, tuple(hand.joint_names[i] for i in joints)))
    # spread first (65 deg), fingers once it is there (delay 1 s)
    qs = qf.copy()
    spread = [hand.joint_index("F1_spread"), hand.joint_index("F2_spread")]
    qs[spread] = np.radians(65.0)
    delay = np.where(np.isin(np.arange(hand.nv), spread), 0.0, 1.0)
    spread_step = SmoothStep(q0, qs, 0.3, delay=delay)
    traj = simulate(hand, lambda: ComputedTorque(hand, spread_step), q0, duration + 1.0, False)
    spread_joints = tuple(i for i in range(hand.nv) if qs[i] != q0[i])
    labels = tuple(hand.joint_names[i] for i in spread_joints)
    add_run(case, Run("CTC with spread 65 deg", False, traj, spread_joints, labels))
    # fingertip (workspace) CTC: exponential approach (4.29) from the start tips to the tips of the target pose
    start = hand.fingertip_positions(hand.configuration(**{f"{f}_proximal": 0.6 for f in hand.fingers}))
    q_start = hand.configuration(**{f"{f}_proximal": 0.6 for f in hand.fingers})
    goal = hand.fingertip_positions(qf)
    refs = {f: exponential_approach(start[i], goal[i], 2.0) for i, f in enumerate(hand.fingers)}
    traj = simulate(hand, lambda: WorkspaceComputedTorque(hand, refs), q_start, duration, False)
    add_run(case, Run("fingertip CTC", False, traj, tuple(range(hand.nv)), hand.joint_names))
    case.header = ["run", "joint", "overshoot %", "rise 10-90 % [s]", "settling 2 % [s]", "max error % of step"]
    _step_rows(case, q0, qf, qs)
    _fingertip_rows(case, hand, start, goal)
    case.notes += [
        "Thesis: fingertip max error 5 % of the steady state, rise < 2 s, settling ~2 s; with spread F3 q2 overshoots"
        " 6 %, settling 1-1.5 s (Simulink) / 2.5-3.5 s (SimMechanics).",
        "Ours: with the exact model CTC gives the linear error dynamics e'' + 160 e' + 400 e = 0 (poles -2.6 and"
        " -157 1/s), so the joints follow the smooth step (time constant 0.5 s, rise 0.5 ln 9 = 1.10 s) with"
        " errors set only by the step's velocity jump at its start; there is no overshoot because the reference"
        " has none and the loop is overdamped.  The joints start 1 deg above their stops (the thesis' initial"
        " pose is our 0, on the stops, whose reaction CTC does not model).  The thesis' overshoot and 5 % errors"
        " come from unmodelled"
        " friction and the 0.5 N m s/rad distal damping of its SimMechanics model, which we do not add.",
    ]
    return case


def _step_rows(case: Case, q0: np.ndarray, qf: np.ndarray, qs: np.ndarray) -> None:
    """The joint-step runs' step responses and errors (from ``q0`` to ``qf``, or ``qs`` with the spread)."""
    for run, key in zip((case.runs["CTC joint steps"], case.runs["CTC with spread 65 deg"]), ("joint_steps", "spread")):
        t, q = run.trajectory.t, run.trajectory.q
        target = (qs if "spread" in run.name else qf)[list(run.joints)]
        response = metrics.step_response(t, q[:, list(run.joints)], target, start=q0[list(run.joints)])
        error = run.tracking()
        for k, label in enumerate(run.labels):
            case.table.append(
                [
                    run.name,
                    label,
                    f"{response.overshoot_percent[k]:.2f}",
                    f"{response.rise_time[k]:.2f}",
                    f"{response.settling_time[k]:.2f}",
                    f"{error.max_percent[k]:.3f}",
                ]
            )
            case.values.update(
                {
                    f"{key}/{label}/overshoot_pct": response.overshoot_percent[k],
                    f"{key}/{label}/rise_s": response.rise_time[k],
                    f"{key}/{label}/settling_s": response.settling_time[k],
                    f"{key}/{label}/max_error_pct": error.max_percent[k],
                }
            )
        case.values[f"{key}/max_overshoot_pct"] = np.max(response.overshoot_percent)
        case.values[f"{key}/max_settling_s"] = np.max(response.settling_time)


def _fingertip_rows(case: Case, hand: BarrettHand, start: np.ndarray, goal: np.ndarray) -> None:
    """The fingertip run's largest error [% of each tip's travel from ``start`` to ``goal``], overall and late."""
    tip = case.runs["fingertip CTC"].trajectory
    x_error = np.linalg.norm(tip.log["x_error"].reshape(len(tip.t), -1, 3), axis=2)
    travel = np.linalg.norm(goal - start, axis=1)
    late = tip.t >= 0.5
    for i, finger in enumerate(hand.fingers):
        overall = 100 * x_error[:, i].max() / travel[i]
        after = 100 * x_error[late, i].max() / travel[i] if late.any() else float("nan")  # a run shorter than 0.5 s
        case.table.append(["fingertip CTC", f"{finger} tip", "-", "-", "-", f"{overall:.3f} ({after:.3f} after 0.5 s)"])
        case.values[f"fingertip/{finger}/max_error_pct_of_travel"] = overall
        case.values[f"fingertip/{finger}/max_error_after_0.5s_pct_of_travel"] = after


CASES = {"ctc": ctc_steps, "planar": planar_sinusoid, "barrett": barrett_smc_asmc, "f3": f3_hosm}


def run_chapter3(output: Path, scale: float = 1.0, figures: bool = True, progress: bool = False) -> list[Case]:
    """Run every case (durations x ``scale``), write ``chapter3.md`` and its figures into ``output``.

    ``progress``: a bar over the cases on stderr.
    """
    output = Path(output)
    output.mkdir(parents=True, exist_ok=True)
    cases = [make(scale) for make in case_progress(CASES.values(), len(CASES), "ch3", progress)]
    figure_names = {}
    if figures:
        from bhgrasp import plots

        for case in cases:
            figure_names[case.key] = plots.save_case_figures(case, output)
    write_report(cases, output / "chapter3.md", figure_names, scale)
    return cases


def write_report(cases: list[Case], path: Path, figures: dict[str, list[str]], scale: float) -> Path:
    """The markdown report: per case, our table, the thesis' numbers and why they differ, and the figures."""
    lines = [
        "# Thesis chapter 3 reproduced with bhgrasp",
        "",
        "Generated by `bhgrasp experiments ch3` (module `bhgrasp.thesis.chapter3`)"
        + (f", durations x {scale}" if scale != 1.0 else "")
        + ".  Simulator dt = control period = 1 ms, fully actuated hand in free space, implicit integrator.",
        f"Model error: nominal = plant x {1 - MASS_ERROR:.1f} (every link's mass and inertia) except for CTC cases."
        f"  Noise: sigma_q = {NOISE[0]:g} rad, sigma_v = {NOISE[1]:g} rad/s, seed {SEED}.",
        "Chattering index = total variation of the joint torque per second (a sign switch of +-K every sample gives"
        " 2 K / 1 ms).",
        "",
    ]
    for case in cases:
        lines += [f"## {case.title}", ""]
        lines.append("| " + " | ".join(case.header) + " |")
        lines.append("|" + "---|" * len(case.header))
        lines += ["| " + " | ".join(row) + " |" for row in case.table]
        lines.append("")
        lines += [f"- {note}" for note in case.notes]
        lines.append("")
        for name in figures.get(case.key, []):
            lines += [f"![{case.key}]({name})", ""]
    lines += _findings(cases)
    path.write_text("\n".join(lines) + "\n")
    return path


def _findings(cases: list[Case]) -> list[str]:
    """The uncertainty case's ranking as sentences computed from the runs."""
    f3 = next((case for case in cases if case.key == "f3"), None)
    if f3 is None:
        return []
    rms, chatter = uncertainty_ranking(f3)
    order = sorted(rms, key=rms.get)
    lines = ["## Findings on the uncertainty case (F3, 30 % mass error, noise)", ""]
    lines.append("Mean RMS error over q2, q3 [% of step], best first: " + ", ".join(f"{n} {rms[n]:.3f}" for n in order))
    lines.append("")
    lines.append(
        "Chattering index relative to SMC: "
        + ", ".join(f"{n} {chatter[n] / chatter['SMC']:.3g}" for n in sorted(chatter, key=chatter.get))
    )
    adaptive = ("ASMC", "HOSMA-A", "HOSMA-B", "HOSMA-C")
    beaten = [n for n in adaptive if n in rms and rms[n] < min(rms.get("SMC", np.inf), rms.get("CTC", np.inf))]
    smooth = [n for n in chatter if n.startswith("HOSM") and chatter[n] <= chatter["SMC"] / 5.0]
    rough = [n for n in chatter if n.startswith("HOSM") and n not in smooth]
    lines += [
        "",
        f"- Lower RMS error than both SMC and CTC: {', '.join(beaten) or 'none'} (of {', '.join(adaptive)}).  CTC's"
        " error is large because its PD stiffness M_hat Kp is small for the light BH8-280 links, so 30 % of"
        " gravity stays uncompensated (a linear estimate gives about 8 deg at q2 and 19 deg at q3).",
        f"- At least 5x less chattering than SMC: {', '.join(smooth) or 'none'}; not: {', '.join(rough) or 'none'}."
        "  Super-twisting (C) is continuous.  A is discontinuous at e = e_dot = 0 and B is a sign law, so at a 1 ms"
        " sampling period both switch between +-alpha every few samples once on the surface, as SMC does: the"
        " thesis' smooth torques for A and B are not reproduced (we report this rather than tune it away).",
        "- Adaptive laws have a transient while the estimates converge (about 1 s at gamma = 3000), so an adaptive"
        " controller's max error can exceed SMC's even when its RMS and final errors are lower; non-adaptive"
        " super-twisting needs its integral term to build up the missing torque and has the largest transient"
        " of the sliding family.",
    ]
    return lines


__all__ = [
    "CASES",
    "barrett_smc_asmc",
    "ctc_steps",
    "f3_hosm",
    "planar_sinusoid",
    "run_chapter3",
    "uncertainty_ranking",
    "write_report",
]
