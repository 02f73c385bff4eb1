"""HandModel: the Pinocchio model a :class:`~bhgrasp.model.hand.Hand` wraps, with its names, limits, placement, gravity.

The first of the hand's layers, one module each: :class:`HandModel` (Pinocchio model and data, fingertip frames, names,
sizes, limits, world placement, gravity, configurations, and the checks of ``q``, ``v`` and frame names that the layers
above use) <- :class:`~bhgrasp.model.hand_kinematics.HandKinematics` <-
:class:`~bhgrasp.model.hand_dynamics.HandDynamics` <- :class:`~bhgrasp.model.hand.Hand`.  Conventions as in
:mod:`bhgrasp.model.hand`.
"""

from __future__ import annotations

import functools
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin

from bhgrasp._validation import as_array, as_generator, as_vector, require_name, require_rotation
from bhgrasp.errors import InputError, ModelError
from bhgrasp.model.couplings import Coupling, check_couplings, coupled_model, independent_model, model_couplings

STANDARD_GRAVITY = (0.0, 0.0, -9.81)  # [m/s^2] in world coordinates


class HandModel:
    """A fixed-base hand's Pinocchio model and data, fingertip frames, names, sizes, limits, placement and gravity.

    The base layer of :class:`~bhgrasp.model.hand.Hand`, whose docstring says how its methods treat inputs and results.
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
                :func:`~bhgrasp.model.mount.mounted`): :meth:`finger_joints` leaves them out.
        """
        if not fingertips:
            raise ModelError("a hand needs at least one fingertip frame")
        self._model = model
        self._data = model.createData()
        self.couplings: tuple[Coupling, ...] = model_couplings(model)  # mimic joints (no coordinate of their own)
        check_couplings(model, self.couplings)
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
        """Names of the joints with a coordinate, in Pinocchio's order (the order of ``q``, ``v`` and ``tau``).

        A mimic joint (:attr:`couplings`) has none: it moves with the joint it mimics and is not listed here.
        """
        mimic = {coupling.joint for coupling in self.couplings}  # built once: controllers read it every cycle
        return tuple(name for name in self._model.names[1:] if name not in mimic)

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
        """Index of a 1-DOF joint in ``q``/``v`` (a mimic joint has none: InputError naming the joint it follows)."""
        index = self._joint_indices.get(joint) if isinstance(joint, str) else None
        if index is None:
            for coupling in self.couplings:
                if coupling.joint == joint:
                    source, multiplier, offset = coupling.mimics, coupling.multiplier, coupling.offset
                    raise InputError(
                        f"joint {joint!r} mimics {source!r} (q = {multiplier:g} q[{source!r}] + {offset:g}) and has no "
                        f"coordinate of its own: use {source!r}"
                    )
            require_name(joint, self.joint_names, "joint")  # raises: an unknown name
        return index

    @functools.cached_property
    def _joint_indices(self) -> dict[str, int]:
        return {name: self._model.joints[self._model.getJointId(name)].idx_v for name in self.joint_names}

    def finger_joints(self, finger: str) -> tuple[str, ...]:
        """Names of the joints whose coordinates move a finger's tip, from the base outward (not :attr:`base_joints`).

        A mimic joint counts as the joint it mimics (listed once, where first met).
        """
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
        base, mimics = set(self.base_joints), {coupling.joint: coupling.mimics for coupling in self.couplings}
        result = {}
        for finger, joints in supports.items():
            names = (mimics.get(model.names[j], model.names[j]) for j in joints if model.names[j] not in base)
            result[finger] = tuple(dict.fromkeys(names))  # in order, each once
        return result

    def finger_indices(self, finger: str) -> np.ndarray:
        """Velocity indices of a finger's joints (columns of its Jacobian that can be non-zero)."""
        return np.array([self.joint_index(joint) for joint in self.finger_joints(finger)], dtype=int)

    def frame_names(self) -> tuple[str, ...]:
        """Every frame of the model (links, joints, fixed frames)."""
        return tuple(frame.name for frame in self._model.frames)

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

    def neutral(self) -> np.ndarray:
        """Pinocchio's neutral configuration (all zeros for revolute joints: Barrett fingers open and flat)."""
        return pin.neutral(self._model)

    def random_configuration(self, rng: np.random.Generator | int) -> np.ndarray:
        """Configuration drawn uniformly inside the joint limits.

        Args:
            rng: A NumPy generator or an integer seed (there is no unseeded default).
        """
        generator = as_generator(rng)
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

    # ------------------------------------------------------------------ copies and pickles
    def __getstate__(self) -> dict:
        """Pickles hold the model; a model with mimic joints as its independent twin and :attr:`couplings`.

        Pinocchio 4.1 does not write a mimic joint's extended sizes, and a model read back crashes every algorithm
        (:mod:`bhgrasp.model.couplings`); its Data (and a cached twin) are rebuilt on load either way.
        """
        state = dict(self.__dict__)
        del state["_data"]
        state.pop("_twin", None)  # HandDynamics' cached twin: rebuilt on first use
        if self.couplings:
            state["_model"] = independent_model(self._model)
        return state

    def __setstate__(self, state: dict) -> None:
        if state.get("couplings"):
            state["_model"] = coupled_model(state["_model"], state["couplings"])
            state["_model"].gravity.linear = state["_model_gravity"]
        self.__dict__.update(state)
        self._data = self._model.createData()

    # ------------------------------------------------------------------ validation helpers
    def _q(self, q: Any) -> np.ndarray:
        return as_vector(q, "q", self._model.nq)

    def _v(self, v: Any, name: str) -> np.ndarray:
        return as_vector(v, name, self._model.nv)

    def _frame_id(self, frame: str) -> int:
        if not isinstance(frame, str) or not self._model.existFrame(frame):
            require_name(frame, self.frame_names(), "frame")
        return self._model.getFrameId(frame)
