"""Hand: a robot hand loaded into Pinocchio, with kinematics, Jacobians and rigid-body dynamics.

Conventions: SI units and radians; ``q`` (size ``nq``) and ``v`` (size ``nv``) in Pinocchio's joint order
(:attr:`Hand.joint_names`).  "World" is the frame the hand base is placed in by :attr:`Hand.base_placement`
(identity by default, so world = hand base frame W); gravity is given in world coordinates.

One class, as Pinocchio keeps a model and its algorithms apart: :class:`Hand` holds the model, its data, names,
limits, the base's placement and gravity, and the input checks; the algorithms over it are free functions, one
module per family, that the class also offers as methods (``hand.mass_matrix(q)`` is
``hand_dynamics.mass_matrix(hand, q)``): :mod:`~bhgrasp.model.hand_joints` (configurations, the joint table),
:mod:`~bhgrasp.model.hand_kinematics` (frame poses, fingertip positions, Jacobians),
:mod:`~bhgrasp.model.hand_dynamics` (CRBA, RNEA, ABA, Coriolis, external forces, regressors, perturbed copies) and
:mod:`~bhgrasp.model.urdf` (loading a URDF, collision shapes).
"""

from __future__ import annotations

import functools
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin

from bhgrasp._validation import as_array, as_vector, require_name, require_rotation
from bhgrasp.errors import InputError, ModelError
from bhgrasp.model import hand_dynamics, hand_joints, hand_kinematics, urdf
from bhgrasp.model.couplings import (
    Coupling,
    TwinMap,
    check_couplings,
    coupled_model,
    independent_model,
    model_couplings,
    twin_map,
)
from bhgrasp.model.hand_description import BaseFrame, JointLayout

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
            urdf_path: The URDF the model came from, if any (its collision geometry: :meth:`collision_model`).
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
        self.base_joints = tuple(require_name(joint, model.names[1:], "joint") for joint in base_joints)
        self.layout = JointLayout.of(model, self._tip_ids, self.base_joints, self.couplings)
        self._placement = base_placement if base_placement is not None else pin.SE3.Identity()
        self._gravity_world = as_vector(gravity, "gravity", 3).copy()
        self.base_placement = self._placement  # checks both and builds the base frame

    from_urdf = classmethod(urdf.hand_from_urdf)

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

    @property
    def joint_names(self) -> tuple[str, ...]:
        """Names of the joints with a coordinate, in Pinocchio's order (the order of ``q``, ``v`` and ``tau``).

        A mimic joint (:attr:`couplings`) has none: it moves with the joint it mimics and is not listed here.
        """
        return self.layout.joint_names

    @property
    def fingers(self) -> tuple[str, ...]:
        """Finger names, e.g. ``("F1", "F2", "F3")`` for the Barrett hand."""
        return tuple(self._tip_ids)

    @property
    def fingertip_frames(self) -> dict[str, str]:
        """Finger name -> fingertip frame name."""
        return {finger: self._model.frames[i].name for finger, i in self._tip_ids.items()}

    @property
    def fingertip_ids(self) -> tuple[int, ...]:
        """Pinocchio frame ids of the fingertips, in :attr:`fingers` order."""
        return tuple(self._tip_ids.values())

    def fingertip_id(self, finger: str) -> int:
        """Pinocchio frame id of a finger's tip (InputError naming the fingers for an unknown one)."""
        frame_id = self._tip_ids.get(finger) if isinstance(finger, str) else None
        if frame_id is None:
            require_name(finger, self.fingers, "finger")  # raises
        return frame_id

    lower = property(hand_joints.lower)
    upper = property(hand_joints.upper)
    velocity_limit = property(hand_joints.velocity_limit)
    effort_limit = property(hand_joints.effort_limit)
    total_mass = property(hand_dynamics.total_mass)
    joint_index = hand_joints.joint_index
    finger_joints = hand_joints.finger_joints
    finger_indices = hand_joints.finger_indices

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
        self._update_base()

    @property
    def gravity(self) -> np.ndarray:
        """Gravity in world coordinates [m/s^2]; set it to mount the hand in any orientation."""
        return self._gravity_world.copy()

    @gravity.setter
    def gravity(self, gravity: Sequence[float]) -> None:
        self._gravity_world = as_vector(gravity, "gravity", 3).copy()
        self._update_base()

    @property
    def base(self) -> BaseFrame:
        """The base's placement and gravity in base coordinates, read-only (a new object after every change)."""
        return self._base

    def _update_base(self) -> None:
        placement = self._placement
        rotation, translation = placement.rotation, placement.translation  # views of the placement (Eigen's order)
        gravity = rotation.T @ self._gravity_world
        self._model.gravity.linear = gravity
        for array in (rotation, translation, gravity):
            array.flags.writeable = False
        self._base = BaseFrame(placement, rotation, translation, bool(placement.isIdentity(0.0)), gravity)

    # ------------------------------------------------------------------ the algorithms, as methods
    neutral = hand_joints.neutral
    random_configuration = hand_joints.random_configuration
    configuration = hand_joints.configuration
    within_limits = hand_joints.within_limits
    summary = hand_joints.summary
    frame_placement = hand_kinematics.frame_placement
    fingertip_positions = hand_kinematics.fingertip_positions
    frame_jacobian = hand_kinematics.frame_jacobian
    fingertip_jacobian = hand_kinematics.fingertip_jacobian
    point_jacobian = hand_kinematics.point_jacobian
    point_jacobians = hand_kinematics.point_jacobians
    fingertip_bias_acceleration = hand_kinematics.fingertip_bias_acceleration
    mass_matrix = hand_dynamics.mass_matrix
    nonlinear_effects = hand_dynamics.nonlinear_effects
    gravity_torques = hand_dynamics.gravity_torques
    coriolis_matrix = hand_dynamics.coriolis_matrix
    forward_dynamics = hand_dynamics.forward_dynamics
    inverse_dynamics = hand_dynamics.inverse_dynamics
    external_forces = hand_dynamics.external_forces
    regressor = hand_dynamics.regressor
    slotine_li_torque = hand_dynamics.slotine_li_torque
    slotine_li_regressor = hand_dynamics.slotine_li_regressor
    inertial_parameters = hand_dynamics.inertial_parameters
    compiled_dynamics = hand_dynamics.compiled_dynamics
    perturbed = hand_dynamics.perturbed
    collision_model = urdf.collision_model

    @functools.cached_property
    def twin(self) -> tuple[pin.Model, pin.Data, TwinMap]:
        """The independent twin of a hand with mimic joints, its data and the map to it (built on first use)."""
        twin = independent_model(self._model)
        return twin, twin.createData(), twin_map(self._model, twin)

    def with_model(self, model: pin.Model, name: str) -> Hand:
        """This hand (fingertips, placement, gravity, URDF, collision shapes, base joints) on another model."""
        return Hand(
            model,
            self.fingertip_frames,
            name=name,
            base_placement=self.base_placement,
            gravity=self.gravity,
            urdf_path=self.urdf_path,
            collision_geometry=self.collision_geometry,
            base_joints=self.base_joints,
        )

    # ------------------------------------------------------------------ checks of the inputs
    def check_q(self, q: Any) -> np.ndarray:
        """``q`` as a finite float vector of size ``nq`` (InputError otherwise)."""
        return as_vector(q, "q", self._model.nq)

    def check_v(self, v: Any, name: str = "v") -> np.ndarray:
        """A velocity-sized vector (``v``, ``a``, ``tau``, ...) as a finite float vector of size ``nv``."""
        return as_vector(v, name, self._model.nv)

    def frame_id(self, frame: str) -> int:
        """Pinocchio id of a frame (InputError naming the frames for an unknown one)."""
        if not isinstance(frame, str) or not self._model.existFrame(frame):
            require_name(frame, self.frame_names(), "frame")
        return self._model.getFrameId(frame)

    # ------------------------------------------------------------------ copies and pickles
    def __getstate__(self) -> dict:
        """Pickles hold the model; a model with mimic joints as its independent twin and :attr:`couplings`.

        Pinocchio 4.1 does not write a mimic joint's extended sizes, and a model read back crashes every algorithm
        (:mod:`bhgrasp.model.couplings`); its data, base frame and twin are rebuilt on load.
        """
        state = dict(self.__dict__)
        for rebuilt in ("_data", "_base", "twin"):
            state.pop(rebuilt, None)
        if self.couplings:
            state["_model"] = independent_model(self._model)
        return state

    def __setstate__(self, state: dict) -> None:
        if state.get("couplings"):
            state["_model"] = coupled_model(state["_model"], state["couplings"])
        self.__dict__.update(state)
        self._data = self._model.createData()
        self._update_base()

    def __repr__(self) -> str:
        return f"Hand({self.name!r}, nq={self.nq}, fingers={self.fingers})"
