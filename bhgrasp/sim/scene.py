"""Scene: the hand, free rigid objects and a fixed environment as one Pinocchio model plus coal collision geometry.

The model gives the state's layout and its integration; the dynamics run part by part (the hand's model, one per
object: :mod:`~bhgrasp.sim.scene_parts`), as no joint links an object to the hand or to another object.

Layout of the state: ``q = (q_hand, q_object_1, ...)``, ``v = (v_hand, v_object_1, ...)``.  A free object adds a
translation joint and a spherical joint below it (7 coordinates: position [m] and quaternion (x, y, z, w), as a free
flyer's; 6 velocities: the linear velocity [m/s] of its centre of mass in the *world* frame, then its angular velocity
[rad/s] in its *body* frame).  Translating world-aligned keeps the translational dynamics free of Coriolis terms (``m
dv/dt = f`` exactly), so the integrators conserve linear momentum; Pinocchio's free flyer would step the linear velocity
in the rotating body frame, where the explicit ``w x v`` term pumps energy.  A spring-mounted object
(:class:`~bhgrasp.model.spring_mounted.SpringMounted`) adds one prismatic coordinate: its displacement [m] from rest
along its direction.  World = the frame the hand base is placed in (``hand.base_placement``); gravity is the hand's.
"""

from __future__ import annotations

import copy
from collections.abc import Sequence

import coal
import numpy as np
import pinocchio as pin

from bhgrasp._validation import as_rates
from bhgrasp.errors import InputError
from bhgrasp.model.hand import Hand
from bhgrasp.model.objects import FixedBox, Plane, RigidObject
from bhgrasp.model.spring_mounted import SpringMounted
from bhgrasp.sim.collision_pair import CollisionPair
from bhgrasp.sim.scene_parts import SceneParts

Environment = Plane | FixedBox


class Scene:
    """Hand + objects + environment: one ``pin.Model`` (fixed hand base) and one ``pin.GeometryModel``."""

    def __init__(
        self,
        hand: Hand,
        objects: Sequence[RigidObject | SpringMounted] = (),
        environment: Sequence[Environment] = (),
        environment_touches_hand: bool = True,
        object_drag: float | Sequence[float] = 0.0,
    ) -> None:
        """Assemble the scene.

        Args:
            hand: The hand; its base placement and gravity are the scene's.  Its collision geometry is
                ``hand.collision_geometry`` if set, else read from ``hand.urdf_path`` (else none).
            objects: Free rigid objects and spring-mounted (compliant) objects, in state order.
            environment: Fixed shapes (planes, fixed boxes).
            environment_touches_hand: Whether the environment also stops the hand's moving links (a table under a
                closing finger); :class:`~bhgrasp.grasp.sensing.ContactSensing` reads object contacts only (body a a
                hand link), the BH8-280's sensors (:mod:`bhgrasp.barrett.sensors`) both.
            object_drag: A viscous drag rate d [1/s] on every free object, or one rate per object, stepped
                implicitly with the joint damping: -d m v on its centre's velocity, -d I_ii w_i about its body axes
                (a primitive's principal axes); for a pile settling (:mod:`bhgrasp.scenarios.clutter`), a stand-in
                for the rolling resistance point contacts lack; 0 (the default) adds none.
        """
        self.hand = hand
        self.objects = tuple(objects)
        self.environment = tuple(environment)
        self.environment_touches_hand = bool(environment_touches_hand)
        self.object_drag = as_rates(object_drag, "object_drag", len(self.objects))
        for i, item in enumerate(self.objects):
            if not isinstance(item, RigidObject | SpringMounted):
                raise InputError(f"`objects[{i}]` must be a RigidObject or SpringMounted, got {type(item).__name__}")
        for i, item in enumerate(self.environment):
            if not isinstance(item, Plane | FixedBox):
                raise InputError(f"`environment[{i}]` must be a Plane or FixedBox, got {type(item).__name__}")
        self.object_names = _unique_names([o.name for o in self.objects], "object")
        self.environment_names = _unique_names([e.name for e in self.environment], "environment")

        self.hand_model = _placed_copy(hand.model, hand.base_placement)  # the hand's part (sim.scene_parts)
        self.hand_model.gravity.linear = hand.gravity
        self.model = copy.deepcopy(self.hand_model)
        self.nq_hand, self.nv_hand = hand.nq, hand.nv
        self._add_objects()
        self._data: pin.Data | None = None
        self._parts: SceneParts | None = None  # energy()'s work space
        self._add_geometries()

    @property
    def data(self) -> pin.Data:
        """A Pinocchio data of the whole :attr:`model`, made on first use.

        Its size grows as nv^3 (1.9 GB for 64 free objects, 3.7 GB at its peak while made); the simulator works on
        :class:`~bhgrasp.sim.scene_parts.SceneParts` instead.
        """
        if self._data is None:
            self._data = self.model.createData()
        return self._data

    def _add_objects(self) -> None:
        """Each object's joints in the model, their slices of q and v, and the springs of spring-mounted ones."""
        self.object_joints: list[int] = []  # the joint carrying each object's body (its spherical joint)
        self._object_root: list[int] = []  # the object's first joint (its translation joint when free)
        stiffness, damping = [], []
        for name, item, drag in zip(self.object_names, self.objects, self.object_drag):
            root, joint = self._add_object(name, item)
            self._object_root.append(root)
            self.object_joints.append(joint)
            if isinstance(item, SpringMounted):
                stiffness.append(item.stiffness)
                damping.append(item.damping)
            else:
                stiffness += [0.0] * 6
                damping += list(drag * np.concatenate(([item.mass] * 3, np.diag(item.inertia))))
        self._q_slices, self._v_slices = [], []  # read every step: looked up in the model once
        for root, joint in zip(self._object_root, self.object_joints):
            first, body = self.model.joints[root], self.model.joints[joint]
            self._q_slices.append(slice(first.idx_q, body.idx_q + body.nq))
            self._v_slices.append(slice(first.idx_v, body.idx_v + body.nv))
        self.joint_stiffness = np.concatenate((np.zeros(self.nv_hand), stiffness))  # springs [N/m]
        self.joint_damping = np.concatenate((np.zeros(self.nv_hand), damping))  # [N s/m]

    def _add_geometries(self) -> None:
        """The hand's, the objects' and the environment's collision geometry, their pairs and their requests."""
        self.geometry = self._hand_geometry()
        self.hand_geometries = list(range(self.geometry.ngeoms))
        self.object_geometry_sets: list[list[int]] = []  # each object's geometries (a decomposed mesh has several)
        self._object_of_geometry: dict[int, int] = {}
        for index, (name, joint, item) in enumerate(zip(self.object_names, self.object_joints, self.objects)):
            shapes = item.collision_shapes()
            names = [name] if len(shapes) == 1 else [f"{name}:{k}" for k in range(len(shapes))]
            geometries = [self._add_geometry(n, joint, pin.SE3.Identity(), shape) for n, shape in zip(names, shapes)]
            self.object_geometry_sets.append(geometries)
            self._object_of_geometry.update(dict.fromkeys(geometries, index))
        # every object geometry, in object order (not indexed by object: a decomposed mesh contributes several)
        self.object_geometries = [g for geometries in self.object_geometry_sets for g in geometries]
        self.environment_geometries = [
            self._add_geometry(name, 0, item.placement, item.geometry())
            for name, item in zip(self.environment_names, self.environment)
        ]
        self.pairs = self._collision_pairs()
        # Placements only: the pairs are ours, not Pinocchio's (a pair there holds about 6 kB of query state in each
        # GeometryData, 0.5 GB for 400 objects' 85,000 pairs).  Every pair is queried with these coal requests.
        self.geometry_data = pin.GeometryData(self.geometry)
        self.collision_request = coal.CollisionRequest()
        self.collision_request.enable_contact = True
        self.collision_request.num_max_contacts = 4
        self.patch_request = coal.ContactPatchRequest()

    # ------------------------------------------------------------------ sizes and slices
    @property
    def nq(self) -> int:
        """Size of the scene configuration."""
        return self.model.nq

    @property
    def nv(self) -> int:
        """Size of the scene velocity."""
        return self.model.nv

    def object_index(self, name: str) -> int:
        """Position of an object in :attr:`objects`."""
        if name not in self.object_names:
            raise InputError(f"unknown object {name!r}; valid objects: {', '.join(self.object_names)}")
        return self.object_names.index(name)

    def object_q_slice(self, index: int) -> slice:
        """Slice of an object's coordinates in the scene ``q``."""
        return self._q_slices[index]

    def object_v_slice(self, index: int) -> slice:
        """Slice of an object's velocities in the scene ``v``."""
        return self._v_slices[index]

    # ------------------------------------------------------------------ states
    def initial_state(self, q_hand: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Scene ``(q, v)`` with the hand at ``q_hand`` (default neutral) at rest and objects as described."""
        q = np.zeros(self.nq)
        v = np.zeros(self.nv)
        q[: self.nq_hand] = self.hand.neutral() if q_hand is None else q_hand
        for i, item in enumerate(self.objects):
            if isinstance(item, SpringMounted):
                continue  # displacement 0, at rest
            q[self.object_q_slice(i)] = pin.SE3ToXYZQUAT(item.pose)
            v[self.object_v_slice(i)] = np.concatenate((item.velocity[:3], item.pose.rotation.T @ item.velocity[3:]))
        return q, v

    def object_pose(self, q: np.ndarray, index: int) -> pin.SE3:
        """World pose of an object's centre of mass frame."""
        item = self.objects[index]
        if isinstance(item, SpringMounted):
            displacement = float(q[self.object_q_slice(index)][0])
            return pin.SE3(item.pose.rotation, item.pose.translation + displacement * item.direction)
        return pin.XYZQUATToSE3(q[self.object_q_slice(index)])

    def object_twist(self, q: np.ndarray, v: np.ndarray, index: int) -> np.ndarray:
        """Object velocity (linear [m/s], angular [rad/s]) of its centre of mass in world-aligned coordinates."""
        item = self.objects[index]
        if isinstance(item, SpringMounted):
            return np.concatenate((v[self.object_v_slice(index)][0] * item.direction, np.zeros(3)))
        rotation = pin.XYZQUATToSE3(q[self.object_q_slice(index)]).rotation
        local = v[self.object_v_slice(index)]
        return np.concatenate((local[:3], rotation @ local[3:]))

    def energy(self, q: np.ndarray, v: np.ndarray) -> float:
        """Kinetic + gravitational potential + object-spring energy [J] (contacts excluded)."""
        if self._parts is None:
            self._parts = SceneParts(self.hand_model, self.model)
        parts = self._parts
        kinetic = 0.5 * v @ parts.mass_matrix(q) @ v
        potential = parts.potential_energy(q)  # moving bodies only
        springs = 0.0
        for i, item in enumerate(self.objects):
            if isinstance(item, SpringMounted):
                springs += 0.5 * item.stiffness * float(q[self.object_q_slice(i)][0]) ** 2
        return float(kinetic + potential + springs)

    # ------------------------------------------------------------------ construction helpers
    def _add_object(self, name: str, item: RigidObject | SpringMounted) -> tuple[int, int]:
        """Add an object's joints and body; returns (first joint, joint carrying the body)."""
        if isinstance(item, SpringMounted):
            axis_local = item.pose.rotation.T @ item.direction
            root = joint = self.model.addJoint(0, pin.JointModelPrismaticUnaligned(axis_local), item.pose, name)
            inertia = item.body.spatial_inertia()
        else:
            root = self.model.addJoint(0, pin.JointModelTranslation(), pin.SE3.Identity(), f"{name}_translation")
            joint = self.model.addJoint(root, pin.JointModelSpherical(), pin.SE3.Identity(), name)
            inertia = item.spatial_inertia()
        self.model.appendBodyToJoint(joint, inertia, pin.SE3.Identity())
        self.model.addFrame(pin.Frame(name, joint, pin.SE3.Identity(), pin.FrameType.BODY))
        return root, joint

    def _hand_geometry(self) -> pin.GeometryModel:
        geometry = self.hand.collision_model()
        placement = self.hand.base_placement
        for geometry_object in geometry.geometryObjects:
            if geometry_object.parentJoint == 0:
                geometry_object.placement = placement * geometry_object.placement
        return geometry

    def _add_geometry(self, name: str, joint: int, placement: pin.SE3, shape: object) -> int:
        return self.geometry.addGeometryObject(pin.GeometryObject(name, joint, placement, shape))

    def _collision_pairs(self) -> list[CollisionPair]:
        """The pairs (a, b, friction of a): hand links vs objects, environment vs objects, objects vs objects.

        Then, with ``environment_touches_hand``, the environment vs every moving hand link.
        """
        candidates: list[tuple[int, int, float | None]] = []
        for b in self.object_geometries:
            candidates += [(a, b, None) for a in self.hand_geometries]
            candidates += [(a, b, env.friction) for a, env in zip(self.environment_geometries, self.environment)]
        for i, (first, geometries) in enumerate(zip(self.objects, self.object_geometry_sets)):
            later = [b for others in self.object_geometry_sets[i + 1 :] for b in others]  # not its own pieces
            candidates += [(a, b, first.friction) for a in geometries for b in later]
        if self.environment_touches_hand:  # after the others: the earlier pairs keep their indices
            moving = [g for g in self.hand_geometries if self.geometry.geometryObjects[g].parentJoint != 0]
            for a, env in zip(self.environment_geometries, self.environment):
                candidates += [(a, b, env.friction) for b in moving]
        friction_of: dict[int, float | None] = {
            g: self.objects[i].friction for g, i in self._object_of_geometry.items()
        }
        friction_of.update(dict.fromkeys(self.hand_geometries))  # hand pads: the contact law's coefficient
        pairs = []
        for index, (a, b, friction_a) in enumerate(candidates):
            joint_a, joint_b = (self.geometry.geometryObjects[g].parentJoint for g in (a, b))
            body_a, body_b = self._body_name(a), self._body_name(b)
            pairs.append(CollisionPair(index, a, b, joint_a, joint_b, body_a, body_b, friction_a, friction_of[b]))
        return pairs

    def _body_name(self, geom: int) -> str:
        geometry_object = self.geometry.geometryObjects[geom]
        if geom in self.hand_geometries:
            return self.model.frames[geometry_object.parentFrame].name
        if geom in self._object_of_geometry:  # an object's piece carries its object's name
            return self.object_names[self._object_of_geometry[geom]]
        return geometry_object.name

    def __reduce__(self) -> tuple:
        """Pickles and copies rebuild the scene from its hand, objects and environment."""
        return Scene, (self.hand, self.objects, self.environment, self.environment_touches_hand, self.object_drag)

    def __repr__(self) -> str:
        return (
            f"Scene({self.hand.name!r}, objects={self.object_names}, environment={self.environment_names}, "
            f"nq={self.nq}, nv={self.nv}, pairs={len(self.pairs)})"
        )


def _placed_copy(model: pin.Model, placement: pin.SE3) -> pin.Model:
    """A copy of a fixed-base model whose base sits at ``placement`` in the world."""
    placed = copy.deepcopy(model)
    for joint in range(1, placed.njoints):
        if placed.parents[joint] == 0:
            placed.jointPlacements[joint] = placement * placed.jointPlacements[joint]
    for i, frame in enumerate(placed.frames):
        if frame.parentJoint == 0 and i > 0:
            frame.placement = placement * frame.placement
            placed.frames[i] = frame
    base = placed.inertias[0]
    placed.inertias[0] = pin.Inertia(
        base.mass, placement.act(base.lever), placement.rotation @ base.inertia @ placement.rotation.T
    )
    return placed


def _unique_names(names: Sequence[str | None], kind: str) -> list[str]:
    result = []
    for i, name in enumerate(names):
        result.append(name if name else f"{kind}{i}")
    duplicates = {n for n in result if result.count(n) > 1}
    if duplicates:
        raise InputError(f"{kind} names must be unique, got duplicates {sorted(duplicates)}")
    return result
