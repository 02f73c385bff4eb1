"""How far the rigid-grasp model of :mod:`bhgrasp.controllers.object_estimator` carries a held object.

:func:`rigid_model_residual` replays a recorded run: from the instant three fingers hold the object, it moves the
object's true pose at that instant with the anchors' rigid motion alone (the encoders, no tracker) and compares it
with the true pose.  What it misses (rolling, the contacts' compliance, slip) is the residual; :func:`drift_rate`
turns it into the random walk rate the filter's :class:`~bhgrasp.controllers.object_estimator.EstimatorSettings`
take, and :func:`rigid_model_drift` measures both on the grasp demo with exact sensing.
"""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np
import pinocchio as pin

from bhgrasp._validation import as_positive
from bhgrasp.controllers.object_estimator import HeldObjectEstimator
from bhgrasp.data import State, Trajectory
from bhgrasp.errors import InputError
from bhgrasp.grasp.rigid_fit import rigid_fit
from bhgrasp.model.hand import Hand


def pose_at(trajectory: Trajectory, k: int, index: int = 0) -> pin.SE3:
    """Object ``index``'s recorded pose at sample ``k``."""
    return pin.XYZQUATToSE3(
        np.concatenate((trajectory.object_position[k, index], trajectory.object_quaternion[k, index]))
    )


def state_at(trajectory: Trajectory, k: int, index: int = 0) -> State:
    """Recorded sample ``k`` as the controller's :class:`~bhgrasp.data.state.State` (object ``index`` only)."""
    contacts = trajectory.contacts_at(k)
    return State(
        float(trajectory.t[k]),
        trajectory.q[k],
        trajectory.v[k],
        object_poses=(pose_at(trajectory, k, index),),
        object_twists=trajectory.object_twist[k, index][None],
        contact_points=contacts["point"],
        contact_normals=contacts["normal"],
        contact_forces=contacts["force"],
        contact_bodies=tuple((str(a), str(b)) for a, b in contacts["bodies"]),
    )


def states_of(trajectory: Trajectory, index: int = 0) -> Iterator[State]:
    """The recorded samples as the controller's :class:`~bhgrasp.data.state.State` (object ``index`` only)."""
    for k in range(len(trajectory.t)):
        yield state_at(trajectory, k, index)


def rigid_model_residual(hand: Hand, trajectory: Trajectory) -> tuple[np.ndarray, np.ndarray]:
    """Times [s] (n,) from the hold and the residual (n, 6): true pose minus the rigidly carried one (world).

    Position [m] then rotation log(R_true R_carried^T) [rad].

    Raises:
        InputError: Three fingers never hold the object in ``trajectory``.
    """
    estimator = HeldObjectEstimator(hand)
    start = None
    times, residuals = [], []
    for state in states_of(trajectory):
        if start is None:
            if not estimator.anchor(state):
                continue
            start = (estimator.anchor_points(state.q), state.object_poses[0])
        turn, shift = rigid_fit(start[0], estimator.anchor_points(state.q))
        pose = state.object_poses[0]
        carried_position = turn @ start[1].translation + shift
        carried_rotation = turn @ start[1].rotation
        times.append(state.t)
        residuals.append(
            np.concatenate((pose.translation - carried_position, pin.log3(pose.rotation @ carried_rotation.T)))
        )
    if start is None:
        raise InputError("three fingers never hold the object in this trajectory: no rigid grasp to follow")
    return np.array(times), np.array(residuals)


def drift_rate(times: np.ndarray, residual: np.ndarray, lag: float) -> tuple[float, float]:
    """(sqrt(q_p) [m/sqrt(s)], sqrt(q_r) [rad/sqrt(s)]): a random walk's rate fitted to a residual (n, 6).

    The rms change of a component over ``lag`` [s], per sqrt(lag); position and rotation components pooled.
    """
    lag = as_positive(lag, "lag")
    steps = round(lag / float(np.median(np.diff(times))))
    if steps < 1 or steps >= len(times):
        raise InputError(f"`lag` {lag} s must span 1 to {len(times) - 1} samples of the residual")
    change = residual[steps:] - residual[:-steps]
    span_s = float(np.mean(times[steps:] - times[:-steps]))
    return (
        float(np.sqrt(np.mean(change[:, :3] ** 2) / span_s)),
        float(np.sqrt(np.mean(change[:, 3:] ** 2) / span_s)),
    )


def pre_hold_motion(times: np.ndarray, trajectory: Trajectory) -> tuple[np.ndarray, np.ndarray]:
    """Times [s] and the object's true pose minus its first (n, 6) (world) before ``times[0]``, the hold's start."""
    before = trajectory.t < times[0]
    poses = [pose_at(trajectory, k) for k in np.flatnonzero(before)]
    first = poses[0]
    motion = [
        np.concatenate((pose.translation - first.translation, pin.log3(pose.rotation @ first.rotation.T)))
        for pose in poses
    ]
    return trajectory.t[before], np.array(motion)


def rigid_model_drift(
    masses: tuple[float, ...] = (0.2, 0.6, 1.0), lag: float = 1.0, free_lag: float = 0.05
) -> dict[float, dict[str, tuple[float, float]]]:
    """Per box mass [kg], the grasp demo's rates (exact sensing) that set the estimator's defaults.

    ``"held"``: the rigid model's :func:`drift_rate` over ``lag`` [s]; ``"free"``: the box's own over ``free_lag``
    [s] before the hold (:func:`pre_hold_motion`).
    """
    from bhgrasp.scenarios.grasp_demo import run_grasp_demo

    rates = {}
    for mass in masses:
        result = run_grasp_demo(mass=mass, estimate=0.5)
        times, residual = rigid_model_residual(result.scene.hand, result.trajectory)
        rates[mass] = {
            "held": drift_rate(times, residual, lag),
            "free": drift_rate(*pre_hold_motion(times, result.trajectory), free_lag),
        }
    return rates


__all__ = [
    "drift_rate",
    "pose_at",
    "pre_hold_motion",
    "rigid_model_drift",
    "rigid_model_residual",
    "state_at",
    "states_of",
]
