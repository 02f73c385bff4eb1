"""The README's "Results at a glance" table: its rows, each case beside the thesis, rendered from docs/results.

:func:`render_readme_table` fills every ``{N:key:format}`` field of "ours" from ``docs/results/chapterN.json``
(``bhgrasp experiments readme-table``); :func:`update_readme` rewrites the README's table in place.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from bhgrasp.thesis.results import REFERENCE, decode, load

README_HEADER = ["chapter", "case", "ours", "thesis"]
# (chapter, case, ours, thesis).  "ours" holds only {N:key:format} fields of docs/results/chapterN.json and words
# without digits (tests/test_results.py checks it): every number it shows is a measured one.
README_ROWS: list[tuple[str, str, str, str]] = [
    (
        "3",
        "CTC joint steps, exact model (2 % settling)",
        "overshoot {3:ctc/joint_steps/max_overshoot_pct:.0f} %, settling {3:ctc/joint_steps/max_settling_s:.2f} s",
        "F3 q2 overshoot 6 %, 1-1.5 s",
    ),
    (
        "3",
        "planar finger, sinusoid, RMS error q2: SMC / ASMC / HOSMA-A",
        "{3:planar/clean/SMC/q2/rms_error_pct:.2f} / {3:planar/clean/ASMC/q2/rms_error_pct:.2f} / "
        "{3:planar/clean/HOSMA-A/q2/rms_error_pct:.2f} %",
        "SMC 2-5 %, ASMC 0.05-0.5 %",
    ),
    (
        "3",
        "F3, 30 % mass error: max error q3, CTC / SMC / HOSMA-A",
        "{3:f3/clean/CTC/F3_q3/max_error_pct:.0f} / {3:f3/clean/SMC/F3_q3/max_error_pct:.1f} / "
        "{3:f3/clean/HOSMA-A/F3_q3/max_error_pct:.1f} %",
        "abstract: SMC 15 %, HOSM 8 %, HOSMA 5 %",
    ),
    (
        "4",
        "adaptive FIM, planar, 15 -> 30 N",
        "{4:planar/adaptive_FIM_f_d_15_to_30_N/final_N:.2f} N, k_e estimate "
        "{4:planar/adaptive_FIM_f_d_15_to_30_N/k_e_estimate_N_m_true#1:.1f} N/m for "
        "{4:planar/adaptive_FIM_f_d_15_to_30_N/k_e_estimate_N_m_true#2:.1f}",
        "converges to 30 N, k_e ~409",
    ),
    (
        "4",
        "adaptive FIM on F3, K_s = 10 kN/m, f_d = 10 N",
        "{4:f3_force/adaptive_FIM_K_s_10000/final_N:.2f} N, k_e estimate / true "
        "{4:f3_force/adaptive_FIM_K_s_10000/k_e_estimate_true:.4f}",
        "steady error ~0.02 N",
    ),
    (
        "4",
        "the thesis' FIM as printed (no J^T f_d feed-forward) on F3, K_s = 10 kN/m, f_d = 10 N",
        "{4:f3_force/FIM_as_printed_K_s_10000/final_N:.2f} N; closed form "
        "{4:f3_force/FIM_as_printed_K_s_10000/closed_form_N_measured_friction:.2f} N (the inner loop is a "
        "spring Kp m_x in series)",
        "converges to f_d",
    ),
    (
        "4",
        "CMA-ES tuning to cma's convergence (from [0.5, 0.5]; tuned at 6 N, shown at f_d = 4 N)",
        "found [{4:tuning/0.5_0.5/F_d_N=4/found_M_I_K_I#1:.4f}, {4:tuning/0.5_0.5/F_d_N=4/found_M_I_K_I#2:.4f}] "
        "in {4:tuning/0.5_0.5/F_d_N=4/generations:.0f} generations, mean force error "
        "{4:tuning/0.5_0.5/F_d_N=4/mean_error_N_untuned_to_tuned#1:.3f} -> "
        "{4:tuning/0.5_0.5/F_d_N=4/mean_error_N_untuned_to_tuned#2:.3f} N",
        "found [0.0050, 4.7561]",
    ),
    (
        "5",
        "object CTC / natural / stiffness, 10 mm lift + 0.1 rad",
        "final {5:laws/ctc/final_error_z_mm:.3f} / {5:laws/natural/final_error_z_mm:.3f} / "
        "{5:laws/stiffness/final_error_z_mm:.3f} mm, slip events {5:laws/ctc/slip_events:d} / "
        "{5:laws/natural/slip_events:d} / {5:laws/stiffness/slip_events:d}",
        "0.002-0.05 m errors",
    ),
    (
        "5",
        "SMC-adaptive, 1 kg box told 0.5 kg (estimate within 2 %)",
        "contact force error {5:smc/contact_force_error_pct:.2f} %, mass {5:smc/mass_estimate_kg:.4f} kg after "
        "{5:smc/mass_estimate_within_2pct_s:.1f} s, {5:smc/slip_events:d} slip events",
        "1-5 %, ~2 s",
    ),
    (
        "5",
        "unknown mass 0.2-1.0 kg: QP vs the thesis' G^+",
        "QP: force error <= {5:mass/qp/max_force_error_pct:.2f} %, {5:mass/qp/slip_events:d} slip events; G^+: "
        "outside the cone from {5:mass/pinv/lightest_outside_cone_kg:.1f} kg, "
        "{5:mass/1.0kg/pinv/slip_events:d} slip events at the heaviest box",
        "-",
    ),
    (
        "5",
        "object motions of the thesis' pinch and of a pinch with the spread off its stop (13 requests each: lifts, "
        "turns of 0.15-0.3 rad about x, y, z, shifts): success = no slip and within 0.5 mm / 5 mrad of the request",
        "{5:motions/allowed_success_pct:.0f} % of the {5:motions/allowed_motions:.0f} motions not refused succeed; the "
        "others are refused with their reason, before simulating or when the move starts",
        "one motion (Table 5.2)",
    ),
    (
        "5",
        "robustness Monte-Carlo, 30 boxes of 0.2-1.0 kg per scenario (pose noise 0.5 mm / 5 mrad, force noise 0.2 "
        "N, delay 5 ms, torque limit 0.75 N m, true mu 0.5 for 0.6 assumed; true mu 0.48 with a 30 % friction "
        "margin; a real bench: a 30 Hz tracker 30 ms late, encoder and force noise, a 2 ms bus, joint friction, true "
        "mu 20 % low): runs within 0.5 mm / 5 mrad, no hand link sliding over 0.1 mm on the box; [95 % interval]",
        "exact {5:robustness/exact/success_pct:.0f} %; pose noise {5:robustness/pose_noise/success_pct:.0f} % "
        "[{5:robustness/pose_noise/success_low_pct:.0f}, {5:robustness/pose_noise/success_high_pct:.0f}], with the "
        "pose from the encoders {5:robustness/pose_noise_hand/success_pct:.0f} % "
        "[{5:robustness/pose_noise_hand/success_low_pct:.0f}, {5:robustness/pose_noise_hand/success_high_pct:.0f}]; "
        "force noise {5:robustness/force_noise/success_pct:.0f} %; delay {5:robustness/delay/success_pct:.0f} %; "
        "torque limit {5:robustness/torque_limit/success_pct:.0f} % (failed: "
        "{5:robustness/torque_limit/over_torque_limit_failures:.0f} of the "
        "{5:robustness/torque_limit/over_torque_limit_runs:.0f} boxes that no forces inside the assumed cones hold "
        "within the limit, {5:robustness/torque_limit/within_torque_limit_failures:.0f} of the others), told to the "
        "controller {5:robustness/torque_limit_known/success_pct:.0f} % "
        "[{5:robustness/torque_limit_known/success_low_pct:.0f}, "
        "{5:robustness/torque_limit_known/success_high_pct:.0f}]; lower true mu "
        "{5:robustness/wrong_mu/success_pct:.0f} %, with the margin {5:robustness/mu_margin/success_pct:.0f} %; "
        "milder combination {5:robustness/all/success_pct:.0f} %, with the encoders' estimate and the margin "
        "{5:robustness/all_estimated/success_pct:.0f} % [{5:robustness/all_estimated/success_low_pct:.0f}, "
        "{5:robustness/all_estimated/success_high_pct:.0f}], the limit told too "
        "{5:robustness/all_remedied/success_pct:.0f} %; the real bench "
        "{5:robustness/bench_low_mu/success_pct:.0f} % "
        "[{5:robustness/bench_low_mu/success_low_pct:.0f}, {5:robustness/bench_low_mu/success_high_pct:.0f}] with "
        "the encoders' estimate (the true mu as far above: {5:robustness/bench_high_mu/success_pct:.0f} %), "
        "{5:robustness/bench_tracker_only/success_pct:.0f} % with the tracker alone",
        "-",
    ),
    (
        "5",
        "learning the object online: a 0.6 kg box told 0.3 kg, lifted and shaken (along y and z, turns about x and "
        "y), with the robustness table's combined sensor noise over 5 seeds",
        "composite law: mass within {5:adaptation/grasp/composite/noisy/max_mass_error_pct:.2f} %, inertia about x / y "
        "within {5:adaptation/grasp/composite/noisy/max_I_xx_error_pct:.1f} / "
        "{5:adaptation/grasp/composite/noisy/max_I_yy_error_pct:.1f} %; the thesis' law (exact sensing): mass "
        "{5:adaptation/grasp/thesis/exact/mass_error_pct:.1f} % off, inertia about x "
        "{5:adaptation/grasp/thesis/exact/I_xx_error_pct:.0f} % off; in the ideal loop the Lyapunov function V_o never "
        "rises and falls by what the law dissipates, to {5:adaptation/ideal/composite/balance_error_pct:.2f} %",
        "parameters converge, V_dot <= 0 (5.65)",
    ),
    (
        "5",
        "grasp synthesis: the planner's grasps of a box, a cube, a can and a ball, each lifted, turned and shifted "
        "(lift; turns about x, y and z; shifts along x and y)",
        "box: the thesis' pinch, epsilon {5:synthesis/box/epsilon:.3f}; ball epsilon {5:synthesis/ball/epsilon:.3f}, "
        "can {5:synthesis/can/epsilon:.3f}; {5:synthesis/allowed_success_pct:.0f} % of the "
        "{5:synthesis/allowed_motions:.0f} motions not refused succeed, each given to the first grasp that makes it "
        "({5:synthesis/refused_motions:.0f} of the {5:synthesis/requested_motions:.0f} requested for the three objects "
        "grasped are refused: turns about z and shifts along x, which the finger without a spread makes only by "
        "sliding, and the can's shift "
        "along -y)",
        "-",
    ),
    (
        "5",
        "continuous paths: the thesis' pinch and the synthesised ball grasp lift their object, then carry it once "
        "around a 4 mm circle in the vertical y-z plane in 2 s, or through turns joined by overlapping minimum-jerk "
        "blends (told half the mass)",
        "after the lift, circles: at most {5:paths/box/circle/max_deviation_mm:.2f} (box) and "
        "{5:paths/ball/circle/max_deviation_mm:.2f} mm from the path; waypoints: "
        "{5:paths/box/waypoints/max_deviation_mm:.2f} and "
        "{5:paths/ball/waypoints/max_deviation_mm:.2f} mm; slip samples {5:paths/box/circle/slip_events:.0f}, "
        "{5:paths/ball/circle/slip_events:.0f}, {5:paths/box/waypoints/slip_events:.0f}, "
        "{5:paths/ball/waypoints/slip_events:.0f}",
        "-",
    ),
]

_FIELD = re.compile(r"\{(\d+):([^:{}]+):([^{}]*)\}")
README_MARK = "<!-- generated from docs/results/chapterN.json by `bhgrasp experiments readme-table` -->"


def fill(template: str, documents: Mapping[int, Mapping[str, Any]]) -> str:
    """``template`` with each ``{N:key:format}`` replaced by that value of chapter N (KeyError: no such key)."""

    def value(match: re.Match) -> str:
        chapter, key, spec = int(match[1]), match[2], match[3]
        number = decode(documents[chapter]["values"][key])
        if not (isinstance(number, int) or math.isfinite(number)):
            return str(number)
        return format(number, spec)

    # the literal "%" of the templates survives: fields are replaced one by one, no str.format over the whole
    return _FIELD.sub(value, template)


def load_folder(folder: Path = REFERENCE) -> dict[int, dict[str, Any]]:
    """Every ``chapterN.json`` of ``folder``, by chapter number."""
    return {int(path.stem[7:]): load(path) for path in sorted(Path(folder).glob("chapter*.json"))}


def render_readme_table(folder: Path = REFERENCE) -> str:
    """The README's "Results at a glance" table (marker comment and markdown table) from the JSON in ``folder``."""
    documents = load_folder(folder)
    lines = [README_MARK, "", "| " + " | ".join(README_HEADER) + " |", "|" + "---|" * len(README_HEADER)]
    for chapter, case, ours, thesis in README_ROWS:
        lines.append(f"| {chapter} | {case} | {fill(ours, documents)} | {thesis} |")
    return "\n".join(lines) + "\n"


def readme_table(readme_text: str) -> str:
    """The generated part of a README: from the marker comment to the end of the table after it."""
    start = readme_text.index(README_MARK)
    lines = readme_text[start:].splitlines()
    end = next(i for i in range(3, len(lines) + 1) if i == len(lines) or not lines[i].startswith("|"))
    return "\n".join(lines[:end]) + "\n"


def update_readme(readme: Path, folder: Path = REFERENCE) -> bool:
    """Rewrite the README's generated table from ``folder``; True if the file changed."""
    text = Path(readme).read_text()
    current = readme_table(text)
    fresh = render_readme_table(folder)
    if current == fresh:
        return False
    Path(readme).write_text(text.replace(current, fresh, 1))
    return True


__all__ = [
    "README_HEADER",
    "README_MARK",
    "README_ROWS",
    "fill",
    "load_folder",
    "readme_table",
    "render_readme_table",
    "update_readme",
]
