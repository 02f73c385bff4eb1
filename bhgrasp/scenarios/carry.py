"""Grasped objects carried along continuous paths: a circle (:func:`circle`) or waypoints (:func:`waypoints`).

:func:`run_path` takes a grasp planned by :func:`~bhgrasp.scenarios.object_grasp.object_grasp`, lifts its object 10 mm,
then follows the path: a circle (:class:`~bhgrasp.motion.paths.PoseCircle`, minimum-jerk in arc angle) in a plane of
:data:`PLANES`, or turns and shifts joined by minimum-jerk blends that overlap
(:class:`~bhgrasp.motion.paths.PoseWaypoints`; :data:`WAYPOINTS` holds moves for two objects of
:data:`~bhgrasp.scenarios.object_grasp.OBJECTS`).  The path is checked against the grasp's manipulable space before
simulating (its ``extremes``); the SMC-adaptive law, told half the mass, tracks it
(:class:`~bhgrasp.controllers.supervisor.GraspSupervisor` with ``path``).  Measured along the path after the lift: the
true centre of mass's distance from the reference, the orientation's angle from the reference's, slip, the least cone
margin of the commanded forces; at the end, the pose error against the path's end (success:
:data:`~bhgrasp.scenarios.demo_result.SUCCESS`).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from functools import partial

import numpy as np
import pinocchio as pin

from bhgrasp.controllers.supervisor import GraspSupervisor
from bhgrasp.errors import InputError
from bhgrasp.grasp.metrics import slip_events_after
from bhgrasp.motion.paths import PoseCircle, PoseWaypoints
from bhgrasp.scenarios.demo_result import SUCCESS
from bhgrasp.scenarios.grasp_controllers import grasp_controller

RADIUS, CIRCLE_TIME, SETTLE = 0.004, 2.0, 0.5  # [m], [s], [s] after the path
LIFT, LIFT_TIME = (0.0, 0.0, 0.01), 0.5  # [m], [s]: the circle's lift
PLANES = {"y-z": ((0.0, 1.0, 0.0), (0.0, 0.0, 1.0)), "x-y": ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0))}
OVERLAP = 0.3  # [s] each waypoint move starts this long before the previous one ends
LIFT_MOVE = ((0.0, 0.0, 0.01, 0.0, 0.0, 0.0), 0.6)  # (offset, duration [s]): the waypoint paths' first move
WAYPOINTS = {  # object of OBJECTS -> the moves after the lift: (offset (dx [m], dtheta [rad]), [s])
    "box": [((0.0, 0.003, 0.0, 0.15, 0.0, 0.0), 0.8), ((0.0, -0.003, 0.0, -0.15, 0.0, 0.0), 0.8)],
    "ball": [
        ((0.0, 0.0, 0.0, 0.0, 0.1, 0.0), 0.8),
        ((0.0, 0.0, 0.0, 0.1, -0.1, 0.0), 0.8),
        ((0.0, 0.0, 0.0, -0.1, 0.0, 0.0), 0.8),
    ],
}


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
    """The supervisor's path factory of a :class:`~bhgrasp.motion.paths.PoseCircle`.

    The circle follows :data:`LIFT` made in :data:`LIFT_TIME`.
    """
    return partial(PoseCircle, radius=radius, plane=PLANES[plane], duration=duration, lift=LIFT, lift_time=LIFT_TIME)


def waypoints(moves, overlap: float = OVERLAP):
    """The supervisor's path factory of :class:`~bhgrasp.motion.paths.PoseWaypoints`.

    The waypoint moves are :data:`LIFT_MOVE`, then ``moves``.
    """
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
    supervisor = GraspSupervisor(
        setup.hand, setup.candidate.q_contact, grasp, path=path, fingers=setup.candidate.fingers
    )
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
        t=traj.t[on_path],
        reference=wanted,
        position=position,
        max_deviation=float(deviation.max()),
        lift_deviation=float(max(lift_gap, default=0.0)),
        rms_deviation=float(np.sqrt(np.mean(deviation**2))),
        max_rotation=float(max(turns)),
        final_position_error=float(np.linalg.norm(traj.object_position[-1, 0] - end[:3])),
        final_rotation_error=_turn(traj.object_quaternion[-1, 0], pin.exp3(end[3:])),
        slip_events=slip_events_after(setup.hand, traj, closed),
        cone_margin=float(np.nanmin(traj.log["cone_margin"][grasping])),
    )


def _lifted(reference) -> float:
    """When the path's lift ends [s] (a waypoint path's first move is its lift, :func:`waypoints`)."""
    if isinstance(reference, PoseCircle):
        return reference.delay + reference.lift_time
    return float(reference.starts[0] + reference.durations[0])


def _turn(quaternion: np.ndarray, held: np.ndarray) -> float:
    x, y, z, w = quaternion
    return float(np.linalg.norm(pin.log3(held.T @ pin.Quaternion(w, x, y, z).toRotationMatrix())))


__all__ = [
    "CIRCLE_TIME",
    "LIFT",
    "LIFT_MOVE",
    "LIFT_TIME",
    "OVERLAP",
    "PLANES",
    "RADIUS",
    "SETTLE",
    "WAYPOINTS",
    "PathRun",
    "circle",
    "run_path",
    "waypoints",
]
