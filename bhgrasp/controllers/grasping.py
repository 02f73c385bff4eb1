"""Object-space grasp control with contact forces from the friction-cone QP: the laws' common base.

:class:`ObjectGraspController` is what every object-space grasp law shares (the contacts grouped by finger, the
reference, the force distribution); :class:`~bhgrasp.controllers.grasp_force.GraspForceController`, the simplest,
holds or moves a grasped object: an object-space PD law (plus feed-forward of the
object's weight and of the reference acceleration) gives the wrench w the contacts must exert on the object; the
:class:`~bhgrasp.grasp.forces.ContactForceQP` distributes it over the contacts inside their friction cones,
closest to a desired squeeze (internal force); the joints apply tau = g(q) + J_h^T f.  This is the structure of the
thesis' object computed torque (5.32), tau = J^T G^+ F + J^T F_n, with the pseudo-inverse and the hand-made internal
force replaced by the QP so that the commanded forces never leave the cones.  The fingers' own inertia is not
compensated (the BH8-280's links weigh tens of grams); :mod:`bhgrasp.grasp.dynamics` has the full reduced model.

The controller reads the object pose and twist from the state (a simulator provides them; on a real hand they come
from vision or tactile estimation) and the contacts grouped by finger; with fewer than two touching fingers it
only compensates gravity and closes each finger with ``approach_torque``.
"""

from __future__ import annotations

from abc import abstractmethod
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pinocchio as pin

from bhgrasp._validation import as_vector
from bhgrasp.controllers.base import Controller
from bhgrasp.controllers.grasp_options import DEFAULT_GRASP, GraspOptions
from bhgrasp.data import State
from bhgrasp.errors import InputError
from bhgrasp.grasp.forces import ContactForceQP, cone_violations, pseudo_inverse_forces
from bhgrasp.grasp.frames import contact_frames, grasp_map_from_frames, hand_jacobian
from bhgrasp.grasp.sensing import ContactSensing, FingerContact
from bhgrasp.grasp.torque_limited import internal_scale, split_internal
from bhgrasp.model.hand import Hand
from bhgrasp.motion.trajectories import Reference


class ObjectGraspController(Controller):
    """Base of the object-space grasp controllers: contacts, grasp map, reference, and the force distribution.

    With two or more touching fingers, a subclass's :meth:`grasp_torques` turns the object pose error into joint
    torques; before that every finger is closed with ``approach_torque`` on top of gravity compensation.  The
    wrench the contacts must exert is distributed either by the friction-cone QP (``distribution="qp"``, forces
    inside the cones, closest to ``squeeze`` along every normal, or with a friction margin to the larger of it and
    the measured tangential load / :attr:`design_mu`) or by the thesis' pseudo-inverse form (5.45)
    (``"pinv"``: f = G^+ w + (I - G^+ G) f_squeeze, no cone constraint; kept as the baseline).

    Logged: ``object_error`` (position [m], rotation vector [rad], world), ``wrench`` (commanded on the object),
    ``commanded_normal`` (normal force per finger of the hand [N], 0 if not touching), ``feasible`` (1 if the
    forces exert the wrench, 0 if no admissible forces do: the QP then returns, and the controller applies, the
    nearest admissible ones, see :mod:`bhgrasp.grasp.forces`), ``infeasible_cycles`` (how many grasp cycles so far
    were infeasible), ``wrench_residual`` (|G f - w| of the applied forces [N, N m]), ``qp_iterations`` (solver
    iterations of the cycle, at most :attr:`~bhgrasp.grasp.forces.ContactForceQP.iteration_bound`; 0 for
    ``"pinv"``), ``cone_margin`` (smallest mu f_n - |f_t| of the commanded forces [N], negative = outside the
    assumed cone; mu less the friction margin when one is set, :attr:`design_mu`), ``contacts`` (number of touching
    fingers).  With a torque limit (``options.torque_limit``) the grasp squeezes less where the distribution's forces
    would load a joint past it (:meth:`limit_squeeze`) and logs ``squeeze_scale``, the fraction of the internal
    force kept (1 within the limits, or where no squeeze moves the joints past them; NaN before a grasp).
    """

    def __init__(
        self, nominal: Hand, reference: Reference | None = None, options: GraspOptions = DEFAULT_GRASP
    ) -> None:
        """Set up the shared parts.

        Args:
            nominal: The controller's hand model.
            reference: Desired object pose as a Reference of size 6 (COM position [m], rotation vector [rad] of
                world <- body, both world); ``None`` holds the pose found when the grasp is first established.
            options: The force distribution, closing torque and gravity
                (:class:`~bhgrasp.controllers.grasp_options.GraspOptions`), kept for the controller's life.
        """
        super().__init__()
        if not isinstance(nominal, Hand):
            raise InputError(f"`nominal` must be a bhgrasp Hand, got {nominal!r}")
        if reference is not None and (not isinstance(reference, Reference) or reference.size != 6):
            raise InputError(f"`reference` must be a Reference of size 6 (position, rotation vector), got {reference}")
        if not isinstance(options, GraspOptions):
            raise InputError(f"`options` must be a GraspOptions, got {options!r}")
        self.nominal = nominal
        self.reference = reference
        self._options = options
        self._gravity = np.array(options.gravity)
        self._gravity.flags.writeable = False
        self.sensing = ContactSensing(nominal)
        self._qps: dict[int, ContactForceQP] = {}
        self._infeasible_cycles = 0
        self._hold: pin.SE3 | None = None
        self._time: float | None = None
        self._closing = self._closing_torque()
        self._torque_limits = joint_limits(options.torque_limit, nominal.nv)

    @property
    def options(self) -> GraspOptions:
        """The shared options (read-only: other options make another controller)."""
        return self._options

    @property
    def mu(self) -> float:
        """Friction coefficient the distribution assumes."""
        return self._options.mu

    @property
    def friction_margin(self) -> float | None:
        """Fraction of :attr:`mu` kept in reserve (``None``: none; see :class:`GraspOptions`)."""
        return self._options.friction_margin

    @property
    def design_mu(self) -> float:
        """Friction coefficient the distribution enforces, (1 - margin) mu."""
        return self._options.design_mu

    @property
    def squeeze(self) -> float:
        """Desired normal force per contact [N] (with a friction margin, the least: distribute() raises it)."""
        return self._options.squeeze

    @property
    def min_normal_force(self) -> float:
        """Lower bound of every normal force in the QP [N]."""
        return self._options.min_normal_force

    @property
    def torque_limit(self) -> np.ndarray | None:
        """The joints' torque limits (nv,) [N m] the grasp respects (``None``: none; see :meth:`limit_squeeze`)."""
        return self._torque_limits

    @property
    def approach_torque(self) -> float:
        """Closing torque [N m] before contact."""
        return self._options.approach_torque

    @property
    def gravity(self) -> np.ndarray:
        """World gravity [m/s^2], read-only."""
        return self._gravity

    @property
    def distribution(self) -> str:
        """``"qp"`` or ``"pinv"``."""
        return self._options.distribution

    def _closing_torque(self) -> np.ndarray:
        torque = np.zeros(self.nominal.nv)
        for finger in self.nominal.fingers:
            joints = [j for j in self.nominal.finger_joints(finger) if "spread" not in j]
            if joints:
                torque[self.nominal.joint_index(joints[0])] = self.approach_torque
        return torque

    def reset(self, state: State) -> None:
        """Forget the held pose, the QP warm starts, the infeasible-cycle count and the clock."""
        self._hold = None
        self._qps.clear()
        self._infeasible_cycles = 0
        self._time = None

    def __call__(self, t: float, state: State) -> np.ndarray:
        """Joint torques [N m]."""
        hand = self.nominal
        q = as_vector(state.q, "state.q", hand.nq)
        if not state.object_poses:
            raise InputError(f"{type(self).__name__} needs the object's pose in the state (a scene with an object)")
        touching = self.touching(state)
        self.log["contacts"] = np.array(float(len(touching)))
        if len(touching) < 2:
            self._hold = None
            self.log["commanded_normal"] = np.zeros(len(hand.fingers))
            if self._torque_limits is not None:
                self.log["squeeze_scale"] = np.array(np.nan)
            return hand.gravity_torques(q) + self._closing
        pose = state.object_poses[0]
        if self._hold is None:
            self._hold = pin.SE3(pose)
        dt = 0.0 if self._time is None else t - self._time
        if dt < 0.0:
            raise InputError(f"time went backwards: t = {t} after {self._time}; call reset() to restart")
        self._time = t
        contacts = GraspContacts(
            points=np.array([c.point for c in touching.values()]),
            normals=np.array([c.normal for c in touching.values()]),
            links=[c.link for c in touching.values()],
            fingers=list(touching),
            forces=np.array([c.force for c in touching.values()]),
        )
        tau = self.grasp_torques(t, dt, state, contacts)
        if not np.all(np.isfinite(tau)):
            raise InputError(f"{type(self).__name__} produced non-finite torques {tau} at t = {t} s")
        return tau

    def touching(self, state: State) -> dict[str, FingerContact]:
        """The sensed contacts of the fingers that press on the object, by finger."""
        return {f: c for f, c in self.sensing.fingers(state).items() if c.link is not None}

    @abstractmethod
    def grasp_torques(self, t: float, dt: float, state: State, contacts: GraspContacts) -> np.ndarray:
        """Joint torques [N m] once two or more fingers touch; ``dt`` [s] since the previous grasp step."""

    def target(self, t: float) -> tuple[pin.SE3, np.ndarray, np.ndarray]:
        """Desired object pose, twist (v, omega) [m/s, rad/s] and its derivative, world."""
        if self.reference is None:
            return self._hold, np.zeros(6), np.zeros(6)
        sample, velocity, acceleration = self.reference(t)
        return pin.SE3(pin.exp3(sample[3:]), sample[:3]), velocity, acceleration

    def errors(self, t: float, state: State) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Pose error e = (x - x_d, log(R R_d^T)), twist error e_dot, desired twist and its derivative (world)."""
        pose, twist = state.object_poses[0], np.asarray(state.object_twists[0], dtype=float)
        target, velocity, acceleration = self.target(t)
        error = np.concatenate((pose.translation - target.translation, pin.log3(pose.rotation @ target.rotation.T)))
        self.log["object_error"] = error
        return error, twist - velocity, velocity, acceleration

    def distribute(self, contacts: GraspContacts, wrench: np.ndarray) -> np.ndarray:
        """Contact forces (n, 3) (contact frames: t1, t2, n) [N] that exert ``wrench`` about the object's COM.

        When no admissible forces exert it, the QP's nearest admissible forces (never an exception, at most
        :attr:`~bhgrasp.grasp.forces.ContactForceQP.iteration_bound` iterations); ``log["feasible"]`` is then 0.
        """
        n = len(contacts.fingers)
        gmap = contacts.grasp_map
        desired = np.zeros((n, 3))
        desired[:, 2] = self.squeeze
        if self.friction_margin is not None:  # the grip follows the measured load (GraspOptions.friction_margin)
            tangential = np.linalg.norm(contacts.measured()[:, :2], axis=1)
            desired[:, 2] = np.maximum(self.squeeze, tangential / self.design_mu)
        if self.distribution == "qp":
            if n not in self._qps:
                self._qps[n] = ContactForceQP(n, self.design_mu, min_normal_force=self.min_normal_force)
            result = self._qps[n].solve(gmap, wrench, desired)
            forces, feasible, iterations = result.forces, result.feasible, result.iterations
        else:
            forces, feasible, iterations = pseudo_inverse_forces(gmap, wrench, desired), True, 0
        self._infeasible_cycles += not feasible
        self.log["wrench"] = wrench
        self.log["feasible"] = np.array(float(feasible))
        self.log["infeasible_cycles"] = np.array(float(self._infeasible_cycles))
        self.log["wrench_residual"] = np.array(float(np.linalg.norm(gmap @ forces.ravel() - wrench)))
        self.log["qp_iterations"] = np.array(float(iterations))
        self._log_commanded(contacts, forces)
        return forces

    def _log_commanded(self, contacts: GraspContacts, forces: np.ndarray) -> None:
        self.log["cone_margin"] = np.array(-np.max(cone_violations(forces, self.design_mu)))
        commanded = np.zeros(len(self.nominal.fingers))
        for finger, force in zip(contacts.fingers, forces):
            commanded[self.nominal.fingers.index(finger)] = force[2]
        self.log["commanded_normal"] = commanded

    def limit_squeeze(
        self, contacts: GraspContacts, forces: np.ndarray, torques_of: Callable[[np.ndarray], np.ndarray]
    ) -> np.ndarray:
        """``forces`` (n, 3) with their internal part scaled down to keep every joint within :attr:`torque_limit`.

        ``torques_of`` maps contact forces to the law's joint torques [N m] (affine in them, without side effects; the
        SMC-adaptive law with ``hand_adaptation`` is affine to first order: its estimate's update depends on them, and
        the limit then holds to its second-order term, ~1e-10 N m measured).
        Unchanged (the same array) without a limit or within it; the wrench they exert is the same
        (:mod:`bhgrasp.grasp.torque_limited`).  With a limit, logs ``squeeze_scale`` (beta, 1 when unchanged) and
        the scaled forces' ``commanded_normal``, ``cone_margin`` and ``wrench_residual``.
        """
        limits = self._torque_limits
        if limits is None:
            return forces
        torque = torques_of(forces)
        beta = 1.0
        if np.all(np.isfinite(torque)) and not np.all(np.abs(torque) <= limits):  # non-finite: __call__ raises
            wrench_part, internal = split_internal(contacts.grasp_map, forces)
            wrench_torque = torques_of(wrench_part)
            if not np.all(np.isfinite(wrench_torque)):
                raise InputError(f"{type(self).__name__}: non-finite torques {wrench_torque} for the wrench's forces")
            beta = internal_scale(torque, wrench_torque, limits, forces[:, 2], wrench_part[:, 2])
            forces = wrench_part + beta * internal
            self._log_commanded(contacts, forces)
            residual = contacts.grasp_map @ forces.ravel() - self.log["wrench"]
            self.log["wrench_residual"] = np.array(float(np.linalg.norm(residual)))
        self.log["squeeze_scale"] = np.array(beta)
        return forces


def joint_limits(torque_limit: Any, nv: int) -> np.ndarray | None:
    """``GraspOptions.torque_limit`` (:class:`~bhgrasp.controllers.grasp_options.GraspOptions`) as (nv,) [N m]."""
    if torque_limit is None:
        return None
    limits = np.array(np.broadcast_to(torque_limit, (nv,)) if np.ndim(torque_limit) == 0 else torque_limit)
    if limits.shape != (nv,):
        raise InputError(f"`torque_limit` must be one number or one per joint ({nv}), got {torque_limit!r}")
    limits.flags.writeable = False
    return limits


@dataclass
class GraspContacts:
    """One sensed contact per touching finger (world frame), with the grasp map and hand Jacobian on demand.

    Attributes:
        points: (n, 3) force-weighted contact points [m]; normals: (n, 3) unit normals from finger to object;
        links: the hand link of each contact; fingers: the finger names; forces: (n, 3) measured forces on the
        object [N] (world).  ``reference`` [m] (the object's COM) must be set before :attr:`grasp_map` is read.
        The contact frames are built once, on first use (the arrays are not to be changed afterwards).
    """

    points: np.ndarray
    normals: np.ndarray
    links: list[str]
    fingers: list[str]
    forces: np.ndarray
    reference: np.ndarray | None = None
    _frames: np.ndarray | None = field(default=None, init=False, repr=False)

    @property
    def frames(self) -> np.ndarray:
        """Contact frames [t1, t2, n] (n, 3, 3) (columns, world) of :func:`~bhgrasp.grasp.frames.contact_frames`."""
        if self._frames is None:
            self._frames = contact_frames(self.normals)
        return self._frames

    @property
    def grasp_map(self) -> np.ndarray:
        """G (6, 3n) about :attr:`reference`."""
        if self.reference is None:
            raise InputError("GraspContacts.reference (the object's COM) is not set")
        return grasp_map_from_frames(self.points, self.frames, as_vector(self.reference, "reference", 3))

    def jacobian(self, hand: Hand, q: np.ndarray) -> np.ndarray:
        """J_h (3n, nv) in contact coordinates."""
        return hand_jacobian(hand, q, self.points, self.links, self.normals)

    def measured(self) -> np.ndarray:
        """Measured forces in contact coordinates (t1, t2, n), (n, 3) [N]."""
        return np.einsum("nij,ni->nj", self.frames, self.forces)


__all__ = ["GraspContacts", "ObjectGraspController"]
