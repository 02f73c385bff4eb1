"""Joint-space controllers: PD with gravity compensation (the baseline) and computed torque (thesis (3.28))."""

from __future__ import annotations

from typing import Any

import numpy as np
import pinocchio as pin

from bhgrasp.controllers.base import JointTracking, gain_matrix
from bhgrasp.model.hand import Hand
from bhgrasp.motion.trajectories import Reference


class PDGravity(JointTracking):
    """tau = -Kp e - Kd e_dot + G_hat(q), with e = q - q_d: the baseline joint regulator/tracker."""

    def __init__(self, nominal: Hand, reference: Reference, kp: Any = 1.0, kd: Any = 0.05) -> None:
        """Args: ``kp`` [N m/rad], ``kd`` [N m s/rad]: positive scalars, per-joint vectors or SPD matrices."""
        super().__init__(nominal, reference)
        self.kp = gain_matrix(kp, nominal.nv, "kp")
        self.kd = gain_matrix(kd, nominal.nv, "kd")

    def torque(self, q, v, q_d, v_d, a_d, dt) -> np.ndarray:  # noqa: D102
        return -self.kp @ (q - q_d) - self.kd @ (v - v_d) + self.nominal.gravity_torques(q)


class ComputedTorque(JointTracking):
    """Computed torque (thesis (3.28)): tau = M_hat(q) (qdd_d - Kv e_dot - Kp e) + C_hat(q, qd) qd + G_hat(q).

    With an exact model the closed loop is linear, e_dd + Kv e_d + Kp e = 0 (3.27); gains are in [1/s^2] and
    [1/s], so one pair suits every joint.  Defaults are the thesis' Barrett values Kp = 400, Kv = 160.
    """

    def __init__(self, nominal: Hand, reference: Reference, kp: Any = 400.0, kv: Any = 160.0) -> None:
        """Args: ``kp`` [1/s^2], ``kv`` [1/s]: positive scalars, per-joint vectors or SPD matrices."""
        super().__init__(nominal, reference)
        self.kp = gain_matrix(kp, nominal.nv, "kp")
        self.kv = gain_matrix(kv, nominal.nv, "kv")

    def torque(self, q, v, q_d, v_d, a_d, dt) -> np.ndarray:  # noqa: D102
        acceleration = a_d - self.kv @ (v - v_d) - self.kp @ (q - q_d)
        model = self.nominal.model
        return pin.rnea(model, self.nominal.data, q, v, acceleration).copy()  # M a + C v + G in one pass


__all__ = ["ComputedTorque", "PDGravity"]
