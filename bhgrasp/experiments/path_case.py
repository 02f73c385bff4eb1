"""The chapter-5 path case: grasped objects carried around a circle (issue 17, item 3, continuous paths).

Two grasps of :mod:`bhgrasp.experiments.synthesis_case` (the thesis' box, whose synthesis is the thesis' pinch, and
the ball) lift their object 10 mm and carry it once around a circle of :data:`RADIUS`
(:class:`~bhgrasp.paths.PoseCircle`, minimum-jerk in arc angle) in the plane the grasps translate in, the vertical
y-z plane (F3 has no spread joint: no grasp of the BH8-280 moves its object along x, and a horizontal circle is
refused).  The path is checked against the grasp's manipulable space before simulating
(:meth:`~bhgrasp.paths.PoseCircle.extremes`); the SMC-adaptive law, told half the mass, tracks it
(:class:`~bhgrasp.controllers.supervisor.GraspSupervisor` with ``path``).  Measured along the circle: the true centre
of mass's distance from the reference, the orientation's, slip, the least cone margin of the commanded forces; at
the end, the pose error against the path's end (success as the motion table's,
:data:`~bhgrasp.experiments.motions.SUCCESS`).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from functools import partial

import numpy as np
import pinocchio as pin

from bhgrasp.controllers.supervisor import GraspSupervisor
from bhgrasp.experiments.grasp_demo import grasp_controller
from bhgrasp.experiments.motions import SUCCESS
from bhgrasp.grasp.metrics import slip_events
from bhgrasp.paths import PoseCircle

RADIUS, CIRCLE_TIME, SETTLE = 0.004, 2.0, 0.5  # [m], [s], [s] after the circle
PLANES = {"y-z": ((0.0, 1.0, 0.0), (0.0, 0.0, 1.0)), "x-y": ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0))}
RUNS = {"box": "y-z", "ball": "y-z"}  # object of the synthesis case -> circle plane


@dataclass(frozen=True)
class CircleRun:
    """One object carried around the circle: what the path asked and what the object did (SI units, world)."""

    t: np.ndarray  # (k,) [s] samples on the circle
    reference: np.ndarray  # (k, 3) the path's centre of mass [m]
    position: np.ndarray  # (k, 3) the true centre of mass [m]
    max_deviation: float  # [m] largest distance from the path on the circle
    rms_deviation: float  # [m]
    max_rotation: float  # [rad] largest turn away from the held orientation on the circle
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


def run_circle(setup, plane: str, radius: float = RADIUS, circle_time: float = CIRCLE_TIME) -> CircleRun:
    """Carry ``setup``'s object (:func:`~bhgrasp.experiments.object_grasp.object_grasp`) around a circle in ``plane``.

    Raises:
        UnreachableError: A point of the circle is outside the grasp's manipulable space (before simulating).
    """
    path = partial(PoseCircle, radius=radius, plane=PLANES[plane], duration=circle_time)
    space = setup.manipulable_space()
    for offset in path(pin.SE3.Identity()).extremes():
        space.check(offset)
    nominal = replace(setup.item, mass=0.5 * setup.item.mass, density=None)
    grasp = grasp_controller("smc-adaptive", setup.hand, nominal)
    supervisor = GraspSupervisor(setup.hand, setup.candidate.q_contact, grasp, path=path,
                                 fingers=setup.candidate.fingers)  # fmt: skip
    probe = path(pin.SE3.Identity())
    duration = 0.3 + supervisor.squeeze_time + probe.end_time + SETTLE  # the approach takes about 0.2 s
    traj = setup.simulator.run(supervisor, duration, state=setup.state, progress=False)
    reference = grasp.reference
    grasping = np.flatnonzero(traj.log["phase"] >= 1)
    closed = int(grasping[0])
    on_circle = grasping[traj.t[grasping] >= reference.delay + reference.lift_time]
    wanted = np.array([reference(t)[0][:3] for t in traj.t[on_circle]])
    position = traj.object_position[on_circle, 0]
    deviation = np.linalg.norm(position - wanted, axis=1)
    turns = [_turn(traj.object_quaternion[k, 0], reference.start.rotation) for k in on_circle]
    end = reference(traj.t[-1])[0][:3]
    return CircleRun(
        t=traj.t[on_circle], reference=wanted, position=position, max_deviation=float(deviation.max()),
        rms_deviation=float(np.sqrt(np.mean(deviation**2))), max_rotation=float(max(turns)),
        final_position_error=float(np.linalg.norm(traj.object_position[-1, 0] - end)), final_rotation_error=turns[-1],
        slip_events=slip_events(setup.hand, traj, float(traj.t[min(closed + 1, len(traj.t) - 1)])),
        cone_margin=float(np.nanmin(traj.log["cone_margin"][grasping])),
    )  # fmt: skip


def _turn(quaternion: np.ndarray, held: np.ndarray) -> float:
    x, y, z, w = quaternion
    return float(np.linalg.norm(pin.log3(held.T @ pin.Quaternion(w, x, y, z).toRotationMatrix())))


def path_case(scale: float = 1.0):
    """The chapter-5 case (circles of ``scale`` x :data:`CIRCLE_TIME`)."""
    from bhgrasp.experiments.chapter5 import Case
    from bhgrasp.experiments.object_grasp import object_grasp
    from bhgrasp.experiments.synthesis_case import OBJECTS

    header = ["object and grasp", "circle", "outcome", "max / rms deviation [mm]", "max turn [mrad]",
              "final error [mm] / [mrad]", "slip samples", "least cone margin [N]"]  # fmt: skip
    case = Case("paths", "Continuous paths (issue 17): grasped objects carried around a circle", "-", header)
    runs: dict[str, CircleRun] = {}
    for key, plane in RUNS.items():
        label, item = OBJECTS[key]
        run = runs[key] = run_circle(object_grasp(item), plane, circle_time=CIRCLE_TIME * scale)
        case.table.append([
            f"{label} (synthesised)", f"r {1e3 * RADIUS:g} mm in the {plane} plane, {CIRCLE_TIME * scale:g} s",
            "success" if run.success else "failed", f"{1e3 * run.max_deviation:.3f} / {1e3 * run.rms_deviation:.3f}",
            f"{1e3 * run.max_rotation:.2f}",
            f"{1e3 * run.final_position_error:.3f} / {1e3 * run.final_rotation_error:.2f}", str(run.slip_events),
            f"{run.cone_margin:.2f}",
        ])  # fmt: skip
        case.values.update({f"{key}/success": float(run.success), f"{key}/max_deviation_mm": 1e3 * run.max_deviation,
                            f"{key}/rms_deviation_mm": 1e3 * run.rms_deviation,
                            f"{key}/max_rotation_mrad": 1e3 * run.max_rotation,
                            f"{key}/final_error_mm": 1e3 * run.final_position_error,
                            f"{key}/final_rotation_mrad": 1e3 * run.final_rotation_error,
                            f"{key}/slip_events": float(run.slip_events),
                            f"{key}/cone_margin_N": run.cone_margin})  # fmt: skip
    case.notes += [
        "The path (`bhgrasp.paths.PoseCircle`): a 10 mm lift in 0.5 s, then once around a circle through the lifted "
        f"point, of radius {1e3 * RADIUS:g} mm, in {CIRCLE_TIME * scale:g} s, the arc angle on a minimum-jerk blend "
        "(at rest at both ends), the orientation held; checked against the grasp's manipulable space at eight of its "
        "points before simulating (a circle with a component along x is refused: F3 cannot move along x).",
        "Deviation: the true centre of mass's distance from the path's, from the end of the lift to the end of the "
        "run; turn: the orientation's angle from the held one.  The SMC-adaptive law starts from half the mass (the "
        "largest deviations come as the estimate rises during the lift and the circle's first half).",
    ]
    case.figures["chapter5_paths.png"] = lambda: _figure(runs)
    return case


def _figure(runs: dict[str, CircleRun]):
    from bhgrasp.plots import Figure

    figure = Figure(figsize=(9, 4), layout="tight")
    for axis, (key, run) in zip(figure.subplots(1, len(runs)), runs.items()):
        u, v = (np.flatnonzero(np.array(axis_vector))[0] for axis_vector in PLANES[RUNS[key]])
        origin = run.reference[0]
        axis.plot(1e3 * (run.reference[:, u] - origin[u]), 1e3 * (run.reference[:, v] - origin[v]), "k--", lw=1.0,
                  label="path")  # fmt: skip
        axis.plot(1e3 * (run.position[:, u] - origin[u]), 1e3 * (run.position[:, v] - origin[v]), lw=1.0,
                  label="object (true)")  # fmt: skip
        names = "xyz"
        axis.set(
            xlabel=f"{names[u]} [mm]", ylabel=f"{names[v]} [mm]", title=f"{key}: {RUNS[key]} circle", aspect="equal"
        )
        axis.grid(alpha=0.3)
        axis.legend(fontsize=7)
    return figure


__all__ = ["PLANES", "RADIUS", "RUNS", "CircleRun", "path_case", "run_circle"]
