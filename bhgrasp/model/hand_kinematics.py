"""HandKinematics: frame poses, fingertip positions, Jacobians and bias accelerations of a hand.

The second of the hand's layers (:mod:`bhgrasp.model.hand_model`): Pinocchio's forward kinematics and frame Jacobians,
world-aligned, with the hand's base placement applied.  Every method is a method of :class:`~bhgrasp.model.hand.Hand`.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
import pinocchio as pin

from bhgrasp._validation import as_array, as_vector, require_name
from bhgrasp.model.hand_model import HandModel


class HandKinematics(HandModel):
    """A :class:`~bhgrasp.model.hand_model.HandModel` with kinematics: frame poses, fingertip positions, Jacobians."""

    # ------------------------------------------------------------------ kinematics
    def frame_placement(self, q: Any, frame: str) -> pin.SE3:
        """Pose of a frame in the world, ``transform_frame_to_world``."""
        frame_id = self._frame_id(frame)
        pin.framesForwardKinematics(self._model, self._data, self._q(q))
        return self._placement * self._data.oMf[frame_id]

    def fingertip_positions(self, q: Any) -> np.ndarray:
        """Fingertip frame origins in the world [m], shape (n_fingers, 3), in :attr:`fingers` order."""
        pin.framesForwardKinematics(self._model, self._data, self._q(q))
        points = np.array([self._data.oMf[i].translation for i in self._tip_ids.values()])
        if self._base_at_origin:
            return points
        return points @ self._placement.rotation.T + self._placement.translation

    def frame_jacobian(self, q: Any, frame: str) -> np.ndarray:
        """Spatial Jacobian of a frame, shape (6, nv): rows (linear, angular), world-aligned, at the frame origin."""
        return self._jacobian(self._q(q), self._frame_id(frame), 6)

    def fingertip_jacobian(self, q: Any, finger: str) -> np.ndarray:
        """Translational Jacobian of a fingertip, shape (3, nv), world-aligned: ``p_dot_world = J v``."""
        if finger not in self._tip_ids:
            require_name(finger, self.fingers, "finger")
        return self._jacobian(self._q(q), self._tip_ids[finger], 3)

    def point_jacobian(self, q: Any, frame: str, point: Any) -> np.ndarray:
        """Translational Jacobian (3, nv), world-aligned, of a point [m, world] fixed on ``frame``'s body at ``q``.

        J_p = J_lin - skew(p - o) J_ang with the frame's spatial Jacobian at its origin o (the point moves with the
        body: v_p = v_o + omega x (p - o)).
        """
        point = as_vector(point, "point", 3)
        jacobian = self.frame_jacobian(q, frame)
        origin = self.frame_placement(q, frame).translation  # world, base placement included
        return jacobian[:3] - pin.skew(point - origin) @ jacobian[3:]

    def point_jacobians(self, q: Any, frames: Sequence[str], points: Any) -> np.ndarray:
        """:meth:`point_jacobian` of several points at once, shape (n, 3, nv): one kinematics pass for all.

        Args:
            q: Configuration [rad].
            frames: n frame names, the body each point is fixed on.
            points: (n, 3) points [m], world.
        """
        points = as_array(points, "points", (len(frames), 3))
        model, data = self._model, self._data
        pin.computeJointJacobians(model, data, self._q(q))  # also places the joints (data.oMi)
        if not self._base_at_origin:
            points = (points - self._placement.translation) @ self._placement.rotation  # base-frame points
        result = np.empty((len(frames), 3, model.nv))
        for i, frame in enumerate(frames):
            joint = model.frames[self._frame_id(frame)].parentJoint
            on_joint = pin.SE3(np.eye(3), data.oMi[joint].actInv(points[i]))  # the point, fixed on its body
            jacobian = pin.getFrameJacobian(model, data, joint, on_joint, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)
            result[i] = np.reshape(jacobian, (6, model.nv))[:3]  # (a one-joint model's comes back as a vector)
        if not self._base_at_origin:
            result = np.einsum("ij,njk->nik", self._placement.rotation, result)
        return result

    def fingertip_bias_acceleration(self, q: Any, v: Any, finger: str) -> np.ndarray:
        """J_dot(q, v) v: the fingertip's classical acceleration at zero joint acceleration, world frame [m/s^2].

        With it, fingertip acceleration = ``fingertip_jacobian(q, finger) @ a + fingertip_bias_acceleration(q, v)``.
        """
        require_name(finger, self.fingers, "finger")
        q, v = self._q(q), self._v(v, "v")
        pin.forwardKinematics(self._model, self._data, q, v, np.zeros(self._model.nv))
        frame_id = self._tip_ids[finger]
        acceleration = pin.getFrameClassicalAcceleration(
            self._model, self._data, frame_id, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
        ).linear
        return acceleration.copy() if self._base_at_origin else self._placement.rotation @ acceleration

    def _jacobian(self, q: np.ndarray, frame_id: int, rows: int) -> np.ndarray:
        jacobian = pin.computeFrameJacobian(
            self._model, self._data, q, frame_id, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
        ).reshape(6, self._model.nv)  # a one-joint model's comes back as a vector
        if self._base_at_origin:
            return jacobian[:rows].copy()
        rotation = self._placement.rotation
        return np.vstack([rotation @ jacobian[i : i + 3] for i in range(0, rows, 3)])
