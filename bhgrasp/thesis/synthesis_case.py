"""The chapter-5 synthesis case: grasps the planner finds for boxes, cylinders and spheres, chosen per motion and run.

For each object of :data:`~bhgrasp.scenarios.object_grasp.OBJECTS` (household sizes the BH8-280 spans, each centred
where the thesis' box is), :func:`~bhgrasp.grasp.synthesis.grasp_candidates` finds the grasps (fingers, spread,
contacts; best first), then every motion of :data:`MOTIONS` is given to the first grasp that makes it
(:func:`~bhgrasp.scenarios.object_choice.grasp_for_motion`: checked before simulating, then run with the SMC-adaptive
law told half the mass on a pedestal, :mod:`bhgrasp.scenarios.object_grasp`) or refused when none does, and judged as
the motion table judges (:data:`~bhgrasp.scenarios.demo_result.SUCCESS`: no sliding contact sample after the grasp
closed, the true final pose within 0.5 mm and 5 mrad of the request).
"""

from __future__ import annotations

import time
from dataclasses import replace
from typing import Any

import numpy as np

from bhgrasp.errors import UnreachableError
from bhgrasp.grasp.synthesis import NO_GRASP, grasp_candidates
from bhgrasp.model.barrett_hand import BarrettHand
from bhgrasp.scenarios.box_grasp import FRICTION
from bhgrasp.scenarios.demo_result import MU_ASSUMED, SUCCESS
from bhgrasp.scenarios.object_choice import grasp_for_motion
from bhgrasp.scenarios.object_grasp import OBJECTS
from bhgrasp.thesis.case import Case
from bhgrasp.thesis.motions import short_reason

MOTIONS = {
    "lift": ("lift 10 mm", (0.0, 0.0, 0.01, 0.0, 0.0, 0.0)),
    "rx+0.15": ("lift, turn +0.15 rad about x", (0.0, 0.0, 0.01, 0.15, 0.0, 0.0)),
    "rx-0.15": ("lift, turn -0.15 rad about x", (0.0, 0.0, 0.01, -0.15, 0.0, 0.0)),
    "ry+0.15": ("lift, turn +0.15 rad about y", (0.0, 0.0, 0.01, 0.0, 0.15, 0.0)),
    "ry+0.1": ("lift, turn +0.1 rad about y", (0.0, 0.0, 0.01, 0.0, 0.1, 0.0)),
    "rz+0.15": ("lift, turn +0.15 rad about z", (0.0, 0.0, 0.01, 0.0, 0.0, 0.15)),
    "x+5": ("lift, shift 5 mm along x", (0.005, 0.0, 0.01, 0.0, 0.0, 0.0)),
    "y+5": ("lift, shift 5 mm along y", (0.0, 0.005, 0.01, 0.0, 0.0, 0.0)),
    "y-5": ("lift, shift 5 mm along -y", (0.0, -0.005, 0.01, 0.0, 0.0, 0.0)),
}
DURATION = 3.0  # [s] each run


def synthesis_case(scale: float = 1.0):
    """The chapter-5 case (runs of ``scale`` x 3 s)."""
    header = ["object", "synthesised grasp", "motion", "outcome", "final error [mm] / [mrad]", "slip samples"]
    case = Case(
        "synthesis", "Grasp synthesis: the planner's grasps of boxes, cylinders and spheres, moved", "-", header
    )
    requested = allowed = succeeded = 0
    failed: list[str] = []
    hand = BarrettHand()
    for object_key, (label, item) in OBJECTS.items():
        start = time.perf_counter()
        candidates = grasp_candidates(hand, replace(item, friction=FRICTION, density=None), MU_ASSUMED)
        planning = time.perf_counter() - start
        if not candidates:
            case.values[f"{object_key}/grasp_found"] = 0.0
            case.table.append([label, f"none: {NO_GRASP}", "-", "-", "-", "-"])
            continue
        case.values[f"{object_key}/grasp_found"] = 1.0
        case.values[f"{object_key}/candidates"] = float(len(candidates))
        _record_grasp(case, object_key, candidates[0])
        case.notes.append(f"{label}: {len(candidates)} grasps synthesised in {planning:.1f} s (wall, this machine).")
        for motion_key, (motion, offset) in MOTIONS.items():
            key = f"{object_key}/{motion_key}"
            requested += 1
            try:
                result = grasp_for_motion(item, offset, DURATION * scale, candidates)
            except UnreachableError as error:
                case.values[f"{key}/refused"] = 1.0
                case.values[f"{key}/candidate"] = 0.0
                reasons = error.result or (("", str(error)),)
                ran = sum(reason.startswith("refused when the move started") for _, reason in reasons)
                grasps = f"none of {len(candidates)}" if not ran else f"{ran} run, refused when the move started"
                case.table.append([label, grasps, motion, f"refused: {short_reason(reasons[0][1])}", "-", "-"])
                continue
            allowed += 1
            choice = result.grasp_choice
            case.values[f"{key}/candidate"] = float(len(choice.refused) + 1)
            succeeded += _record_motion(case, key, label, choice.label, motion, result, failed)
    case.values["requested_motions"] = float(requested)
    case.values["refused_motions"] = float(requested - allowed)
    case.values["allowed_motions"] = float(allowed)
    case.values["allowed_success_pct"] = 100.0 * succeeded / allowed if allowed else float("nan")
    case.notes += _notes(allowed, succeeded, failed)
    return case


def _record_grasp(case: Case, object_key: str, c: Any) -> None:
    """The best synthesised grasp ``c``'s values (spread, epsilon, fingers, weight margin)."""
    case.values.update(
        {
            f"{object_key}/spread_deg": float(np.degrees(c.spread)),
            f"{object_key}/epsilon": float(c.quality.epsilon),
            f"{object_key}/fingers": len(c.fingers),
            f"{object_key}/weight_margin_N": float(c.weight_margin),
        }
    )


def _record_motion(case: Case, key: str, label: str, grasp: str, motion: str, result: Any, failed: list[str]) -> bool:
    """A motion's row and values; whether it succeeded (a failure's description goes to ``failed``)."""
    position, rotation = result.true_position_error, result.true_rotation_error
    success = result.slip_events == 0 and position < SUCCESS[0] and rotation < SUCCESS[1]
    if not success:
        failed.append(
            f"{label}, {motion} ({1e3 * position:.2f} mm, {1e3 * rotation:.1f} mrad, {result.slip_events} slip samples)"
        )
    case.table.append(
        [
            label,
            grasp,
            motion,
            "success" if success else "failed",
            f"{1e3 * position:.3f} / {1e3 * rotation:.2f}",
            str(result.slip_events),
        ]
    )
    case.values.update(
        {
            f"{key}/refused": 0.0,
            f"{key}/success": float(success),
            f"{key}/final_error_mm": 1e3 * position,
            f"{key}/final_rotation_mrad": 1e3 * rotation,
            f"{key}/slip_events": float(result.slip_events),
        }
    )
    return success


def _notes(allowed: int, succeeded: int, failed: list[str]) -> list[str]:
    share = f"{100 * succeeded / allowed:.0f} %" if allowed else "-"
    return [
        f"{succeeded} of the {allowed} motions that ran succeed ({share}); "
        + (f"failed: {'; '.join(failed)}." if failed else "none failed."),
        "Synthesis (`bhgrasp.grasp.synthesis`): for every spread (0-90 deg in 10 deg steps) and contact height, each "
        "finger's line of approach is cast at the object; the IK puts the pads there; candidates whose other link "
        "shapes come within 1.5 mm of the object, at the contacts or along a 10 mm lift (first order), or whose "
        "contacts sit within 5 mm of an edge, a flexing joint within 0.05 rad of a limit (a spread joint may rest on "
        "its stop) or a fingertip over its spread axis (the contact Jacobian's least singular value under 2 mm/rad), "
        "are dropped; the rest are ranked "
        "by the Ferrari-Canny epsilon (mu 0.6), then by the force QP's margin holding the weight with 5 N per "
        "contact.  The pre-grasp opens the proximal joints by 0.3 rad; the approach cancels the drive's known "
        "joint damping.  Module `bhgrasp.thesis.synthesis_case`.",
        "Each motion goes to the first grasp, best first, that makes it (`bhgrasp.scenarios.object_choice`): before "
        "simulating, the request must lie in the grasp's manipulable space at the planned contacts, keep the object "
        "off its pedestal and keep the hand's other shapes 0.2 mm off the object along the path with the contacts "
        "rolling (`bhgrasp.grasp.path_check`); when the move starts the supervisor checks the request (missed by more "
        "than 0.5 mm or 5 mrad: `Planning(tolerance=...)`) and the path again at the contacts the fingers sense, and "
        "a refusal there passes the motion to the next grasp that passes (at most 3 runs).  The grasp column gives "
        "the chosen grasp's rank among the object's candidates; 'none of N': no grasp makes the motion, with the "
        "best grasp's reason.",
        "A single sliding sample counts as a failure, from the sample after the grasp controller took over (the "
        "switching sample records the contacts of the approach's last step: there the can's F3 pad, just touched, "
        "skids; counted from the switch, the can's lift and turn about x failed on that one sample).",
        "Errors are the true final pose against the requested motion; the supervisor tracks the part of it the "
        "grasp makes at the contacts it senses (the planned motion), so a request the sensed contacts cannot make "
        "exactly ends off by what the plan misses (at most the plan tolerance) plus the tracking error.",
    ]


__all__ = ["MOTIONS", "synthesis_case"]
