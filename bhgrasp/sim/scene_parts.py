"""The scene's rigid-body terms part by part: the hand's joints in one Pinocchio model, each object's in one of its own.

Pinocchio's ``Data`` for a model of nv velocities holds arrays of nv^3 numbers (the second-order derivatives), built
whatever algorithm runs: for 64 free objects alone (nv = 384) it takes 2.6 s to make, peaks at 3.7 GB while made and
holds about 1.9 GB.  Nothing joins the hand and the objects
but contacts, which the engines apply as external forces, so the scene's mass matrix is block diagonal, and each
part's bias, Jacobians and placements depend on that part's coordinates alone.  :class:`SceneParts` runs Pinocchio's
algorithms on each part (the hand's model as placed in the scene; per object its translation and spherical joints, or
its prismatic one) with the scene model's joints, placements and inertias: every term is the whole model's to the bit
(tests/test_scene_parts.py), for nv_hand^3 + 6^3 numbers per object of work space.  The compiled engine
(``src/scene_parts.cpp``) splits the scene the same way.

Joints keep the scene model's numbering (0 the world, then the hand's, then the objects'); velocities its layout.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from bhgrasp.errors import ModelError

_IDENTITY = pin.SE3.Identity()


@dataclass(frozen=True)
class Part:
    """One part: its model and work space, its slices of the scene's q and v."""

    model: pin.Model
    data: pin.Data
    q: slice
    v: slice


def object_parts(scene_model: pin.Model, first_joint: int) -> list[pin.Model]:
    """The subtrees of ``scene_model`` from joint ``first_joint`` on, one model each.

    A joint whose parent is the world starts one; each has the scene's gravity, and its joints, placements, names,
    inertias and armature as they are.  A joint hanging from the hand's or an earlier object's joints is refused.
    """
    models: list[pin.Model] = []
    starts: list[int] = []  # each part's first velocity in the scene's v
    local: dict[int, int] = {0: 0}  # scene joint -> its joint in the current part
    for joint in range(first_joint, scene_model.njoints):
        parent = scene_model.parents[joint]
        if parent == 0:
            models.append(pin.Model())
            models[-1].gravity = scene_model.gravity
            starts.append(scene_model.joints[joint].idx_v)
            local = {0: 0}
        elif parent not in local:
            raise ModelError(f"joint {joint} of an object hangs from joint {parent}, not of its own object")
        model = models[-1]
        local[joint] = model.addJoint(
            local[parent], scene_model.joints[joint], scene_model.jointPlacements[joint], scene_model.names[joint]
        )
        model.inertias[local[joint]] = scene_model.inertias[joint]
    for model, start in zip(models, starts):
        model.armature = scene_model.armature[start : start + model.nv].copy()
    return models


class SceneParts:
    """Mass matrix, bias, Jacobians and placements of a scene's joints, part by part (module doc)."""

    def __init__(self, hand_model: pin.Model, scene_model: pin.Model) -> None:
        """Split ``scene_model`` after the hand's joints; ``hand_model`` is the hand as placed in the scene."""
        self.nq, self.nv = scene_model.nq, scene_model.nv
        models = [hand_model, *object_parts(scene_model, hand_model.njoints)]
        self.parts: list[Part] = []
        q, v = 0, 0
        for model in models:
            self.parts.append(Part(model, model.createData(), slice(q, q + model.nq), slice(v, v + model.nv)))
            q, v = q + model.nq, v + model.nv
        self._where = [(0, 0)]  # scene joint -> (part, its joint in the part)
        for index, part in enumerate(self.parts):
            self._where += [(index, j) for j in range(1, part.model.njoints)]
        self._lower = {n: np.tril_indices(n, -1) for n in {part.model.nv for part in self.parts}}

    # ------------------------------------------------------------------ kinematics
    def forward_kinematics(self, q: np.ndarray) -> None:
        """Every joint's placement at ``q`` (:meth:`placement` reads them)."""
        for part in self.parts:
            pin.forwardKinematics(part.model, part.data, q[part.q])

    def compute_joint_jacobians(self, q: np.ndarray) -> None:
        """Placements and joint Jacobians at ``q`` (:meth:`point_jacobian` reads them)."""
        for part in self.parts:
            pin.computeJointJacobians(part.model, part.data, q[part.q])

    def placement(self, joint: int) -> pin.SE3:
        """A joint's placement in the world at the last kinematics (the world's own for joint 0)."""
        index, local = self._where[joint]
        return self.parts[index].data.oMi[local] if joint else _IDENTITY

    def point_jacobian(self, joint: int, placement: pin.SE3) -> tuple[slice, np.ndarray]:
        """A frame's Jacobian over its part's velocities: that slice of v, and the 6 rows (LOCAL_WORLD_ALIGNED).

        The frame sits at ``placement`` on ``joint``; the other columns of the scene's Jacobian are zero.  Reads
        :meth:`compute_joint_jacobians`' last call.
        """
        part = self.parts[self._where[joint][0]]
        jacobian = pin.getFrameJacobian(
            part.model, part.data, self._where[joint][1], placement, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
        )
        return part.v, jacobian.reshape(6, part.model.nv)  # a one-joint part's comes as a vector

    def update_geometry_placements(self, geometry: pin.GeometryModel, geometry_data: pin.GeometryData) -> None:
        """Each geometry's placement from its joint's (as ``pin.updateGeometryPlacements``), after the kinematics."""
        for index, geometry_object in enumerate(geometry.geometryObjects):
            geometry_data.oMg[index] = self.placement(geometry_object.parentJoint) * geometry_object.placement

    # ------------------------------------------------------------------ dynamics
    def mass_matrix(self, q: np.ndarray) -> np.ndarray:
        """M(q), (nv, nv), both triangles: the parts' CRBA on the diagonal blocks, zero between parts."""
        mass = np.zeros((self.nv, self.nv))
        for part, block in zip(self.parts, self.mass_blocks(q)):
            mass[part.v, part.v] = block
        return mass

    def mass_blocks(self, q: np.ndarray) -> list[np.ndarray]:
        """M(q) part by part: each part's (n, n) diagonal block, both triangles (:meth:`mass_matrix`'s values)."""
        blocks = []
        for part in self.parts:
            n = part.model.nv
            block = pin.crba(part.model, part.data, q[part.q]).reshape(n, n).copy()
            block[self._lower[n]] = block.T[self._lower[n]]  # CRBA fills the upper triangle
            blocks.append(block)
        return blocks

    def nonlinear_effects(self, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        """Coriolis, centrifugal and gravity terms h(q, v), (nv,)."""
        bias = np.empty(self.nv)
        for part in self.parts:
            bias[part.v] = pin.nonLinearEffects(part.model, part.data, q[part.q], v[part.v])
        return bias

    def potential_energy(self, q: np.ndarray) -> float:
        """Gravitational potential energy [J] of the moving bodies, -sum m g . c (mimic joints too)."""
        energy = 0.0
        for part in self.parts:
            pin.forwardKinematics(part.model, part.data, q[part.q])
            for joint in range(1, part.model.njoints):
                inertia = part.model.inertias[joint]
                centre = part.data.oMi[joint].act(inertia.lever)
                energy -= inertia.mass * float(part.model.gravity.linear @ centre)
        return energy


__all__ = ["Part", "SceneParts", "object_parts"]
