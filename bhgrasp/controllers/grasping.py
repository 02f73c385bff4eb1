"""Object-space grasp control with contact forces from the friction-cone QP.

:class:`GraspForceController` holds or moves a grasped object: an object-space PD law (plus feed-forward of the
object's weight and of the reference acceleration) gives the wrench w the contacts must exert on the object; the
:class:`~bhgrasp.grasp_forces.ContactForceQP` distributes it over the contacts inside their friction cones,
closest to a desired squeeze (internal force); the joints apply tau = g(q) + J_h^T f.  This is the structure of the
thesis' object computed torque (5.32), tau = J^T G^+ F + J^T F_n, with the pseudo-inverse and the hand-made internal
force replaced by the QP so that the commanded forces never leave the cones.  The fingers' own inertia is not
compensated (the BH8-280's links weigh tens of grams); :mod:`bhgrasp.grasp_dynamics` has the full reduced model.

The controller reads the object pose and twist from the state (a simulator provides them; on a real hand they come
from vision or tactile estimation) and the contacts grouped by finger; with fewer than two touching fingers it
only compensates gravity and closes each finger with ``approach_torque``.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pinocchio as pin

from bhgrasp._validation import as_positive, as_real, as_vector
from bhgrasp.controllers.base import Controller
from bhgrasp.errors import InputError
from bhgrasp.grasp import grasp_map, hand_jacobian
from bhgrasp.grasp_forces import ContactForceQP, ContactForceResult
from bhgrasp.hand import Hand
from bhgrasp.sensing import ContactSensing
from bhgrasp.state import State
from bhgrasp.trajectories import Reference


class GraspForceController(Controller):
    """Hold or move a grasped object through contact forces computed by the friction-cone QP.

    Logged: ``object_error`` (position [m], rotation vector [rad]), ``wrench`` (commanded), ``commanded_normal``
    (QP normal force per finger of the hand [N], 0 if not touching), ``feasible``, ``cone_margin`` (smallest
    mu f_n - |f_t| of the commanded forces [N]), ``contacts`` (number of touching fingers), ``mass_estimate``.
    """

    def __init__(
        self,
        nominal: Hand,
        object_mass: float,
        reference: Reference | None = None,
        mu: float = 0.5,
        squeeze: float = 3.0,
        min_normal_force: float = 0.5,
        kp: tuple[float, float] = (400.0, 0.5),
        kd: tuple[float, float] = (8.0, 0.01),
        approach_torque: float = 0.05,
        gravity: Any = (0.0, 0.0, -9.81),
        mass_adaptation: float | None = None,
    ) -> None:
        """Set up the controller.

        Args:
            nominal: The controller's hand model.
            object_mass: Mass [kg] the controller assumes for the object (it may be wrong).
            reference: Desired object pose as a Reference of size 6 (COM position [m], rotation vector [rad] of
                world <- body, both world); ``None`` holds the pose found when the grasp is first established.
            mu: Friction coefficient assumed by the QP (use a margin below the true one).
            squeeze: Desired normal force per contact [N] (the internal force the QP stays closest to).
            min_normal_force: Lower bound of every normal force [N].
            kp, kd: Object PD gains (translation [N/m], [N s/m]; rotation [N m/rad], [N m s/rad]).
            approach_torque: Closing torque [N m] on each finger's proximal-most non-spread joint before contact.
            gravity: World gravity [m/s^2].
            mass_adaptation: ``None``, or the rate gamma [kg s / m^2 ...] of a Slotine-Li estimate of the object's
                mass: with lambda = kp/kd, s = (v_d - v) + lambda (x_d - x), a_r = a_d + lambda (v_d - v), the
                force is m_hat (a_r - g) + kd s and m_hat_dot = gamma (a_r - g) . s (the translational part of
                the thesis' adaptive grasp law (5.46)-(5.60), whose V = m s^2 / 2 + (m_hat - m)^2 / (2 gamma)
                is non-increasing for a rigid grasp).
        """
        super().__init__()
        if not isinstance(nominal, Hand):
            raise InputError(f"`nominal` must be a bhgrasp Hand, got {nominal!r}")
        if reference is not None and (not isinstance(reference, Reference) or reference.size != 6):
            raise InputError(f"`reference` must be a Reference of size 6 (position, rotation vector), got {reference}")
        self.nominal = nominal
        self.object_mass = as_positive(object_mass, "object_mass")
        self.reference = reference
        self.mu = as_real(mu, "mu")
        self.squeeze = as_real(squeeze, "squeeze")
        self.min_normal_force = as_real(min_normal_force, "min_normal_force")
        self.kp = as_vector(kp, "kp", 2)
        self.kd = as_vector(kd, "kd", 2)
        if np.any(self.kp <= 0) or np.any(self.kd < 0):
            raise InputError(f"`kp` must be positive and `kd` non-negative, got {kp}, {kd}")
        self.approach_torque = as_real(approach_torque, "approach_torque")
        self.gravity = as_vector(gravity, "gravity", 3)
        self.mass_adaptation = None if mass_adaptation is None else as_positive(mass_adaptation, "mass_adaptation")
        self.mass_estimate = self.object_mass
        self._time: float | None = None
        self.sensing = ContactSensing(nominal)
        self._qps: dict[int, ContactForceQP] = {}
        self._hold: pin.SE3 | None = None
        self._closing = self._closing_torque()

    def _closing_torque(self) -> np.ndarray:
        torque = np.zeros(self.nominal.nv)
        for finger in self.nominal.fingers:
            joints = [j for j in self.nominal.finger_joints(finger) if "spread" not in j]
            if joints:
                torque[self.nominal.joint_index(joints[0])] = self.approach_torque
        return torque

    def reset(self, state: State) -> None:
        """Forget the held pose, the QP warm starts and the mass estimate."""
        self._hold = None
        self._qps.clear()
        self.mass_estimate = self.object_mass
        self._time = None

    def __call__(self, t: float, state: State) -> np.ndarray:
        """Joint torques [N m]."""
        hand = self.nominal
        q = as_vector(state.q, "state.q", hand.nq)
        tau = hand.gravity_torques(q)
        if not state.object_poses:
            raise InputError("GraspForceController needs the object's pose in the state (a scene with an object)")
        touching = self._touching(state)
        self.log["contacts"] = np.array(float(len(touching)))
        if len(touching) < 2:
            self._hold = None
            return tau + self._closing
        pose, twist = state.object_poses[0], np.asarray(state.object_twists[0], dtype=float)
        if self._hold is None:
            self._hold = pin.SE3(pose)
        points = np.array([c[0] for c in touching.values()])
        normals = np.array([c[1] for c in touching.values()])
        links = [c[2] for c in touching.values()]
        gmap = grasp_map(points, normals, pose.translation)
        jacobian = hand_jacobian(hand, q, points, links, normals)
        dt = 0.0 if self._time is None else max(t - self._time, 0.0)
        self._time = t
        wrench = self._wrench(t, pose, twist, dt)
        result = self._qp(len(touching)).solve(gmap, wrench, np.tile([0.0, 0.0, self.squeeze], (len(touching), 1)))
        self._record(result, wrench)
        commanded = np.zeros(len(hand.fingers))
        for finger, force in zip(touching, result.forces):
            commanded[hand.fingers.index(finger)] = force[2]
        self.log["commanded_normal"] = commanded
        return tau + jacobian.T @ result.forces.ravel()

    def _touching(self, state: State) -> dict[str, tuple[np.ndarray, np.ndarray, str]]:
        """Per pressing finger: force-weighted contact point, normal (finger -> object) and the link it is on."""
        return {
            finger: (contact.point, contact.normal, contact.link)
            for finger, contact in self.sensing.fingers(state).items()
            if contact.link is not None
        }

    def _wrench(self, t: float, pose: pin.SE3, twist: np.ndarray, dt: float) -> np.ndarray:
        """Object wrench [N, N m] about the COM: weight + PD to the reference (+ its acceleration feed-forward)."""
        if self.reference is None:
            target, velocity, acceleration = self._hold, np.zeros(6), np.zeros(6)
        else:
            sample, velocity, acceleration = self.reference(t)
            target = pin.SE3(pin.exp3(sample[3:]), sample[:3])
        position_error = target.translation - pose.translation
        rotation_error = pin.log3(target.rotation @ pose.rotation.T)  # world-frame rotation vector
        self.log["object_error"] = np.concatenate((-position_error, -rotation_error))
        velocity_error = velocity[:3] - twist[:3]
        if self.mass_adaptation is None:
            force = self.object_mass * (acceleration[:3] - self.gravity)
            force += self.kp[0] * position_error + self.kd[0] * velocity_error
        else:
            lam = self.kp[0] / self.kd[0]
            sliding = velocity_error + lam * position_error
            regressor = acceleration[:3] + lam * velocity_error - self.gravity
            self.mass_estimate = max(self.mass_estimate + dt * self.mass_adaptation * (regressor @ sliding), 1e-6)
            force = self.mass_estimate * regressor + self.kd[0] * sliding
            self.log["mass_estimate"] = np.array(self.mass_estimate)
        torque = self.kp[1] * rotation_error + self.kd[1] * (velocity[3:] - twist[3:])
        return np.concatenate((force, torque))

    def _qp(self, n: int) -> ContactForceQP:
        if n not in self._qps:
            self._qps[n] = ContactForceQP(n, self.mu, min_normal_force=self.min_normal_force)
        return self._qps[n]

    def _record(self, result: ContactForceResult, wrench: np.ndarray) -> None:
        self.log["wrench"] = wrench
        self.log["feasible"] = np.array(float(result.feasible))
        self.log["cone_margin"] = np.array(-result.cone_violation)


__all__ = ["GraspForceController"]
