"""The chapter-5 path case: grasped objects carried around a circle and through waypoints.

Two grasps of :mod:`bhgrasp.thesis.synthesis_case` (the thesis' box, whose synthesis is the thesis' pinch, and
the ball) lift their object 10 mm, then follow either a circle of :data:`RADIUS` (:class:`~bhgrasp.paths.PoseCircle`,
minimum-jerk in arc angle) in the plane the grasps translate in, the vertical y-z plane (F3 has no spread joint: no
grasp of the BH8-280 moves its object along x, and a horizontal circle is refused), or :data:`WAYPOINTS`: turns and
shifts joined by minimum-jerk blends that overlap (:class:`~bhgrasp.paths.PoseWaypoints`).  Each path is checked
against the grasp's manipulable space before simulating (its ``extremes``); the SMC-adaptive law, told half the
mass, tracks it (:class:`~bhgrasp.controllers.supervisor.GraspSupervisor` with ``path``).  Measured along the path
after the lift: the true centre of mass's distance from the reference, the orientation's angle from the
reference's, slip, the least cone margin of the commanded forces; at the end, the pose error against the path's end
(success as the motion table's, :data:`~bhgrasp.thesis.motions.SUCCESS`).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from functools import partial

import numpy as np
import pinocchio as pin

from bhgrasp.controllers.supervisor import GraspSupervisor
from bhgrasp.errors import InputError
from bhgrasp.grasp.metrics import slip_events_after
from bhgrasp.paths import PoseCircle, PoseWaypoints
from bhgrasp.scenarios.grasp_controllers import grasp_controller
from bhgrasp.scenarios.object_grasp import object_grasp
from bhgrasp.thesis.case import Case
from bhgrasp.thesis.motions import SUCCESS
from bhgrasp.thesis.synthesis_case import OBJECTS

RADIUS, CIRCLE_TIME, SETTLE = 0.004, 2.0, 0.5  # [m], [s], [s] after the path
LIFT, LIFT_TIME = (0.0, 0.0, 0.01), 0.5  # [m], [s]: the circle's lift
PLANES = {"y-z": ((0.0, 1.0, 0.0), (0.0, 0.0, 1.0)), "x-y": ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0))}
OVERLAP = 0.3  # [s] each waypoint move starts this long before the previous one ends
LIFT_MOVE = ((0.0, 0.0, 0.01, 0.0, 0.0, 0.0), 0.6)  # (offset, duration [s]): the waypoint paths' first move
WAYPOINTS = {  # object of the synthesis case -> the moves after the lift: (offset (dx [m], dtheta [rad]), [s])
    "box": [((0.0, 0.003, 0.0, 0.15, 0.0, 0.0), 0.8), ((0.0, -0.003, 0.0, -0.15, 0.0, 0.0), 0.8)],
    "ball": [((0.0, 0.0, 0.0, 0.0, 0.1, 0.0), 0.8), ((0.0, 0.0, 0.0, 0.1, -0.1, 0.0), 0.8),
             ((0.0, 0.0, 0.0, -0.1, 0.0, 0.0), 0.8)],
}  # fmt: skip


@dataclass(frozen=True)
class PathRun:
    """One object carried along a path: what the path asked and what the object did (SI units, world).

    Samples from the end of the path's lift on (the law, told half the mass, has caught up with the weight).
    """

    t: np.ndarray  # (k,) [s]
    reference: np.ndarray  # (k, 3) the path's centre of mass [m]
    position: np.ndarray  # (k, 3) the true centre of mass [m]
    max_deviation: float  # [m] largest distance from the path
    lift_deviation: float  # [m] largest distance from the path during the lift (before the samples above)
    rms_deviation: float  # [m]
    max_rotation: float  # [rad] largest angle between the object's orientation and the path's
    final_position_error: float  # [m] at the end, against the path's end
    final_rotation_error: float  # [rad]
    slip_events: int  # sliding hand-object samples after the grasp controller took over
    cone_margin: float  # [N] least mu f_n - |f_t| of the commanded forces while grasping

    @property
    def success(self) -> bool:
        """No slip and the final pose within the motion table's tolerance."""
        return (
            self.slip_events == 0 and self.final_position_error < SUCCESS[0] and self.final_rotation_error < SUCCESS[1]
        )


def circle(radius: float = RADIUS, plane: str = "y-z", duration: float = CIRCLE_TIME):
    """The supervisor's path factory of a :class:`~bhgrasp.paths.PoseCircle` after :data:`LIFT` in :data:`LIFT_TIME`."""
    return partial(PoseCircle, radius=radius, plane=PLANES[plane], duration=duration, lift=LIFT, lift_time=LIFT_TIME)


def waypoints(moves, overlap: float = OVERLAP):
    """The supervisor's path factory of :class:`~bhgrasp.paths.PoseWaypoints`: :data:`LIFT_MOVE`, then ``moves``."""
    return partial(PoseWaypoints, moves=[LIFT_MOVE, *moves], overlap=overlap)


def run_path(setup, path) -> PathRun:
    """Carry ``setup``'s object (:func:`~bhgrasp.scenarios.object_grasp.object_grasp`) along ``path``.

    ``path``: ``path(pose, delay=start) -> PoseCircle | PoseWaypoints`` (:func:`circle`, :func:`waypoints`).

    Raises:
        UnreachableError: A point of the path is outside the grasp's manipulable space (before simulating).
        InputError: ``path`` makes neither kind of path, or the grasp closed too late for the path to end in the run.
    """
    space = setup.manipulable_space()
    probe = path(pin.SE3.Identity())
    if not isinstance(probe, (PoseCircle, PoseWaypoints)):
        raise InputError(f"`path` must make a PoseCircle or PoseWaypoints, got {type(probe).__name__}")
    for offset in probe.extremes():
        space.check(offset)
    nominal = replace(setup.item, mass=0.5 * setup.item.mass, density=None)
    grasp = grasp_controller("smc-adaptive", setup.hand, nominal)
    supervisor = GraspSupervisor(setup.hand, setup.candidate.q_contact, grasp, path=path,
                                 fingers=setup.candidate.fingers)  # fmt: skip
    duration = 0.3 + supervisor.squeeze_time + probe.end_time + SETTLE  # the approach takes about 0.2 s
    traj = setup.simulator.run(supervisor, duration, state=setup.state, progress=False)
    reference, grasping = grasp.reference, np.flatnonzero(traj.log["phase"] >= 1)
    if len(grasping) == 0 or traj.t[-1] < reference.end_time:
        raise InputError(f"the grasp closed too late: the {duration:.2f} s run ends before the path does")
    closed = int(grasping[0])
    lifting = grasping[traj.t[grasping] < _lifted(reference)]
    on_path = grasping[traj.t[grasping] >= _lifted(reference)]
    lift_gap = [np.linalg.norm(traj.object_position[k, 0] - reference(traj.t[k])[0][:3]) for k in lifting]
    samples = [reference(t)[0] for t in traj.t[on_path]]
    wanted = np.array([sample[:3] for sample in samples])
    position = traj.object_position[on_path, 0]
    deviation = np.linalg.norm(position - wanted, axis=1)
    turns = [_turn(traj.object_quaternion[k, 0], pin.exp3(sample[3:])) for k, sample in zip(on_path, samples)]
    end = reference(traj.t[-1])[0]
    return PathRun(
        t=traj.t[on_path], reference=wanted, position=position, max_deviation=float(deviation.max()),
        lift_deviation=float(max(lift_gap, default=0.0)),
        rms_deviation=float(np.sqrt(np.mean(deviation**2))), max_rotation=float(max(turns)),
        final_position_error=float(np.linalg.norm(traj.object_position[-1, 0] - end[:3])),
        final_rotation_error=_turn(traj.object_quaternion[-1, 0], pin.exp3(end[3:])),
        slip_events=slip_events_after(setup.hand, traj, closed),
        cone_margin=float(np.nanmin(traj.log["cone_margin"][grasping])),
    )  # fmt: skip


def _lifted(reference) -> float:
    """When the path's lift ends [s] (a waypoint path's first move is its lift, :func:`waypoints`)."""
    if isinstance(reference, PoseCircle):
        return reference.delay + reference.lift_time
    return float(reference.starts[0] + reference.durations[0])


def _turn(quaternion: np.ndarray, held: np.ndarray) -> float:
    x, y, z, w = quaternion
    return float(np.linalg.norm(pin.log3(held.T @ pin.Quaternion(w, x, y, z).toRotationMatrix())))


def path_case(scale: float = 1.0):
    """The chapter-5 case (paths of ``scale`` x their durations after the lift)."""
    header = ["object and grasp", "path", "outcome", "max / rms deviation after the lift [mm]",
              "max deviation in the lift [mm]", "max turn off the path [mrad]", "final error [mm] / [mrad]",
              "slip samples", "least cone margin [N]"]  # fmt: skip
    case = Case("paths", "Continuous paths: grasped objects carried around a circle and through waypoints",
                "-", header)  # fmt: skip
    circles: dict[str, PathRun] = {}
    for key in WAYPOINTS:
        label, item = OBJECTS[key]
        setup = object_grasp(item)
        moves = [(offset, duration * scale) for offset, duration in WAYPOINTS[key]]  # (the overlap scales too)
        paths = {"circle": (circle(duration=CIRCLE_TIME * scale), f"circle r {1e3 * RADIUS:g} mm, y-z plane, "
                            f"{CIRCLE_TIME * scale:g} s"),
                 "waypoints": (waypoints(moves, OVERLAP * scale), _describe(moves))}  # fmt: skip
        for name, (path, description) in paths.items():
            run = run_path(setup, path)
            if name == "circle":
                circles[key] = run
            case.table.append([
                f"{label} (synthesised)", description, "success" if run.success else "failed",
                f"{1e3 * run.max_deviation:.3f} / {1e3 * run.rms_deviation:.3f}", f"{1e3 * run.lift_deviation:.3f}",
                f"{1e3 * run.max_rotation:.2f}",
                f"{1e3 * run.final_position_error:.3f} / {1e3 * run.final_rotation_error:.2f}", str(run.slip_events),
                f"{run.cone_margin:.2f}",
            ])  # fmt: skip
            case.values.update({f"{key}/{name}/{field}": value for field, value in (
                ("success", float(run.success)), ("max_deviation_mm", 1e3 * run.max_deviation),
                ("rms_deviation_mm", 1e3 * run.rms_deviation), ("lift_deviation_mm", 1e3 * run.lift_deviation),
                ("max_rotation_mrad", 1e3 * run.max_rotation),
                ("final_error_mm", 1e3 * run.final_position_error),
                ("final_rotation_mrad", 1e3 * run.final_rotation_error), ("slip_events", float(run.slip_events)),
                ("cone_margin_N", run.cone_margin))})  # fmt: skip
    case.notes += [
        f"Circle (`bhgrasp.paths.PoseCircle`): a {1e3 * LIFT[2]:g} mm lift in {LIFT_TIME:g} s, then once around a "
        "circle through the lifted "
        f"point, of radius {1e3 * RADIUS:g} mm, the arc angle on a minimum-jerk blend (at rest at both ends), the "
        "orientation held; checked against the grasp's manipulable space at eight of its points before simulating "
        "(a circle with a component along x is refused: F3 cannot move along x).",
        f"Waypoints (`bhgrasp.paths.PoseWaypoints`): a {1e3 * LIFT_MOVE[0][2]:g} mm lift in {LIFT_MOVE[1]:g} s, then "
        f"the moves listed, each a minimum-jerk blend starting {OVERLAP * scale:g} s before the previous one ends, so "
        "that the object passes "
        "the inner waypoints without stopping; checked at every waypoint before simulating.",
        "Deviation: the true centre of mass's distance from the path's, in the lift and from the end of the lift to "
        "the end of the run; turn: the angle between the object's orientation and the path's.  The SMC-adaptive law "
        "starts from half the mass: the largest deviations come in the lift, as the estimate rises.",
    ]
    case.figures["chapter5_paths.png"] = lambda: _figure(circles)
    return case


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
        axis.plot(1e3 * (run.reference[:, 1] - origin[1]), 1e3 * (run.reference[:, 2] - origin[2]), "k--", lw=1.0,
                  label="path")  # fmt: skip
        axis.plot(1e3 * (run.position[:, 1] - origin[1]), 1e3 * (run.position[:, 2] - origin[2]), lw=1.0,
                  label="object (true)")  # fmt: skip
        axis.set(xlabel="y [mm]", ylabel="z [mm]", title=f"{key}: circle in the y-z plane", aspect="equal")
        axis.grid(alpha=0.3)
        axis.legend(fontsize=7)
    return figure


__all__ = ["LIFT", "LIFT_MOVE", "LIFT_TIME", "OVERLAP", "PLANES", "RADIUS", "WAYPOINTS", "PathRun", "circle",
           "path_case", "run_path", "waypoints"]  # fmt: skip
