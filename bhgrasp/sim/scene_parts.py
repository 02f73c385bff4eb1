"""The scene's rigid-body terms part by part: the hand's joints in one Pinocchio model, each object's in one of its own.

Pinocchio's ``Data`` for a model of nv velocities holds arrays of nv^3 numbers (the second-order derivatives), built
whatever algorithm runs: 3.7 GB and 2.6 s for 64 free objects alone (nv = 384).  Nothing joins the hand and the objects
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

_IDENTITY = pin.SE3.Identity()


@dataclass(frozen=True)
class Part:
    """One part: its model and work space, its first joint in the scene's numbering, its slices of q and v."""

    model: pin.Model
    data: pin.Data
    first_joint: int
    q: slice
    v: slice


def object_parts(scene_model: pin.Model, first_joint: int) -> list[pin.Model]:
    """The subtrees of ``scene_model`` from joint ``first_joint`` on, one model each.

    A joint whose parent is the world starts one; each has the scene's gravity, and its joints, placements, names and
    inertias as they are.
    """
    models: list[pin.Model] = []
    local: dict[int, int] = {0: 0}
    for joint in range(first_joint, scene_model.njoints):
        parent = scene_model.parents[joint]
        if parent == 0:
            models.append(pin.Model())
            models[-1].gravity = scene_model.gravity
        elif parent < first_joint:
            raise ValueError(f"joint {joint} of an object hangs from joint {parent} of the hand")
        model = models[-1]
        local[joint] = model.addJoint(
            local[parent], scene_model.joints[joint], scene_model.jointPlacements[joint], scene_model.names[joint]
        )
        model.inertias[local[joint]] = scene_model.inertias[joint]
    return models


class SceneParts:
    """Mass matrix, bias, Jacobians and placements of a scene's joints, part by part (module doc)."""

    def __init__(self, hand_model: pin.Model, scene_model: pin.Model) -> None:
        """Split ``scene_model`` after the hand's joints; ``hand_model`` is the hand as placed in the scene."""
        self.nq, self.nv = scene_model.nq, scene_model.nv
        models = [hand_model, *object_parts(scene_model, hand_model.njoints)]
        self.parts: list[Part] = []
        first, q, v = 1, 0, 0
        for model in models:
            self.parts.append(Part(model, model.createData(), first, slice(q, q + model.nq), slice(v, v + model.nv)))
            first, q, v = first + model.njoints - 1, q + model.nq, v + model.nv
        self._where = [(0, 0)]  # scene joint -> (part, its joint in the part)
        for index, part in enumerate(self.parts):
            self._where += [(index, j) for j in range(1, part.model.njoints)]
        self._lower = np.tril_indices(self.nv, -1)

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
        for part in self.parts:
            mass[part.v, part.v] = pin.crba(part.model, part.data, q[part.q]).reshape(part.model.nv, part.model.nv)
        mass[self._lower] = mass.T[self._lower]
        return mass

    def nonlinear_effects(self, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        """Coriolis, centrifugal and gravity terms h(q, v), (nv,)."""
        bias = np.empty(self.nv)
        for part in self.parts:
            bias[part.v] = pin.nonLinearEffects(part.model, part.data, q[part.q], v[part.v])
        return bias

    def potential_energy(self, q: np.ndarray) -> float:
        """Gravitational potential energy [J] of the moving bodies."""
        return float(sum(pin.computePotentialEnergy(part.model, part.data, q[part.q]) for part in self.parts))


__all__ = ["Part", "SceneParts", "object_parts"]
