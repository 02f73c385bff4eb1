"""The simplest object-space grasp law: object PD + weight feed-forward, contact forces from the distribution.

:class:`GraspForceController` (see :mod:`bhgrasp.controllers.grasping` for the structure it shares).
"""

from __future__ import annotations

import numpy as np

from bhgrasp._validation import as_positive, as_vector
from bhgrasp.controllers.grasp_options import DEFAULT_GRASP, GraspOptions
from bhgrasp.controllers.grasping import GraspContacts, ObjectGraspController
from bhgrasp.data import State
from bhgrasp.errors import InputError
from bhgrasp.model.hand import Hand
from bhgrasp.motion.trajectories import Reference


class GraspForceController(ObjectGraspController):
    """Hold or move a grasped object: object PD + weight feed-forward, contact forces from the distribution.

    tau = g(q) + J_h^T f with G f = w: the structure of (5.32) without the reduced model's inertia (the BH8-280's
    links weigh tens of grams; :class:`~bhgrasp.controllers.object_space.ObjectSpaceController` has it).  Also
    logs ``mass_estimate``.
    """

    def __init__(
        self,
        nominal: Hand,
        object_mass: float,
        reference: Reference | None = None,
        kp: tuple[float, float] = (400.0, 0.5),
        kd: tuple[float, float] = (8.0, 0.01),
        mass_adaptation: float | None = None,
        options: GraspOptions = DEFAULT_GRASP,
    ) -> None:
        """Set up the controller (see :class:`ObjectGraspController` for the shared arguments).

        Args:
            nominal: The controller's hand model.
            object_mass: Mass [kg] the controller assumes for the object (it may be wrong).
            reference, options: As in the base.
            kp, kd: Object PD gains (translation [N/m], [N s/m]; rotation [N m/rad], [N m s/rad]).
            mass_adaptation: ``None``, or the rate gamma [kg s / m^2 ...] of a Slotine-Li estimate of the object's
                mass: with lambda = kp/kd, s = (v_d - v) + lambda (x_d - x), a_r = a_d + lambda (v_d - v), the
                force is m_hat (a_r - g) + kd s and m_hat_dot = gamma (a_r - g) . s (the translational part of
                the thesis' adaptive grasp law (5.46)-(5.60), whose V = m s^2 / 2 + (m_hat - m)^2 / (2 gamma)
                is non-increasing for a rigid grasp).
        """
        super().__init__(nominal, reference, options)
        self.object_mass = as_positive(object_mass, "object_mass")
        self.kp = as_vector(kp, "kp", 2)
        self.kd = as_vector(kd, "kd", 2)
        if np.any(self.kp <= 0) or np.any(self.kd < 0):
            raise InputError(f"`kp` must be positive and `kd` non-negative, got {kp}, {kd}")
        self.mass_adaptation = None if mass_adaptation is None else as_positive(mass_adaptation, "mass_adaptation")
        self.mass_estimate = self.object_mass

    def reset(self, state: State) -> None:
        """Forget the held pose, the QP warm starts and the mass estimate."""
        super().reset(state)
        self.mass_estimate = self.object_mass

    def grasp_torques(self, t: float, dt: float, state: State, contacts: GraspContacts) -> np.ndarray:
        """Tau = g(q) + J_h^T f, f distributing the object PD wrench."""
        contacts.reference = state.object_poses[0].translation
        error, velocity_error, _, acceleration = self.errors(t, state)
        if self.mass_adaptation is None:
            force = self.object_mass * (acceleration[:3] - self.gravity)
            force -= self.kp[0] * error[:3] + self.kd[0] * velocity_error[:3]
        else:
            lam = self.kp[0] / self.kd[0]
            sliding = -(velocity_error[:3] + lam * error[:3])
            regressor = acceleration[:3] - lam * velocity_error[:3] - self.gravity
            self.mass_estimate = max(self.mass_estimate + dt * self.mass_adaptation * (regressor @ sliding), 1e-6)
            force = self.mass_estimate * regressor + self.kd[0] * sliding
            self.log["mass_estimate"] = np.array(self.mass_estimate)
        torque = -self.kp[1] * error[3:] - self.kd[1] * velocity_error[3:]
        forces = self.distribute(contacts, np.concatenate((force, torque)))
        gravity, jacobian = self.nominal.gravity_torques(state.q), contacts.jacobian(self.nominal, state.q)
        forces = self.limit_squeeze(contacts, forces, lambda f: gravity + jacobian.T @ f.ravel())
        return gravity + jacobian.T @ forces.ravel()


__all__ = ["GraspForceController"]
