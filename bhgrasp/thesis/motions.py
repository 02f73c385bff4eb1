"""Which object motions the chapter-5 grasps make: a table of grasp x motion -> refused, or run and measured.

The grasp pipeline goes beyond one scripted lift-and-turn: every requested motion either runs to its
end with no slip (final error below :data:`SUCCESS`) or is refused before anything is simulated, with the reason
(:func:`~bhgrasp.scenarios.grasp_demo.run_grasp_demo` refuses a motion outside the grasp's manipulable space, one
that drives a joint past its limit, and one whose path drives the box into its pedestal).

Two grasps of the thesis' box (:mod:`~bhgrasp.scenarios.box_grasp`): the thesis' fingertip pinch, F1 and F2
50 mm apart with the spread joints on their stop, and the same pinch with F1 and F2 55 mm apart, the spread off its
stop.  Motions (:data:`MOTIONS`): a 10 mm lift, alone and followed by turns of 0.15 and 0.3 rad about x, y and z
and 5 mm shifts along x and y, a combined turn, and a turn without the lift.  Each run is the SMC-adaptive demo
(0.6 kg box, the controller told 0.3 kg) for 3 s; its errors are the true final pose against the *requested* motion.
"""

from __future__ import annotations

import re
from typing import Any

import numpy as np

from bhgrasp.errors import InputError, UnreachableError
from bhgrasp.scenarios.box_grasp import KNUCKLE_SPACING, OFF_STOP_SPACING
from bhgrasp.scenarios.demo_result import SUCCESS
from bhgrasp.scenarios.grasp_demo import run_grasp_demo
from bhgrasp.thesis.case import Case

MASS, ESTIMATE, DURATION = 0.6, 0.3, 3.0  # [kg], [kg], [s]
GRASPS: dict[str, tuple[str, float]] = {
    "on_stop": ("pinch, spread on its stop (thesis)", KNUCKLE_SPACING),
    "off_stop": ("pinch, spread off its stop", OFF_STOP_SPACING),
}
LIFT = 0.01  # [m]


def _motion(dx: float = 0.0, dy: float = 0.0, rx: float = 0.0, ry: float = 0.0, rz: float = 0.0, lift: float = LIFT):
    return (dx, dy, lift, rx, ry, rz)


MOTIONS: dict[str, tuple[str, tuple[float, ...]]] = {
    "lift": ("lift 10 mm", _motion()),
    "rx+0.15": ("lift, turn +0.15 rad about x", _motion(rx=0.15)),
    "rx-0.15": ("lift, turn -0.15 rad about x", _motion(rx=-0.15)),
    "rx+0.3": ("lift, turn +0.3 rad about x", _motion(rx=0.3)),
    "ry+0.15": ("lift, turn +0.15 rad about y", _motion(ry=0.15)),
    "ry-0.15": ("lift, turn -0.15 rad about y", _motion(ry=-0.15)),
    "ry+0.3": ("lift, turn +0.3 rad about y", _motion(ry=0.3)),
    "rz+0.15": ("lift, turn +0.15 rad about z", _motion(rz=0.15)),
    "rz+0.3": ("lift, turn +0.3 rad about z", _motion(rz=0.3)),
    "x+5": ("lift, shift 5 mm along x", _motion(dx=0.005)),
    "y+5": ("lift, shift 5 mm along y", _motion(dy=0.005)),
    "rx+ry": ("lift, turn 0.1 rad about x and 0.1 about y", _motion(rx=0.1, ry=0.1)),
    "ry-nolift": ("turn 0.15 rad about y without a lift", _motion(ry=0.15, lift=0.0)),
}


def run_motion(spacing: float, offset: Any, duration: float = DURATION) -> dict[str, Any]:
    """One grasp and motion: ``refused`` with its reason, or the run's figures (errors against the request)."""
    try:
        result = run_grasp_demo(MASS, ESTIMATE, offset=offset, duration=duration, finger_spacing=spacing)
    except UnreachableError as error:
        return {"refused": True, "reason": short_reason(str(error))}
    if result.planned_offset is None:  # the run ended before the motion began: nothing was planned or moved
        raise InputError(
            f"a {duration:g} s run ends before the motion starts at {result.motion_start:.2f} s: nothing to compare "
            f"(chapter 5 at --scale below {result.motion_start / DURATION:.2f} leaves its motions no time)"
        )
    traj = result.trajectory
    moving = traj.t >= result.motion_start
    tracking = traj.log["object_error"][moving]
    position, rotation = result.true_position_error, result.true_rotation_error
    missing = np.asarray(offset, dtype=float) - result.planned_offset  # what the plan leaves out of the request
    return {
        "plan_shortfall_mm": 1e3 * float(np.linalg.norm(missing[:3])),
        "plan_shortfall_mrad": 1e3 * float(np.linalg.norm(missing[3:])),
        "refused": False,
        "reason": "",
        "success": bool(result.slip_events == 0 and position < SUCCESS[0] and rotation < SUCCESS[1]),
        "final_error_mm": 1e3 * position,
        "final_rotation_mrad": 1e3 * rotation,
        "max_error_mm": 1e3 * float(np.max(np.linalg.norm(tracking[:, :3], axis=1), initial=0.0)),
        "max_rotation_mrad": 1e3 * float(np.max(np.linalg.norm(tracking[:, 3:], axis=1), initial=0.0)),
        "slip_events": result.slip_events,
        "force_error_pct": 100 * result.force_error,
        "planned": result.planned_offset is not None and not np.allclose(result.planned_offset, offset, 0, 1e-12),
    }


def _face(match: re.Match) -> str:
    face = f"the {match.group(3)} face" if match.group(3) else "the object"
    return f"{match.group(1).replace('_', ' ')} link body within {match.group(2)} mm of {face} at {match.group(4)} rad"


_REASONS = (  # (pattern in a refusal's message, its few words), first match wins
    (r"joint (\S+) reaches its limit", lambda m: f"joint {m.group(1)} at its limit"),
    (r"contact (\S+) would slide or roll ([\d.]+) mm", lambda m: f"{m.group(1)} would slide {m.group(2)} mm"),
    (r"(\w+?)_link_\d+ \(\S+\) comes within ([\d.]+) mm of the object's (\S*) ?face .*? \(([\d.]+) rad\)", _face),
    (
        r"only to within ([\d.]+) mm and ([\d.]+) mrad",
        lambda m: f"the sensed contacts miss it by {m.group(1)} mm / {m.group(2)} mrad",
    ),
    (
        r"joint (\S+) leaves its limits at (\d+) % of the path",
        lambda m: f"joint {m.group(1)} leaves its limits {m.group(2)} % along the path",
    ),
    (
        r"([\d.]+) mm into (\S+) at .*?lift the object by ([\d.]+) mm",
        lambda m: f"{m.group(1)} mm into {m.group(2)}: lift {m.group(3)} mm first",
    ),
)


def short_reason(message: str) -> str:
    """A refusal in a few words: the joint at its limit, the contact that would slide, or the shape in the way."""
    for pattern, words in _REASONS:
        match = re.search(pattern, message)
        if match:
            return words(match)
    return message.split(";")[0][:80]


def motions_case(scale: float = 1.0):
    """The chapter-5 case: every grasp x motion (runs of ``scale`` x 3 s)."""
    header = [
        "grasp",
        "motion",
        "outcome",
        "final error [mm] / [mrad]",
        "max tracking error [mm] / [mrad]",
        "slip samples",
        "force error [%]",
    ]
    case = Case(
        "motions",
        "Object motions of the chapter-5 grasps: refused before simulating, or run",
        "Table 5.2 asks for one motion: 10 mm and 2-9 degrees",
        header,
    )
    allowed = succeeded = 0
    failed: list[str] = []
    for grasp_key, (grasp_label, spacing) in GRASPS.items():
        for motion_key, (motion_label, offset) in MOTIONS.items():
            row = run_motion(spacing, offset, DURATION * scale)
            key = f"{grasp_key}/{motion_key}"
            case.values[f"{key}/refused"] = float(row["refused"])
            if row["refused"]:
                case.table.append([grasp_label, motion_label, f"refused: {row['reason']}", "-", "-", "-", "-"])
                continue
            allowed += 1
            succeeded += row["success"]
            if not row["success"]:
                failed.append(f"{motion_label} ({grasp_label}: {row['slip_events']} slip samples)")
            _record(case, key, grasp_label, motion_label, row)
    case.values["allowed_motions"] = float(allowed)
    case.values["allowed_success_pct"] = 100.0 * succeeded / allowed if allowed else float("nan")
    shortfall = tuple(
        max((v for k, v in case.values.items() if k.endswith(f"plan_shortfall_{unit}")), default=0.0)
        for unit in ("mm", "mrad")
    )
    case.notes += _notes(allowed, succeeded, failed, shortfall)
    return case


def _record(case: Case, key: str, grasp_label: str, motion_label: str, row: dict) -> None:
    """A motion run's row, and its values under ``key``."""
    outcome = ("success" if row["success"] else "failed") + (" (planned)" if row["planned"] else "")
    case.table.append(
        [
            grasp_label,
            motion_label,
            outcome,
            f"{row['final_error_mm']:.3f} / {row['final_rotation_mrad']:.2f}",
            f"{row['max_error_mm']:.3f} / {row['max_rotation_mrad']:.2f}",
            str(row["slip_events"]),
            f"{row['force_error_pct']:.2f}",
        ]
    )
    for name in (
        "final_error_mm",
        "final_rotation_mrad",
        "max_error_mm",
        "max_rotation_mrad",
        "slip_events",
        "force_error_pct",
        "plan_shortfall_mm",
        "plan_shortfall_mrad",
    ):
        case.values[f"{key}/{name}"] = float(row[name])
    case.values[f"{key}/success"] = float(row["success"])


def _notes(allowed: int, succeeded: int, failed: list[str], shortfall: tuple[float, ...]) -> list[str]:
    share = f"{100 * succeeded / allowed:.0f} %" if allowed else "-"
    failures = f"Failed: {'; '.join(failed)}." if failed else "No motion that ran failed."
    return [
        failures,
        f"{succeeded} of the {allowed} motions that were not refused succeed ({share}): no sliding contact sample "
        f"after the grasp closed and the true final pose within {1e3 * SUCCESS[0]:g} mm and {1e3 * SUCCESS[1]:g} mrad "
        "of the requested one.  Max tracking error: the controller's pose error from the start of the move (against "
        "the motion it tracked).",
        "Refused before simulating (`run_grasp_demo` raises `UnreachableError` with the reason): a motion the "
        "fingers cannot make without a contact sliding (first order, more than 0.2 mm; F3 cannot move along x, so "
        "neither shifts along x nor turns about z through the centre are possible), one that drives a joint past its "
        "limit (on their stop the spread joints cannot open for a turn about y), and one whose path drives the box "
        "into its pedestal (a turn without a lift; the message gives the lift that clears it).",
        "Refused when the move starts (the supervisor's second-order check, `bhgrasp.grasp.path_check`: the planned "
        "motion followed to its end with the sensed contacts rolling without slip): one along which another part of "
        "a finger comes within 0.2 mm of the box.  The 0.3 rad turns about x end where F3's distal link body, beside "
        "its spherical pad, meets the tilted face; run anyway, the finger then touches at several points, its "
        "normal force splits among them and the pad's share no longer holds its tangential load, so it slides "
        "(before this check they ran and slid; with the link bodies taken out of the collision model they succeed).  "
        "The check is conservative: a 0.25 rad turn grazes the face at its end and would be refused, though it "
        "still succeeds when run.",
        "(planned): the supervisor tracked the part of the request the fingers make at the contacts they sense when "
        "the move starts (`GraspSupervisor._plan`): the fingertips touch a little below the pads' centres, so a turn "
        "about y through the box's centre would drag F3 along x; the error is still measured against the request.  "
        f"A plan more than 0.5 mm or 5 mrad from the request would be refused (here at most {shortfall[0]:.2f} mm "
        f"and {shortfall[1]:.2f} mrad).",
        f"Scene and run: the chapter-5 box ({MASS} kg, the controller told {ESTIMATE} kg), SMC-adaptive law with QP "
        f"forces, {DURATION:g} s per run (move 1 s after a 0.3 s squeeze); module `bhgrasp.thesis.motions`.",
    ]


__all__ = ["GRASPS", "MOTIONS", "motions_case", "run_motion", "short_reason"]
