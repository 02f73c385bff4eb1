"""The grasp demo's result: the run and its figures of merit (of :mod:`bhgrasp.scenarios.grasp_demo`)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from bhgrasp.data import Trajectory
from bhgrasp.errors import InputError
from bhgrasp.grasp.metrics import finger_normal_forces, sliding_distances, slip_events_after
from bhgrasp.scenarios.uncertainty import final_pose_error
from bhgrasp.sim.scene import Scene

if TYPE_CHECKING:
    from bhgrasp.scenarios.grasp_choice import GraspChoice

MU_ASSUMED = 0.6  # the true friction is 0.8
SUCCESS = (0.5e-3, 5e-3)  # [m], [rad] a moved object's final error against the request (with no sliding sample)


@dataclass
class GraspDemoResult:
    """The run and its figures of merit (errors at the end; force error over the settled window).

    Times [s] are absolute: the grasp closes at ``grasp_time``, the object moves from ``motion_start`` to
    ``motion_end``, and the force error is taken from ``settle_time`` on.  ``q_contact`` is the IK contact
    configuration the approach aimed at; ``scene`` the simulated scene (for :mod:`bhgrasp.viz`).
    ``position_error`` and ``rotation_error`` are the controller's own (its last logged error, from what it sensed);
    ``true_position_error`` and ``true_rotation_error`` compare the object's true final pose with the requested
    motion's end (they differ when the sensors are noisy or late, :class:`~bhgrasp.sim.sensor_model.SensorModel`, or
    when the supervisor planned a motion other than the one requested: ``planned_offset``, ``None`` before the move;
    ``requested_offset`` the request).  ``grasp_choice``: the pinch the motion was given to, and why others were
    refused (:mod:`bhgrasp.scenarios.grasp_choice`).  ``slide`` [m]: the farthest a hand link slid on the object
    after the grasp closed (:func:`~bhgrasp.grasp.metrics.sliding_distances`), where ``slip_events`` counts the
    contact samples at the Coulomb limit, a patch's lightly loaded edge among them.
    """

    trajectory: Trajectory
    controller: str
    true_mass: float
    initial_estimate: float
    mass_estimate: float | None
    grasp_time: float
    motion_start: float
    motion_end: float
    settle_time: float
    position_error: float
    rotation_error: float
    force_error: float
    slip_events: int
    cone_margin: float
    infeasible_samples: int
    wall_time: float
    q_contact: np.ndarray
    scene: Scene
    true_position_error: float = float("nan")
    true_rotation_error: float = float("nan")
    planned_offset: np.ndarray | None = None
    requested_offset: np.ndarray | None = None
    grasp_choice: GraspChoice | None = None
    slide: float = float("nan")

    @property
    def object_label(self) -> str:
        """The grasped object in the summary: its name, or its shape's (``box``) if it was given none."""
        item = self.scene.objects[0]
        return item.name or type(item).__name__.lower()

    def summary(self) -> str:
        """A few lines for the terminal."""
        duration = float(self.trajectory.t[-1])
        estimate = "" if self.mass_estimate is None else f", estimated {self.mass_estimate:.3f} kg"
        motion = f"motion {self.motion_start:.2f}-{self.motion_end:.2f} s"
        final, window = "final", f"max over fingers from {self.settle_time:.2f} s"
        if duration < self.motion_end:  # a short run: say what the numbers are
            stage = "before the motion" if duration < self.motion_start else "during the motion"
            motion += f" (the run ended at {duration:.2f} s, {stage})"
            final = "at the end of the run, not the motion's final error"
        if duration < self.settle_time:
            window = f"at the last sample: the run ended before the forces settle at {self.settle_time:.2f} s"
        return "\n".join(
            [
                f"grasp demo ({self.scene.hand.name}, {self.controller}): {self.object_label} {self.true_mass:.2f} kg, "
                f"controller told {self.initial_estimate:.2f} kg{estimate}",
                f"  grasp closed at {self.grasp_time:.3f} s; {motion}",
                f"  object pose error: {1e3 * self.position_error:.3f} mm, "
                f"{1e3 * self.rotation_error:.3f} mrad ({final})",
                *self._plan_lines(),
                f"  contact force error: {100 * self.force_error:.2f} % of the commanded normal force ({window})",
                f"  slip events: {self.slip_events} (sliding hand-object contact samples after the grasp closed; "
                f"the farthest a link slid: {1e3 * self.slide:.3f} mm)",
                f"  commanded forces: min cone margin {self.cone_margin:.3f} N at mu {MU_ASSUMED}, "
                f"{self.infeasible_samples} infeasible samples",
                f"  time: {duration:.2f} s simulated in {self.wall_time:.1f} s wall",
            ]
        )

    def _plan_lines(self) -> list[str]:
        """The planned motion and the error against the request, when the supervisor changed the motion."""
        requested = self.requested_offset
        if self.planned_offset is None or requested is None or np.allclose(self.planned_offset, requested, 0, 1e-12):
            return []
        return [
            f"  planned motion {np.round(self.planned_offset, 5).tolist()} (m, rad) for the requested "
            f"{np.round(requested, 5).tolist()}: the part the grasp makes without sliding",
            f"  true pose error against the request: {1e3 * self.true_position_error:.3f} mm, "
            f"{1e3 * self.true_rotation_error:.3f} mrad",
        ]


def evaluate_demo(traj, hand, controller, mass, estimate, supervisor, wall, scene) -> GraspDemoResult:
    """A supervised grasp run's figures of merit (the grasp closes when the supervisor's phase first leaves 0).

    Slip samples are counted from the sample after that one: the contacts of the switching sample are the approach's
    (a pad that has just touched may skid for that millisecond, as the can's F3 does at 0.18 N).

    Raises:
        InputError: The fingers never closed on the object (nothing to evaluate).
    """
    phase = traj.log["phase"]
    if not np.any(phase >= 1):
        raise InputError(f"the fingers did not close on the object within {traj.t[-1]:.2f} s (no grasp to evaluate)")
    closed = int(np.argmax(phase >= 1))
    grasp_time = float(traj.t[closed])
    motion_start = grasp_time + supervisor.squeeze_time
    motion_end = motion_start + supervisor.move_time
    settle = motion_end + 0.5
    settled = traj.t >= min(settle, float(traj.t[-1]))
    measured = finger_normal_forces(hand, traj)[settled]
    commanded = traj.log["commanded_normal"][settled]
    force_error = float(np.max(np.abs(measured - commanded) / np.maximum(commanded, 1e-9)))
    error = traj.log["object_error"][-1]
    true_error = final_pose_error(traj, supervisor)
    grasping = phase >= 1
    estimate_log = traj.log.get("mass_estimate")
    final_estimate = None if estimate_log is None else float(np.ravel(estimate_log[-1])[0])
    return GraspDemoResult(
        trajectory=traj,
        controller=controller,
        true_mass=mass,
        initial_estimate=estimate,
        mass_estimate=final_estimate if controller in ("smc-adaptive",) else None,
        grasp_time=grasp_time,
        motion_start=motion_start,
        motion_end=motion_end,
        settle_time=settle,
        position_error=float(np.linalg.norm(error[:3])),
        rotation_error=float(np.linalg.norm(error[3:])),
        force_error=force_error,
        slip_events=slip_events_after(hand, traj, closed),
        slide=max(sliding_distances(hand, traj, float(traj.t[min(closed + 1, len(traj.t) - 1)])).values(), default=0.0),
        cone_margin=float(np.nanmin(traj.log["cone_margin"][grasping])),
        infeasible_samples=int(np.sum(traj.log["feasible"][grasping] < 1.0)),
        wall_time=wall,
        q_contact=supervisor.q_contact,
        scene=scene,
        true_position_error=float(np.linalg.norm(true_error[:3])),
        true_rotation_error=float(np.linalg.norm(true_error[3:])),
        planned_offset=None if supervisor.planned_offset is None else supervisor.planned_offset.copy(),
        requested_offset=supervisor.offset.copy(),
    )


__all__ = ["MU_ASSUMED", "SUCCESS", "GraspDemoResult", "evaluate_demo"]
