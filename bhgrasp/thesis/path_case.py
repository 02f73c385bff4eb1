"""The chapter-5 path case: grasped objects carried around a circle and through waypoints (scenarios.carry).

Two grasps of :mod:`bhgrasp.thesis.synthesis_case` (the thesis' box, whose synthesis is the thesis' pinch, and the ball)
lift their object 10 mm, then follow either a circle of :data:`~bhgrasp.scenarios.carry.RADIUS`
(:class:`~bhgrasp.motion.paths.PoseCircle`, minimum-jerk in arc angle) in the plane the grasps translate in, the
vertical y-z plane (F3 has no spread joint: no grasp of the BH8-280 moves its object along x, and a horizontal circle is
refused), or :data:`~bhgrasp.scenarios.carry.WAYPOINTS`: turns and shifts joined by minimum-jerk blends that overlap
(:class:`~bhgrasp.motion.paths.PoseWaypoints`).  Each path is checked against the grasp's manipulable space before
simulating (its ``extremes``); the SMC-adaptive law, told half the mass, tracks it
(:class:`~bhgrasp.controllers.supervisor.GraspSupervisor` with ``path``).  Measured along the path after the lift: the
true centre of mass's distance from the reference, the orientation's angle from the reference's, slip, the least cone
margin of the commanded forces; at the end, the pose error against the path's end (success as the motion table's,
:data:`~bhgrasp.scenarios.demo_result.SUCCESS`).
"""

from __future__ import annotations

from bhgrasp.scenarios.carry import (
    CIRCLE_TIME,
    LIFT,
    LIFT_MOVE,
    LIFT_TIME,
    OVERLAP,
    RADIUS,
    WAYPOINTS,
    PathRun,
    circle,
    run_path,
    waypoints,
)
from bhgrasp.scenarios.object_grasp import OBJECTS, object_grasp
from bhgrasp.thesis.case import Case


def path_case(scale: float = 1.0):
    """The chapter-5 case (paths of ``scale`` x their durations after the lift)."""
    header = [
        "object and grasp",
        "path",
        "outcome",
        "max / rms deviation after the lift [mm]",
        "max deviation in the lift [mm]",
        "max turn off the path [mrad]",
        "final error [mm] / [mrad]",
        "slip samples",
        "least cone margin [N]",
    ]
    case = Case("paths", "Continuous paths: grasped objects carried around a circle and through waypoints", "-", header)
    circles: dict[str, PathRun] = {}
    for key in WAYPOINTS:
        label, item = OBJECTS[key]
        setup = object_grasp(item)
        moves = [(offset, duration * scale) for offset, duration in WAYPOINTS[key]]  # (the overlap scales too)
        paths = {
            "circle": (
                circle(duration=CIRCLE_TIME * scale),
                f"circle r {1e3 * RADIUS:g} mm, y-z plane, {CIRCLE_TIME * scale:g} s",
            ),
            "waypoints": (waypoints(moves, OVERLAP * scale), _describe(moves)),
        }
        for name, (path, description) in paths.items():
            run = run_path(setup, path)
            if name == "circle":
                circles[key] = run
            _record(case, f"{key}/{name}", label, description, run)
    case.notes += [
        f"Circle (`bhgrasp.motion.paths.PoseCircle`): a {1e3 * LIFT[2]:g} mm lift in {LIFT_TIME:g} s, then once "
        "around a circle through the lifted "
        f"point, of radius {1e3 * RADIUS:g} mm, the arc angle on a minimum-jerk blend (at rest at both ends), the "
        "orientation held; checked against the grasp's manipulable space at eight of its points before simulating "
        "(a circle with a component along x is refused: F3 cannot move along x).",
        f"Waypoints (`bhgrasp.motion.paths.PoseWaypoints`): a {1e3 * LIFT_MOVE[0][2]:g} mm lift in "
        f"{LIFT_MOVE[1]:g} s, then the moves listed, each a minimum-jerk blend starting {OVERLAP * scale:g} s "
        "before the previous one ends, so that the object passes "
        "the inner waypoints without stopping; checked at every waypoint before simulating.",
        "Deviation: the true centre of mass's distance from the path's, in the lift and from the end of the lift to "
        "the end of the run; turn: the angle between the object's orientation and the path's.  The SMC-adaptive law "
        "starts from half the mass: the largest deviations come in the lift, as the estimate rises.",
    ]
    case.figures["chapter5_paths.png"] = lambda: _figure(circles)
    return case


def _record(case: Case, prefix: str, label: str, description: str, run: PathRun) -> None:
    """A path run's row, and its values under ``prefix``."""
    case.table.append(
        [
            f"{label} (synthesised)",
            description,
            "success" if run.success else "failed",
            f"{1e3 * run.max_deviation:.3f} / {1e3 * run.rms_deviation:.3f}",
            f"{1e3 * run.lift_deviation:.3f}",
            f"{1e3 * run.max_rotation:.2f}",
            f"{1e3 * run.final_position_error:.3f} / {1e3 * run.final_rotation_error:.2f}",
            str(run.slip_events),
            f"{run.cone_margin:.2f}",
        ]
    )
    case.values.update(
        {
            f"{prefix}/{field}": value
            for field, value in (
                ("success", float(run.success)),
                ("max_deviation_mm", 1e3 * run.max_deviation),
                ("rms_deviation_mm", 1e3 * run.rms_deviation),
                ("lift_deviation_mm", 1e3 * run.lift_deviation),
                ("max_rotation_mrad", 1e3 * run.max_rotation),
                ("final_error_mm", 1e3 * run.final_position_error),
                ("final_rotation_mrad", 1e3 * run.final_rotation_error),
                ("slip_events", float(run.slip_events)),
                ("cone_margin_N", run.cone_margin),
            )
        }
    )


def _describe(moves) -> str:
    parts = []
    for offset, duration in moves:
        shift = [f"{1e3 * offset[i]:+g} mm along {'xyz'[i]}" for i in range(3) if offset[i]]
        turn = [f"{offset[3 + i]:+g} rad about {'xyz'[i]}" for i in range(3) if offset[3 + i]]
        parts.append(f"{', '.join(shift + turn)} ({duration:g} s)")
    return "lift, then " + "; ".join(parts)


def _figure(runs: dict[str, PathRun]):
    from bhgrasp.plots import Figure

    figure = Figure(figsize=(9, 4), layout="tight")
    for axis, (key, run) in zip(figure.subplots(1, len(runs)), runs.items()):
        origin = run.reference[0]
        axis.plot(
            1e3 * (run.reference[:, 1] - origin[1]),
            1e3 * (run.reference[:, 2] - origin[2]),
            "k--",
            lw=1.0,
            label="path",
        )
        axis.plot(
            1e3 * (run.position[:, 1] - origin[1]),
            1e3 * (run.position[:, 2] - origin[2]),
            lw=1.0,
            label="object (true)",
        )
        axis.set(xlabel="y [mm]", ylabel="z [mm]", title=f"{key}: circle in the y-z plane", aspect="equal")
        axis.grid(alpha=0.3)
        axis.legend(fontsize=7)
    return figure


__all__ = ["path_case"]
