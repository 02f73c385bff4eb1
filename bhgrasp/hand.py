"""Hand: a robot hand loaded into Pinocchio, with kinematics, Jacobians and rigid-body dynamics.

Conventions: SI units and radians; ``q`` (size ``nq``) and ``v`` (size ``nv``) in Pinocchio's joint order
(:attr:`Hand.joint_names`).  "World" is the frame the hand base is placed in by :attr:`Hand.base_placement`
(identity by default, so world = hand base frame W); gravity is given in world coordinates.
"""

from __future__ import annotations

import functools
import warnings
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin

from bhgrasp._native import kernel
from bhgrasp._validation import as_array, as_vector, require_name, require_rotation
from bhgrasp.errors import InputError, ModelError
from bhgrasp.resources import barrett_urdf_path, leaf_links, mimic_joints, read_urdf

BARRETT_FINGERTIPS = {"F1": "F1_tip", "F2": "F2_tip", "F3": "F3_tip"}
STANDARD_GRAVITY = (0.0, 0.0, -9.81)  # [m/s^2] in world coordinates


class Hand:
    """A fixed-base hand: Pinocchio model and data, fingertip frames, limits, kinematics and dynamics.

    Every method takes the configuration explicitly and validates its inputs (shape, finiteness); results are
    fresh arrays that the caller may keep.  One :class:`pinocchio.Data` is reused between calls, so a ``Hand``
    is not thread-safe: give each thread or process its own (``copy.deepcopy`` works).
    """

    def __init__(
        self,
        model: pin.Model,
        fingertips: Mapping[str, str],
        *,
        name: str | None = None,
        base_placement: pin.SE3 | None = None,
        gravity: Sequence[float] = STANDARD_GRAVITY,
        urdf_path: Path | None = None,
        collision_geometry: pin.GeometryModel | None = None,
        base_joints: Sequence[str] = (),
    ) -> None:
        """Wrap a Pinocchio model.

        Args:
            model: Fixed-base model (no free-flyer root).
            fingertips: Finger name -> frame name of its fingertip.
            name: Display name; defaults to the model's name.
            base_placement: Pose of the hand base in the world, ``transform_base_to_world``.
            gravity: Gravity vector in world coordinates [m/s^2].
            urdf_path: The URDF the model came from, if any (kept for later layers, e.g. collision geometry).
            collision_geometry: Collision shapes attached to the model's joints and frames, for a hand built
                without a URDF (e.g. a planar finger's tip sphere); scenes use it instead of ``urdf_path``'s.
            base_joints: Joints that move the whole hand and belong to no finger (a wrist mount's,
                :func:`~bhgrasp.mount.mounted`): :meth:`finger_joints` leaves them out.
        """
        if not fingertips:
            raise ModelError("a hand needs at least one fingertip frame")
        self._model = model
        self._data = model.createData()
        self.name = name or model.name
        self.urdf_path = urdf_path
        self.collision_geometry = collision_geometry
        frame_names = [frame.name for frame in model.frames]
        self._tip_ids: dict[str, int] = {}
        for finger, frame in fingertips.items():
            require_name(frame, frame_names, "frame")
            self._tip_ids[str(finger)] = model.getFrameId(frame)
        self._fingertips = {finger: model.frames[i].name for finger, i in self._tip_ids.items()}
        self.base_joints = tuple(require_name(joint, model.names[1:], "joint") for joint in base_joints)
        self._placement = pin.SE3.Identity()
        self._base_at_origin = True  # skip world <- base products when the base frame is the world frame
        self._lower_triangle = np.tril_indices(model.nv, -1)
        self._gravity_world = np.zeros(3)
        self.base_placement = base_placement if base_placement is not None else pin.SE3.Identity()
        self.gravity = gravity

    # ------------------------------------------------------------------ construction
    @classmethod
    def from_urdf(
        cls,
        path: str | Path,
        fingertips: Sequence[str] | Mapping[str, str] | None = None,
        mimic: str = "refuse",
        **kwargs: Any,
    ) -> Hand:
        """Load any fixed-base hand URDF.

        Every joint is an independent degree of freedom.  A URDF whose joints carry ``<mimic>`` tags (couplings)
        is refused unless ``mimic="independent"`` says to load those joints as independent too (their coupling
        is then up to an actuation model, as :class:`~bhgrasp.sim.actuation.BarrettActuation` does for the
        BH8-280's).

        Args:
            path: URDF file.  It is parsed without DTDs or entities before Pinocchio sees it.
            fingertips: Frame names of the fingertips (finger name = frame name), or a mapping finger name ->
                frame name; by default the URDF's leaf links below a moving joint
                (:func:`~bhgrasp.resources.leaf_links`: a palm pad fixed to the base is not a fingertip).
            mimic: ``"refuse"`` (default: a ``<mimic>`` tag is a ModelError naming the joints) or
                ``"independent"`` (load mimic joints as independent joints).
            **kwargs: ``name``, ``base_placement``, ``gravity`` as for :class:`Hand`.

        Raises:
            ModelError: Missing/malformed/unsafe/non-UTF-8 URDF, one Pinocchio cannot build, or an ``<inertial>``
                no rigid body has: mass missing, NaN/inf or < 0; an inertia component missing or NaN/inf; a tensor
                that is not positive semi-definite or whose ixx, iyy, izz break the triangle inequality (the
                message names the file and the link).  Point masses and massless links are legal.
            InputError: A fingertip frame that the model does not have.

        Warns:
            UserWarning: A link whose principal moments of inertia break the triangle inequality although its
                diagonal does not (products of inertia no body has, e.g. example-robot-data's Allegro fingertips).
        """
        if mimic not in ("refuse", "independent"):
            raise InputError(f"`mimic` must be 'refuse' or 'independent', got {mimic!r}")
        model, root = _build_model(path)
        coupled = mimic_joints(root)
        if coupled and mimic == "refuse":
            pairs = ", ".join(f"{joint} mimics {source}" for joint, source in coupled.items())
            raise ModelError(
                f"URDF {str(path)!r} couples joints with <mimic> tags ({pairs}); bhgrasp models every joint as an "
                "independent DOF: pass mimic='independent' (`bhgrasp info --mimic independent`) to load them so (an "
                "actuation model then couples them), "
                "or remove the tags (for the Barrett hand use bh.BarrettHand())"
            )
        if fingertips is None:
            fingertips = leaf_links(root)
            if not fingertips:
                raise ModelError(f"URDF {str(path)!r} has no leaf links to use as fingertips; pass `fingertips`")
        if not isinstance(fingertips, Mapping):
            fingertips = {frame: frame for frame in fingertips}
        return Hand(model, fingertips, urdf_path=Path(path), **kwargs)

    # ------------------------------------------------------------------ names, sizes, limits
    @property
    def model(self) -> pin.Model:
        """The Pinocchio model (shared, do not modify while the hand is in use)."""
        return self._model

    @property
    def data(self) -> pin.Data:
        """The Pinocchio data that the last call filled in."""
        return self._data

    @property
    def nq(self) -> int:
        """Size of the configuration vector."""
        return self._model.nq

    @property
    def nv(self) -> int:
        """Size of the velocity/torque vector."""
        return self._model.nv

    @functools.cached_property
    def joint_names(self) -> tuple[str, ...]:
        """Joint names in Pinocchio's order (the order of ``q``, ``v`` and ``tau``)."""
        return tuple(self._model.names[1:])  # read by controllers every cycle: built once (the model is fixed)

    @property
    def fingers(self) -> tuple[str, ...]:
        """Finger names, e.g. ``("F1", "F2", "F3")`` for the Barrett hand."""
        return tuple(self._tip_ids)

    @property
    def fingertip_frames(self) -> dict[str, str]:
        """Finger name -> fingertip frame name."""
        return dict(self._fingertips)

    @property
    def lower(self) -> np.ndarray:
        """Lower joint position limits [rad], shape (nq,)."""
        return self._model.lowerPositionLimit.copy()

    @property
    def upper(self) -> np.ndarray:
        """Upper joint position limits [rad], shape (nq,)."""
        return self._model.upperPositionLimit.copy()

    @property
    def velocity_limit(self) -> np.ndarray:
        """Joint speed limits [rad/s], shape (nv,)."""
        return self._model.velocityLimit.copy()

    @property
    def effort_limit(self) -> np.ndarray:
        """Joint torque limits [N m], shape (nv,)."""
        return self._model.effortLimit.copy()

    @property
    def total_mass(self) -> float:
        """Mass of every body, base included [kg]."""
        return float(sum(inertia.mass for inertia in self._model.inertias))

    def joint_index(self, joint: str) -> int:
        """Index of a 1-DOF joint in ``q``/``v``."""
        index = self._joint_indices.get(joint) if isinstance(joint, str) else None
        if index is None:
            require_name(joint, self.joint_names, "joint")  # raises: an unknown name
        return index

    @functools.cached_property
    def _joint_indices(self) -> dict[str, int]:
        return {name: self._model.joints[self._model.getJointId(name)].idx_v for name in self.joint_names}

    def finger_joints(self, finger: str) -> tuple[str, ...]:
        """Names of the joints that move a finger's tip, from the base outward (not the :attr:`base_joints`)."""
        joints = self._finger_joints.get(finger) if isinstance(finger, str) else None
        if joints is None:
            require_name(finger, self.fingers, "finger")  # raises: an unknown finger
        return joints

    @functools.cached_property
    def _finger_joints(self) -> dict[str, tuple[str, ...]]:
        model = self._model
        supports = {
            finger: model.supports[model.frames[frame].parentJoint][1:] for finger, frame in self._tip_ids.items()
        }
        base = set(self.base_joints)
        return {finger: tuple(model.names[j] for j in joints if model.names[j] not in base)
                for finger, joints in supports.items()}  # fmt: skip

    def finger_indices(self, finger: str) -> np.ndarray:
        """Velocity indices of a finger's joints (columns of its Jacobian that can be non-zero)."""
        return np.array([self.joint_index(joint) for joint in self.finger_joints(finger)], dtype=int)

    def collision_model(self) -> pin.GeometryModel:
        """A copy of the hand's collision shapes on its own model (``collision_geometry``, else its URDF's, else none).

        Raises:
            ModelError: The URDF's collision geometry does not load.
        """
        if self.collision_geometry is not None:
            return self.collision_geometry.copy()
        path = self.urdf_path
        if path is None:
            return pin.GeometryModel()
        try:
            return pin.buildGeomFromUrdfString(
                self._model, path.read_text(), pin.GeometryType.COLLISION, None, [str(p) for p in path.parents]
            )
        except (ValueError, RuntimeError, OSError) as error:
            raise ModelError(f"cannot load the collision geometry of {str(path)!r}: {error}") from error

    # ------------------------------------------------------------------ world placement and gravity
    @property
    def base_placement(self) -> pin.SE3:
        """Pose of the hand base frame in the world, ``transform_base_to_world``."""
        return self._placement.copy()

    @base_placement.setter
    def base_placement(self, placement: pin.SE3) -> None:
        if not isinstance(placement, pin.SE3):
            raise InputError(f"`base_placement` must be a pinocchio.SE3, got {type(placement).__name__}")
        as_array(placement.homogeneous, "base_placement", (4, 4))
        require_rotation(placement.rotation, "base_placement")
        self._placement = placement.copy()
        self._base_at_origin = bool(placement.isIdentity(0.0))
        self._update_model_gravity()

    @property
    def gravity(self) -> np.ndarray:
        """Gravity in world coordinates [m/s^2]; set it to mount the hand in any orientation."""
        return self._gravity_world.copy()

    @gravity.setter
    def gravity(self, gravity: Sequence[float]) -> None:
        self._gravity_world = as_vector(gravity, "gravity", 3).copy()
        self._update_model_gravity()

    def _update_model_gravity(self) -> None:
        self._model_gravity = self._placement.rotation.T @ self._gravity_world
        self._model.gravity.linear = self._model_gravity

    def _dynamics(self) -> Any:
        """The compiled ``_core.HandDynamics`` of this hand's model, built on first use (``None`` without the core).

        It holds a copy of the model: the hand's inertias must not be changed in place afterwards
        (:meth:`perturbed` makes a new hand); gravity is passed at every call.
        """
        return kernel(self, "HandDynamics", lambda core: core.HandDynamics(self._model.saveToString()))

    def neutral(self) -> np.ndarray:
        """Pinocchio's neutral configuration (all zeros for revolute joints: Barrett fingers open and flat)."""
        return pin.neutral(self._model)

    def random_configuration(self, rng: np.random.Generator | int) -> np.ndarray:
        """Configuration drawn uniformly inside the joint limits.

        Args:
            rng: A NumPy generator or an integer seed (there is no unseeded default).
        """
        generator = _generator(rng)
        return generator.uniform(self._model.lowerPositionLimit, self._model.upperPositionLimit)

    def configuration(self, **joint_values: float) -> np.ndarray:
        """Neutral configuration with the named joints set, e.g. ``hand.configuration(F3_proximal=0.8)`` [rad].

        Raises:
            InputError: Unknown joint name (the message lists the valid ones), non-finite value, or a value
                outside the joint's limits.
        """
        q = self.neutral()
        for joint, value in joint_values.items():
            i = self.joint_index(joint)
            angle = float(as_vector([value], joint, 1)[0])
            low, high = self._model.lowerPositionLimit[i], self._model.upperPositionLimit[i]
            if not low <= angle <= high:
                raise InputError(f"joint {joint!r} = {angle!r} rad is outside its limits [{low:.6g}, {high:.6g}]")
            q[i] = angle
        return q

    def within_limits(self, q: Any, tolerance: float = 0.0) -> bool:
        """Whether every joint of ``q`` lies inside its limits (widened by ``tolerance`` [rad])."""
        q = self._q(q)
        return bool(
            np.all(q >= self._model.lowerPositionLimit - tolerance)
            and np.all(q <= self._model.upperPositionLimit + tolerance)
        )

    # ------------------------------------------------------------------ kinematics
    def frame_names(self) -> tuple[str, ...]:
        """Every frame of the model (links, joints, fixed frames)."""
        return tuple(frame.name for frame in self._model.frames)

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

    # ------------------------------------------------------------------ dynamics
    def mass_matrix(self, q: Any) -> np.ndarray:
        """Joint-space inertia matrix M(q) (CRBA), full symmetric, shape (nv, nv) [kg m^2]."""
        mass = pin.crba(self._model, self._data, self._q(q)).copy()  # CRBA fills the upper triangle
        mass[self._lower_triangle] = mass.T[self._lower_triangle]
        return mass

    def nonlinear_effects(self, q: Any, v: Any) -> np.ndarray:
        """Coriolis, centrifugal and gravity torques C(q, v) v + G(q), shape (nv,) [N m]."""
        return pin.nonLinearEffects(self._model, self._data, self._q(q), self._v(v, "v")).copy()

    def gravity_torques(self, q: Any) -> np.ndarray:
        """Gravity torques G(q), shape (nv,) [N m] (the torques that hold the hand still)."""
        return pin.computeGeneralizedGravity(self._model, self._data, self._q(q)).copy()

    def coriolis_matrix(self, q: Any, v: Any) -> np.ndarray:
        """Coriolis matrix C(q, v), shape (nv, nv), with M_dot - 2 C skew-symmetric (thesis (2.27))."""
        return pin.computeCoriolisMatrix(self._model, self._data, self._q(q), self._v(v, "v")).copy()

    def forward_dynamics(self, q: Any, v: Any, tau: Any, f_ext: Any = None) -> np.ndarray:
        """Joint accelerations (ABA) under joint torques ``tau`` [N m] and optional external forces.

        Args:
            f_ext: ``None``, or one force per joint (``njoints`` entries, index 0 = universe) in each joint's
                local frame, as ``pinocchio.Force`` objects or an array (njoints, 6) of (linear, angular);
                :meth:`external_forces` builds it from forces on frames.
        """
        q, v, tau = self._q(q), self._v(v, "v"), self._v(tau, "tau")
        if f_ext is None:
            return pin.aba(self._model, self._data, q, v, tau).copy()
        return pin.aba(self._model, self._data, q, v, tau, self._fext(f_ext)).copy()

    def inverse_dynamics(self, q: Any, v: Any, a: Any, f_ext: Any = None) -> np.ndarray:
        """Joint torques (RNEA) that produce accelerations ``a`` [rad/s^2]; ``f_ext`` as in :meth:`forward_dynamics`."""
        q, v, a = self._q(q), self._v(v, "v"), self._v(a, "a")
        if f_ext is None:
            return pin.rnea(self._model, self._data, q, v, a).copy()
        return pin.rnea(self._model, self._data, q, v, a, self._fext(f_ext)).copy()

    def external_forces(self, q: Any, forces: Mapping[str, Any]) -> pin.StdVec_Force:
        """Convert world-frame forces on frames into Pinocchio's per-joint ``f_ext``.

        Args:
            forces: Frame name -> force [N], shape (3,), applied at the frame origin, or wrench (6,) =
                (force [N], torque [N m]) about the frame origin; both in world coordinates.
        """
        pin.framesForwardKinematics(self._model, self._data, self._q(q))
        f_ext = pin.StdVec_Force()
        for _ in range(self._model.njoints):
            f_ext.append(pin.Force.Zero())
        rotation = self._placement.rotation  # base <- world is rotation.T
        for frame, value in forces.items():
            frame_id = self._frame_id(frame)
            wrench = _wrench(value, f"forces[{frame!r}]")
            force_at_frame = pin.Force(rotation.T @ wrench[:3], rotation.T @ wrench[3:])
            frame_origin = pin.SE3(np.eye(3), self._data.oMf[frame_id].translation)
            joint = self._model.frames[frame_id].parentJoint
            f_ext[joint] += self._data.oMi[joint].actInv(frame_origin.act(force_at_frame))
        return f_ext

    def regressor(self, q: Any, v: Any, a: Any) -> np.ndarray:
        """Joint-torque regressor Y(q, v, a), shape (nv, 10 * n_bodies): ``Y @ inertial_parameters() == rnea``.

        Columns come in blocks of 10 per joint body (Pinocchio's dynamic parameters: m, m c, I at the joint
        origin).  For the Slotine-Li form Y(q, qdot, qdot_r, qddot_r) see :meth:`slotine_li_regressor`.
        """
        q, v, a = self._q(q), self._v(v, "v"), self._v(a, "a")
        return pin.computeJointTorqueRegressor(self._model, self._data, q, v, a).copy()

    def slotine_li_torque(self, q: Any, v: Any, v_r: Any, a_r: Any) -> np.ndarray:
        """M(q) a_r + C(q, v) v_r + G(q) [N m], the model term of sliding and adaptive laws (thesis (3.39)-(3.40)).

        C is the Christoffel-symbol Coriolis matrix (bilinear and symmetric in its velocity arguments, with
        M_dot - 2 C skew-symmetric), obtained by polarisation of RNEA's velocity-product torques h(w) = C(q, w) w:
        C(q, v) v_r = (h(v + v_r) - h(v - v_r)) / 4.  Three RNEA passes, no matrix is formed.
        """
        q, v, v_r, a_r = self._q(q), self._v(v, "v"), self._v(v_r, "v_r"), self._v(a_r, "a_r")
        kernel = self._dynamics()
        if kernel is None:
            return self._slotine_li_torque_python(q, v, v_r, a_r)
        return kernel.slotine_li_torque(self._model_gravity, q, v, v_r, a_r)

    def _slotine_li_torque_python(self, q: np.ndarray, v: np.ndarray, v_r: np.ndarray, a_r: np.ndarray) -> np.ndarray:
        """:meth:`slotine_li_torque` through Pinocchio's Python API (the twin of the compiled ``HandDynamics``)."""
        model, data, zero = self._model, self._data, np.zeros(self._model.nv)
        plus = pin.rnea(model, data, q, v + v_r, zero).copy()
        minus = pin.rnea(model, data, q, v - v_r, zero)  # gravity cancels in the difference
        return pin.rnea(model, data, q, zero, a_r) + 0.25 * (plus - minus)

    def slotine_li_regressor(self, q: Any, v: Any, v_r: Any, a_r: Any) -> np.ndarray:
        """Y(q, v, v_r, a_r), shape (nv, 10 n_bodies): ``Y @ inertial_parameters() == slotine_li_torque(...)``.

        Pinocchio's regressor takes (q, v, a) and gives M a + C(q, v) v + G; the adaptive laws need the
        reference velocity in the Coriolis term, so this builds it from three regressors by the same polarisation
        as :meth:`slotine_li_torque`.
        """
        q, v, v_r, a_r = self._q(q), self._v(v, "v"), self._v(v_r, "v_r"), self._v(a_r, "a_r")
        model, data, zero = self._model, self._data, np.zeros(self._model.nv)
        plus = pin.computeJointTorqueRegressor(model, data, q, v + v_r, zero).copy()
        minus = pin.computeJointTorqueRegressor(model, data, q, v - v_r, zero).copy()
        return pin.computeJointTorqueRegressor(model, data, q, zero, a_r) + 0.25 * (plus - minus)

    def inertial_parameters(self) -> np.ndarray:
        """Dynamic parameters of every moving body, shape (10 * n_bodies,).

        Per body: (m, mc_x, mc_y, mc_z, I_xx, I_xy, I_yy, I_xz, I_yz, I_zz), inertia about the joint origin, in
        the joint frame (Pinocchio's ``Inertia.toDynamicParameters``).
        """
        inertias = self._model.inertias
        return np.concatenate([inertias[j].toDynamicParameters() for j in range(1, self._model.njoints)])

    # ------------------------------------------------------------------ model errors
    def perturbed(
        self,
        mass_scale: float | Sequence[float] = 1.0,
        payload: tuple[str, float] | None = None,
        name: str | None = None,
    ) -> Hand:
        """A copy of this hand with different inertial parameters: a controller's nominal model, or a plant.

        Kinematics, limits and fingertips are unchanged; the copy has its own Pinocchio model and data.

        Args:
            mass_scale: Factor on each moving body's mass and rotational inertia (centre of mass unchanged): one
                number, or one per body in joint order (``nv`` values for a hand of 1-DOF joints).  0.7 is a
                nominal model that underestimates every body by 30 %.
            payload: ``(frame, mass [kg])``: a point mass rigidly attached at that frame's origin, e.g. an unknown
                load at a fingertip.
            name: Display name (default: this hand's name with the perturbation).

        Raises:
            InputError: Non-positive or non-finite scales, a negative payload, or an unknown frame.
        """
        n_bodies = self._model.njoints - 1
        uniform = np.ndim(mass_scale) == 0
        scales = as_vector(np.full(n_bodies, mass_scale) if uniform else mass_scale, "mass_scale", n_bodies)
        if np.any(scales <= 0.0):
            raise InputError(f"`mass_scale` must be positive and finite, got {mass_scale!r}")
        model = pin.Model(self._model)
        for joint, scale in enumerate(scales, start=1):
            inertia = model.inertias[joint]
            model.inertias[joint] = pin.Inertia(scale * inertia.mass, inertia.lever.copy(), scale * inertia.inertia)
        label = f"mass x{float(mass_scale):g}" if uniform else "masses scaled"
        if payload is not None:
            frame, mass = payload
            frame_id = self._frame_id(frame)
            mass = float(mass)
            if not np.isfinite(mass) or mass < 0.0:
                raise InputError(f"payload mass must be a finite number >= 0 [kg], got {payload[1]!r}")
            placement = model.frames[frame_id].placement  # frame in its parent joint's frame
            joint = model.frames[frame_id].parentJoint
            point = pin.Inertia(mass, placement.translation.copy(), np.zeros((3, 3)))
            model.inertias[joint] = model.inertias[joint] + point
            label += f", {mass:g} kg at {frame}"
        return Hand(
            model,
            self._fingertips,
            name=name or f"{self.name} ({label})",
            base_placement=self.base_placement,
            gravity=self.gravity,
            urdf_path=self.urdf_path,
            collision_geometry=self.collision_geometry,
            base_joints=self.base_joints,
        )

    # ------------------------------------------------------------------ display
    def summary(self) -> str:
        """A human-readable table of joints, limits, fingers and mass."""
        lines = [f"{self.name}: {self.nv} joints, {len(self.fingers)} fingers, {self.total_mass:.4f} kg"]
        lines.append(
            f"  {'joint':<16}{'lower':>9}{'upper':>9}  [deg]{'vel':>8} [rad/s]{'effort':>8} [N m]{'link mass':>11} [kg]"
        )
        for i, joint in enumerate(self.joint_names):
            joint_id = self._model.getJointId(joint)
            mass = self._model.inertias[joint_id].mass
            prismatic = self._model.joints[joint_id].shortname().startswith("JointModelP")
            limits = (f"{self.lower[i]:9.3f}{self.upper[i]:9.3f}" if prismatic  # a sliding joint: [m], [m/s], [N]
                      else f"{np.degrees(self.lower[i]):9.1f}{np.degrees(self.upper[i]):9.1f}")  # fmt: skip
            lines.append(
                f"  {joint:<16}{limits}{self.velocity_limit[i]:13.3f}{self.effort_limit[i]:15.3f}{mass:14.4f}"
                + "  [m, N]" * prismatic
            )
        for finger in self.fingers:
            lines.append(
                f"  finger {finger}: tip {self._fingertips[finger]!r}, joints {', '.join(self.finger_joints(finger))}"
            )
        return "\n".join(lines)

    def __repr__(self) -> str:
        return f"Hand({self.name!r}, nq={self.nq}, fingers={self.fingers})"

    # ------------------------------------------------------------------ validation helpers
    def _q(self, q: Any) -> np.ndarray:
        return as_vector(q, "q", self._model.nq)

    def _v(self, v: Any, name: str) -> np.ndarray:
        return as_vector(v, name, self._model.nv)

    def _frame_id(self, frame: str) -> int:
        if not isinstance(frame, str) or not self._model.existFrame(frame):
            require_name(frame, self.frame_names(), "frame")
        return self._model.getFrameId(frame)

    def _fext(self, f_ext: Any) -> pin.StdVec_Force:
        njoints = self._model.njoints
        if isinstance(f_ext, pin.StdVec_Force) or (
            isinstance(f_ext, Sequence) and f_ext and isinstance(f_ext[0], pin.Force)
        ):
            if len(f_ext) != njoints:
                raise InputError(
                    f"`f_ext` must hold {njoints} forces (one per joint, universe first), got {len(f_ext)}"
                )
            for i, force in enumerate(f_ext):
                as_vector(force.vector, f"f_ext[{i}]", 6)
            if isinstance(f_ext, pin.StdVec_Force):
                return f_ext
            vector = pin.StdVec_Force()
            for force in f_ext:
                vector.append(force)
            return vector
        array = as_array(f_ext, "f_ext", (njoints, 6))
        vector = pin.StdVec_Force()
        for row in array:
            vector.append(pin.Force(row[:3], row[3:]))
        return vector


class BarrettHand(Hand):
    """The packaged Barrett BH8-280 (``urdf/barrett_hand.urdf``): 8 independent joints, fingers F1, F2, F3.

    Joint order: F1_spread, F1_proximal, F1_distal, F2_spread, F2_proximal, F2_distal, F3_proximal, F3_distal.
    """

    def __init__(
        self,
        *,
        base_placement: pin.SE3 | None = None,
        gravity: Sequence[float] = STANDARD_GRAVITY,
        name: str = "BarrettHand BH8-280",
    ) -> None:
        """Load the packaged URDF; ``base_placement`` and ``gravity`` as for :class:`Hand`."""
        path = barrett_urdf_path()
        model, _ = _build_model(path)
        super().__init__(
            model, BARRETT_FINGERTIPS, name=name, base_placement=base_placement, gravity=gravity, urdf_path=path
        )


def _build_model(path: str | Path) -> tuple[pin.Model, Any]:
    """Safely read a URDF and build its Pinocchio model (``<mimic>`` tags not applied: independent joints)."""
    text, root = read_urdf(path)
    _check_inertials(root, path)
    try:
        model = pin.buildModelFromXML(text)
    except (ValueError, RuntimeError) as error:
        raise ModelError(f"Pinocchio cannot build a model from {str(path)!r}: {error}") from error
    if model.nv == 0:
        raise ModelError(f"URDF {str(path)!r} has no moving joints")
    _check_model_inertias(model, path)
    return model, root


# Inertia checks: relative tolerance on the principal moments, plus an absolute floor [kg m^2] far below any real
# body's inertia (a 1 mg, 1 mm cube has ~2e-13) that absorbs the 1e-20-sized noise some published URDFs carry.
_INERTIA_RTOL = 1e-9
_INERTIA_ATOL = 1e-15
_INERTIA_ATTRIBUTES = ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")


def _check_inertials(root: Any, path: str | Path) -> None:
    """Refuse ``<inertial>`` blocks that urdfdom would silently drop or that no rigid body can have.

    Every ``<inertial>`` of every ``<link>`` needs a ``<mass value>`` that is finite and >= 0, six finite
    ``<inertia>`` components, a finite ``<origin>`` and a tensor that :func:`_inertia_error` accepts.  A massless
    link with zero inertia (or no ``<inertial>``), a point mass and a thin rod stay legal.  Principal moments that
    break the triangle inequality while ``ixx, iyy, izz`` satisfy it (off-diagonal products of inertia that no
    body has, e.g. example-robot-data's Allegro fingertips) only warn: such a tensor is still positive definite.

    Raises:
        ModelError: Naming the file and the link.
    """
    odd = []  # links whose principal moments break the triangle inequality: one warning for the file
    for link in root.findall("link"):
        where = f"URDF {str(path)!r} link {link.get('name')!r}"
        for inertial in link.findall("inertial"):
            mass_element = inertial.find("mass")
            mass = _urdf_number(None if mass_element is None else mass_element.get("value"))
            if mass is None or mass < 0.0:
                got = "no <mass value=...>" if mass_element is None else repr(mass_element.get("value"))
                raise ModelError(f"{where}: <inertial> mass must be a finite number >= 0 [kg], got {got}")
            inertia_element = inertial.find("inertia")
            c: dict[str, float] = {}
            for name in _INERTIA_ATTRIBUTES:
                value = None if inertia_element is None else inertia_element.get(name)
                number = _urdf_number(value)
                if number is None:
                    got = "no <inertia>" if inertia_element is None else f"{name}={value!r}"
                    raise ModelError(
                        f"{where}: <inertial> needs six finite <inertia> components "
                        f"{', '.join(_INERTIA_ATTRIBUTES)} [kg m^2], got {got}"
                    )
                c[name] = number
            origin = inertial.find("origin")
            for name in ("xyz", "rpy"):
                value = None if origin is None else origin.get(name)
                numbers = [] if value is None else [_urdf_number(x) for x in value.split()]
                if value is not None and (len(numbers) != 3 or None in numbers):
                    raise ModelError(f"{where}: <inertial> <origin {name}> must be 3 finite numbers, got {value!r}")
            tensor = np.array(
                [[c["ixx"], c["ixy"], c["ixz"]], [c["ixy"], c["iyy"], c["iyz"]], [c["ixz"], c["iyz"], c["izz"]]]
            )
            components = ", ".join(f"{name}={c[name]:.6g}" for name in _INERTIA_ATTRIBUTES)
            error = _inertia_error(tensor)
            if error:
                raise ModelError(f"{where}: {error} ({components})")
            moments = np.linalg.eigvalsh(tensor)
            if moments[0] + moments[1] < moments[2] - _inertia_tolerance(moments):
                odd.append(
                    f"link {link.get('name')!r}: the principal moments of inertia [{_shown(moments)}] kg m^2 break "
                    f"the triangle inequality ({moments[0]:.6g} + {moments[1]:.6g} < {moments[2]:.6g}) ({components})"
                )
    if odd:
        warnings.warn(
            f"URDF {str(path)!r}: no rigid body has these inertias (check the signs of ixy, ixz, iyz); the dynamics "
            f"use them as given: " + "; ".join(odd),
            UserWarning,
            stacklevel=4,
        )


def _check_model_inertias(model: pin.Model, path: str | Path) -> None:
    """Refuse non-finite, negative or indefinite inertias in what Pinocchio built (links merged across fixed joints)."""
    for joint, inertia in enumerate(model.inertias):
        links = [f.name for f in model.frames if f.type == pin.FrameType.BODY and f.parentJoint == joint]
        where = f"URDF {str(path)!r}: the body of joint {model.names[joint]!r} (links {', '.join(links)})"
        mass, lever, tensor = float(inertia.mass), np.array(inertia.lever), np.array(inertia.inertia)
        if not (np.isfinite(mass) and mass >= 0.0 and np.all(np.isfinite(lever)) and np.all(np.isfinite(tensor))):
            raise ModelError(
                f"{where} must have a finite mass >= 0 [kg], centre of mass and inertia in Pinocchio's model, got "
                f"mass {mass!r}, centre of mass {lever.tolist()}, inertia {tensor.tolist()}"
            )
        error = _inertia_error(tensor)
        if error:
            raise ModelError(f"{where}: {error} in Pinocchio's model")


def _inertia_error(tensor: np.ndarray) -> str | None:
    """Why a finite rotational inertia about the centre of mass [kg m^2] is impossible, or ``None``.

    It must be positive semi-definite (zero moments, of point masses and thin rods, are legal) and its diagonal
    ``ixx, iyy, izz`` must satisfy the triangle inequality (``ixx + iyy - izz = 2 * integral(z^2 dm) >= 0``), both
    within ``_INERTIA_RTOL`` of the largest principal moment plus ``_INERTIA_ATOL``.
    """
    moments = np.linalg.eigvalsh(0.5 * (tensor + tensor.T))  # ascending
    tolerance = _inertia_tolerance(moments)
    if moments[0] < -tolerance:
        return f"the inertia tensor must be positive semi-definite, got principal moments [{_shown(moments)}] kg m^2"
    diagonal = np.sort(np.diag(tensor))
    if diagonal[0] + diagonal[1] < diagonal[2] - tolerance:
        return (
            f"the moments of inertia ixx, iyy, izz break the triangle inequality "
            f"({diagonal[0]:.6g} + {diagonal[1]:.6g} < {diagonal[2]:.6g} kg m^2): no rigid body has them"
        )
    return None


def _inertia_tolerance(moments: np.ndarray) -> float:
    return _INERTIA_RTOL * float(np.max(np.abs(moments))) + _INERTIA_ATOL


def _shown(values: np.ndarray) -> str:
    return ", ".join(f"{value:.6g}" for value in values)


def _urdf_number(text: str | None) -> float | None:
    """A finite float from a URDF attribute, or ``None`` if it is missing, not a number, NaN or inf."""
    if text is None or "_" in text:  # Python's float() accepts "1_000", urdfdom does not
        return None
    try:
        value = float(text)
    except ValueError:
        return None
    return value if np.isfinite(value) else None


def _wrench(value: Any, name: str) -> np.ndarray:
    """A force (3,) or wrench (6,) as a wrench (6,) = (force, torque)."""
    size = np.size(value)
    wrench = as_vector(np.ravel(value) if size in (3, 6) else value, name, 6 if size == 6 else 3)
    return wrench if size == 6 else np.concatenate((wrench, np.zeros(3)))


def _generator(rng: np.random.Generator | int) -> np.random.Generator:
    if isinstance(rng, np.random.Generator):
        return rng
    if isinstance(rng, (int, np.integer)) and not isinstance(rng, bool):
        return np.random.default_rng(int(rng))
    raise InputError(f"`rng` must be a numpy.random.Generator or an integer seed, got {rng!r}")
