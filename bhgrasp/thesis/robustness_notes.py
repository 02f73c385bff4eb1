"""The robustness table's notes: its design and what it shows, in words with the table's own numbers."""

from __future__ import annotations

import math

from bhgrasp.scenarios.box_grasp import FRICTION
from bhgrasp.scenarios.demo_result import MU_ASSUMED
from bhgrasp.thesis.robustness_scenarios import (
    ALL,
    CONFIDENCE,
    ESTIMATE,
    MARGIN,
    MASS_RANGE,
    SCENARIOS,
    SEED,
    SLIDE,
    SUCCESS,
)

TORQUE_LIMIT = SCENARIOS["torque_limit"][1]["torque_limit"]  # [N m]

Summaries = dict[str, dict[str, float]]


def robustness_notes(samples: int, duration: float, summaries: Summaries) -> list[str]:
    """The design's notes (``samples`` runs of ``duration`` [s] per scenario), then what the rows show."""
    low, high = MASS_RANGE
    return [
        f"{samples} runs per scenario of {duration:g} s: box masses uniform in {low}-{high} kg (one seeded design, "
        f"seed {SEED}, the same boxes and noise seeds in every scenario), the controller starting at {ESTIMATE} kg; "
        f"SMC-adaptive law, QP forces (mu {MU_ASSUMED} assumed, 0.8 true unless the scenario says).  Modules "
        "`bhgrasp.thesis.robustness`, `bhgrasp.thesis.robustness_scenarios`.",
        f"Success: the true final pose within {1e3 * SUCCESS[0]:g} mm and {1e3 * SUCCESS[1]:g} mrad of the "
        f"requested one and no hand link slid farther than {1e3 * SLIDE:g} mm on the box after the grasp closed "
        "(bhgrasp.grasp.metrics.sliding_distances: a link's sliding contact points move against the box at their "
        "relative tangential speed); in brackets the success rate's "
        f"{100 * CONFIDENCE:.0f} % Wilson score interval.  Strict success: the same pose bounds and no hand-box "
        "contact sample at the Coulomb limit after the grasp closed (the table's criterion before the slide bound).  "
        "Errors are the object's true pose against the requested "
        "motion, not what the sensors report; force error: largest |measured - commanded| / commanded normal force "
        "over the fingers 0.5 s after the move (true forces).",
        "Noise is Gaussian, independent per reading and control step (1 ms): pose on the object's position and "
        "rotation vector, twist on its linear and angular velocity, force on each contact force component, joint "
        "on the encoders; the delay makes every reading that much older.  Friction and the torque limit act on "
        "every joint of the simulated hand; the controller's model has neither, unless the scenario tells it the "
        "limit.",
        "The milder combined scenario ('all'): pose 0.2 mm / 2 mrad, twist 2 mm/s / 20 mrad/s, force 0.1 N, joints "
        "1e-4 rad / 5e-3 rad/s, delay 2 ms, joint friction 0.01 N m + 0.1 N m s/rad, torque limit 1.5 N m, true mu "
        "0.6.",
        "A real bench: a tracker of 0.5 mm / 5 mrad at 30 frames/s, each frame delivered 30 ms late (its twist 5 "
        "mm/s / 50 mrad/s), encoders 1e-4 rad / 5e-3 rad/s, contact forces 0.1 N, a 2 ms bus, joint friction 0.01 N "
        f"m + 0.1 N m s/rad, torque limit 1.5 N m, a friction margin of {100 * MARGIN:.0f} %, and the true mu 20 % "
        "below or above the assumed one.",
        *limits(summaries),
    ]


def limits(summaries: Summaries) -> list[str]:
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
            f"Object pose noise read as it comes reaches the contact forces through the object-space feedback (force "
            f"error {pose['mean_force_error_pct']:.1f} % on average, {pose['mean_slip_events']:.0f} sliding samples "
            f"per run, a finger sliding up to {pose['max_slide_mm']:.1f} mm), where noise on the twist, the contact "
            "forces or the encoders and a delay leave the mean pose "
            f"error at or below {max(others):.3f} mm."
        )
    lines += estimator_limits(summaries)
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
            f"({mu['mean_slip_events']:.0f} sliding samples per run, a finger sliding {mu['mean_slide_mm']:.1f} mm on "
            f"average and up to {mu['max_slide_mm']:.1f} mm, rotation errors up to "
            f"{mu['max_rotation_mrad']:.0f} mrad); cones below the true mu alone do not prevent it "
            "(bhgrasp.thesis.robustness_scenarios.MARGIN)."
        )
    limited = summaries.get("torque_limit")
    if limited is not None and limited["success_pct"] < 100.0:
        lines.append(
            f"Under the torque limit heavy boxes fail, the lightest {limited['lightest_failure_kg']:.3f} kg "
            f"(rotation errors up to {limited['max_rotation_mrad']:.0f} mrad, {limited['mean_slip_events']:.1f} "
            "sliding samples per run): F3 opposes F1 and F2 together, so its inner joint carries the hold's largest "
            "torque, and the heavier the box the more of it.  " + torque_need(limited)
        )
    known = summaries.get("torque_limit_known")
    if known is not None:
        lines.append(
            "Told the limit (GraspOptions.torque_limit), the controller keeps its commands within it: where the QP's "
            "forces would load a joint past it, it scales their internal part down (bhgrasp.grasp.torque_limited), "
            "so the fingers exert the same wrench and press less together, on friction the assumed cones kept in "
            f"reserve.  Then {known['success_pct']:.0f} % of the runs succeed (mean true error "
            f"{known['mean_error_mm']:.3f} mm / {known['mean_rotation_mrad']:.2f} mrad, at most "
            f"{known['max_error_mm']:.3f} mm / {known['max_rotation_mrad']:.2f} mrad; "
            f"{known['mean_slip_events']:.1f} sliding samples per run), the "
            f"{known['over_torque_limit_runs']:.0f} boxes that need more than the limit inside the assumed cones "
            "included."
        )
    lines += remedied_limits(summaries)
    margin = summaries.get("mu_margin")
    if margin is not None:
        lines.append(
            f"With a friction margin (GraspOptions.friction_margin = {MARGIN:g}: the QP's cones at "
            f"{1 - MARGIN:g} mu and each contact's normal force raised to its measured tangential load / "
            f"({1 - MARGIN:g} mu)) a true mu 20 % below the assumed one holds in {margin['success_pct']:.0f} % of the "
            f"runs ({margin['mean_slip_events']:.1f} sliding samples per run)."
        )
    return lines


def remedied_limits(summaries: Summaries) -> list[str]:
    """What the milder combination leaves with the remedies on, in words with the table's numbers."""
    milder, estimated, remedied = (summaries.get(key) for key in ("all", "all_estimated", "all_remedied"))
    if milder is None or estimated is None or remedied is None:
        return []
    line = (
        f"At the milder levels with the encoders' estimate and the friction margin {estimated['success_pct']:.0f} % "
        f"of the runs succeed (from {milder['success_pct']:.0f} %; mean true error {estimated['mean_error_mm']:.3f} "
        f"mm, at most {estimated['max_error_mm']:.3f} mm), and with the torque limit told too "
        f"{remedied['success_pct']:.0f} % (mean {remedied['mean_error_mm']:.3f} mm, at most "
        f"{remedied['max_error_mm']:.3f} mm / {remedied['max_rotation_mrad']:.2f} mrad)."
    )
    within = remedied["max_error_mm"] < 1e3 * SUCCESS[0] and remedied["max_rotation_mrad"] < 1e3 * SUCCESS[1]
    if remedied["success_pct"] < 100.0 and within and remedied["failed_runs"] == 0.0:
        line += (
            "  With every remedy each run ends within the pose bounds; those that fail, the lightest of their boxes "
            f"{remedied['lightest_failure_kg']:.3f} kg (without the limit told "
            f"{estimated['lightest_failure_kg']:.3f} kg), had a finger slide farther than the {1e3 * SLIDE:g} mm bound "
            f"(the farthest {remedied['max_slide_mm']:.2f} mm).  Holding their boxes at rest inside the margin's "
            f"cones needs at least {remedied['hold_torque_failure_min_nm']:.2f} N m of the "
            f"{ALL['torque_limit']:g} N m limit and the motion's load comes on top: squeezing less to stay within it "
            "spends the margin's reserve, which a true mu equal to the assumed one does not have beyond it."
        )
    return [line]


def torque_need(limited: dict[str, float]) -> str:
    """What the torque-limit scenario's boxes need: the least peak joint torque of their final grasps' holds."""
    over, failed_over = limited["over_torque_limit_runs"], limited["over_torque_limit_failures"]
    need = (
        "In the controller's model of each run's final grasp (one contact per finger, the pyramids of its cones at "
        f"mu {MU_ASSUMED}, each contact at least its least normal force; bhgrasp.grasp.hold_torque) the least peak "
        f"joint torque that holds the box at rest is at most {limited['hold_torque_success_max_nm']:.3f} N m for the "
        f"boxes that held and at least {limited['hold_torque_failure_min_nm']:.3f} N m for those that failed; "
        f"{over:.0f} boxes need more than the {TORQUE_LIMIT:g} N m limit, so no forces inside the assumed cones "
        f"hold them within it, and {failed_over:.0f} of them fail"
        f"{' (the rest stay within the success bounds)' if over > failed_over else ''}, while "
        f"{limited['within_torque_limit_failures']:.0f} boxes within the limit fail."
    )
    true_mu = limited["hold_torque_true_mu_max_nm"]
    within = math.isfinite(true_mu) and true_mu <= TORQUE_LIMIT
    reserve = ", within the limit: the limit takes away the reserve the assumed mu keeps" if within else ""
    same = f"In the same model with the true mu ({FRICTION:g}) every box needs at most {true_mu:.3f} N m"
    return f"{need}  {same}{reserve}."


def estimator_limits(summaries: Summaries) -> list[str]:
    """What the pose estimated from the encoders and the tracker changes, in words with the table's numbers."""
    lines = []
    pose, held = summaries.get("pose_noise"), summaries.get("pose_noise_hand")
    if pose is not None and held is not None:
        lines.append(
            "With the pose estimated from the fingers' encoders and the tracker (estimator='hand': "
            "bhgrasp.controllers.object_estimator, a Kalman filter carrying the box with the contact points anchored "
            f"on their links once three fingers hold it) the same pose noise leaves {held['success_pct']:.0f} % "
            f"success (from {pose['success_pct']:.0f} %), a mean true error of {held['mean_error_mm']:.3f} mm / "
            f"{held['mean_rotation_mrad']:.2f} mrad and a force error of {held['mean_force_error_pct']:.2f} % (from "
            f"{pose['mean_force_error_pct']:.1f} %)."
        )
    bench, tracker = summaries.get("bench_low_mu"), summaries.get("bench_tracker_only")
    if bench is not None and tracker is not None:
        lines.append(
            f"On the real bench with the true mu 20 % low the estimator makes {bench['success_pct']:.0f} % of the runs "
            f"succeed ({bench['mean_error_mm']:.3f} mm / {bench['mean_rotation_mrad']:.2f} mrad on average, "
            f"{bench['mean_slip_events']:.1f} sliding samples per run, its farthest-sliding link "
            f"{bench['mean_slide_mm']:.3f} mm on average; "
            f"{bench['strict_success_pct']:.0f} % with no contact sample at the Coulomb limit: in the others a "
            "fingertip patch's lightly loaded edge or the last finger in its first milliseconds on the box reached "
            "it), "
            "the tracker's pose read as it comes "
            f"{tracker['success_pct']:.0f} % ({tracker['mean_error_mm']:.3f} mm / "
            f"{tracker['mean_rotation_mrad']:.2f} mrad, {tracker['mean_slip_events']:.1f} sliding samples)."
        )
    return lines


__all__ = ["estimator_limits", "limits", "remedied_limits", "robustness_notes", "torque_need"]
