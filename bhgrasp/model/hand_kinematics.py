"""A hand's kinematics: frame poses, fingertip positions, Jacobians and bias accelerations.

Free functions over a :class:`~bhgrasp.model.hand.Hand` (which offers each as a method of the same name):
Pinocchio's forward kinematics and frame Jacobians, world-aligned, with the hand's base placement
(:attr:`~bhgrasp.model.hand.Hand.base`) applied.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
import pinocchio as pin

from bhgrasp._validation import as_array, as_vector
from bhgrasp.model.hand_description import HandDescription as Hand


def frame_placement(hand: Hand, q: Any, frame: str) -> pin.SE3:
    """Pose of a frame in the world, ``transform_frame_to_world``."""
    frame_id = hand.frame_id(frame)
    pin.framesForwardKinematics(hand.model, hand.data, hand.check_q(q))
    return hand.base.placement * hand.data.oMf[frame_id]


def fingertip_positions(hand: Hand, q: Any) -> np.ndarray:
    """Fingertip frame origins in the world [m], shape (n_fingers, 3), in :attr:`fingers` order."""
    pin.framesForwardKinematics(hand.model, hand.data, hand.check_q(q))
    points = np.array([hand.data.oMf[i].translation for i in hand.fingertip_ids])
    base = hand.base
    return points if base.at_origin else points @ base.rotation.T + base.translation


def frame_jacobian(hand: Hand, q: Any, frame: str) -> np.ndarray:
    """Spatial Jacobian of a frame, shape (6, nv): rows (linear, angular), world-aligned, at the frame origin."""
    return _jacobian(hand, hand.check_q(q), hand.frame_id(frame), 6)


def fingertip_jacobian(hand: Hand, q: Any, finger: str) -> np.ndarray:
    """Translational Jacobian of a fingertip, shape (3, nv), world-aligned: ``p_dot_world = J v``."""
    return _jacobian(hand, hand.check_q(q), hand.fingertip_id(finger), 3)


def point_jacobian(hand: Hand, q: Any, frame: str, point: Any) -> np.ndarray:
    """Translational Jacobian (3, nv), world-aligned, of a point [m, world] fixed on ``frame``'s body at ``q``.

    J_p = J_lin - skew(p - o) J_ang with the frame's spatial Jacobian at its origin o (the point moves with the
    body: v_p = v_o + omega x (p - o)).
    """
    point = as_vector(point, "point", 3)
    jacobian = frame_jacobian(hand, q, frame)
    origin = frame_placement(hand, q, frame).translation  # world, base placement included
    return jacobian[:3] - pin.skew(point - origin) @ jacobian[3:]


def point_jacobians(hand: Hand, q: Any, frames: Sequence[str], points: Any) -> np.ndarray:
    """:meth:`point_jacobian` of several points at once, shape (n, 3, nv): one kinematics pass for all.

    Args:
        q: Configuration [rad].
        frames: n frame names, the body each point is fixed on.
        points: (n, 3) points [m], world.
    """
    points = as_array(points, "points", (len(frames), 3))
    model, data = hand.model, hand.data
    pin.computeJointJacobians(model, data, hand.check_q(q))  # also places the joints (data.oMi)
    base = hand.base
    if not base.at_origin:
        points = (points - base.translation) @ base.rotation  # base-frame points
    result = np.empty((len(frames), 3, model.nv))
    for i, frame in enumerate(frames):
        joint = model.frames[hand.frame_id(frame)].parentJoint
        on_joint = pin.SE3(np.eye(3), data.oMi[joint].actInv(points[i]))  # the point, fixed on its body
        jacobian = pin.getFrameJacobian(model, data, joint, on_joint, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)
        result[i] = np.reshape(jacobian, (6, model.nv))[:3]  # (a one-joint model's comes back as a vector)
    if not base.at_origin:
        result = np.einsum("ij,njk->nik", base.rotation, result)
    return result


def fingertip_bias_acceleration(hand: Hand, q: Any, v: Any, finger: str) -> np.ndarray:
    """J_dot(q, v) v: the fingertip's classical acceleration at zero joint acceleration, world frame [m/s^2].

    With it, fingertip acceleration = ``fingertip_jacobian(q, finger) @ a + fingertip_bias_acceleration(q, v)``.
    """
    frame_id = hand.fingertip_id(finger)
    q, v = hand.check_q(q), hand.check_v(v, "v")
    pin.forwardKinematics(hand.model, hand.data, q, v, np.zeros(hand.model.nv))
    acceleration = pin.getFrameClassicalAcceleration(
        hand.model, hand.data, frame_id, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
    ).linear
    base = hand.base
    return acceleration.copy() if base.at_origin else base.rotation @ acceleration


def _jacobian(hand: Hand, q: np.ndarray, frame_id: int, rows: int) -> np.ndarray:
    jacobian = pin.computeFrameJacobian(
        hand.model, hand.data, q, frame_id, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
    ).reshape(6, hand.model.nv)  # a one-joint model's comes back as a vector
    base = hand.base
    if base.at_origin:
        return jacobian[:rows].copy()
    rotation = base.rotation
    return np.vstack([rotation @ jacobian[i : i + 3] for i in range(0, rows, 3)])
