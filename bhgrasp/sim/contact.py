"""Contacts: detection with coal (contact patches) and the spring-damper + Coulomb friction force law.

:class:`ContactEngine` detects the contact points of a scene with coal (each point of a patch at its own depth),
matches them to the last step's by collision pair and position on body b (so that a sticking contact keeps its
tangential spring), gives their relative Jacobians (:meth:`ContactEngine.jacobians`) and computes their forces
with the law of :mod:`~bhgrasp.sim.contact_law` (the physics is described there), from its base
:class:`~bhgrasp.sim.contact_law.ContactForces`.  The contacts as data (ContactSet, Contact, ContactMemory) are
in :mod:`~bhgrasp.data.contacts`.
"""

from __future__ import annotations

import coal
import numpy as np
import pinocchio as pin
import scipy.sparse as sparse

from bhgrasp._validation import as_positive
from bhgrasp.data import ContactMemory, ContactSet, empty_contact_set
from bhgrasp.sim.coal_queries import FALLBACK_TOLERANCE, bounding_sphere, converged, fresh_request, plausible_depth
from bhgrasp.sim.contact_law import ContactForces, SpringDamper
from bhgrasp.sim.scene import Scene
from bhgrasp.sim.scene_parts import SceneParts

LOCAL_WORLD_ALIGNED = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
_IDENTITY3 = np.eye(3)

_NO_MEMORY = ContactMemory.empty()


class ContactEngine(ContactForces):
    """Detects contacts of a scene and computes their forces; remembers each contact's tangential displacement.

    Contacts are matched from one step to the next by collision pair and by position on body b (within
    ``match_radius``), so that a sticking contact keeps its tangential spring.
    """

    def __init__(
        self, scene: Scene, law: SpringDamper, match_radius: float = 3e-3, parts: SceneParts | None = None
    ) -> None:
        """Prepare detection for every collision pair of ``scene``.

        ``parts``: the scene's kinematics that detection runs in (and that :meth:`jacobians` reads); default new
        ones, so that engines on one scene share no work space.
        """
        self.scene = scene
        self.parts = SceneParts(scene.hand_model, scene.model) if parts is None else parts
        self.geometry_data = pin.GeometryData(scene.geometry)
        super().__init__(law)
        self.match_radius = as_positive(match_radius, "match_radius")
        self._pair_friction = np.array([pair.friction(law.friction) for pair in scene.pairs])
        self._joint_a = np.array([pair.joint_a for pair in scene.pairs], dtype=int)
        self._joint_b = np.array([pair.joint_b for pair in scene.pairs], dtype=int)
        # Every pair is tested by coal's free functions with requests of our own: Pinocchio's per-pair collision
        # functors keep GJK state from call to call (at a degenerate contact, two faces flush, the witness and with
        # it the patch depended on the configurations queried before: a box resting flat on its pedestal gave a
        # 4-point patch or a 1-point patch), and their default GJK tolerance (1e-6) decided near the threshold
        # whether a pair touched at all.  The free functions start afresh every time, as the compiled engine does;
        # every pair is asked with the same requests, one pair at a time into the same results.
        self._shapes = [item.geometry for item in scene.geometry.geometryObjects]
        self._request = fresh_request(scene.collision_request)
        self._fallback = fresh_request(scene.collision_request, FALLBACK_TOLERANCE)
        self._patch_request = scene.patch_request
        self._result, self._patches = coal.CollisionResult(), coal.ContactPatchResult()
        self._bounds = [bounding_sphere(shape) for shape in self._shapes]
        self._geom_a = np.array([pair.geom_a for pair in scene.pairs], dtype=int)
        self._geom_b = np.array([pair.geom_b for pair in scene.pairs], dtype=int)
        radius = np.array([r for _, r in self._bounds])
        radius_a, radius_b = radius[self._geom_a], radius[self._geom_b]
        self._max_depth = [plausible_depth(a, b) for a, b in zip(radius_a, radius_b)]
        self._reach = radius_a + radius_b  # inf: a pair of an unbounded shape
        self._bounded = np.isfinite(self._reach)
        self._near = self._reach + self._request.security_margin + 1e-9
        self._probe = coal.Sphere(1e-12)  # a point, for signed-distance queries
        self._probe_placement = coal.Transform3s()
        self._distance_request, self._distance_result = coal.DistanceRequest(), coal.DistanceResult()

    # ------------------------------------------------------------------ detection
    def detect(self, q: np.ndarray, memory: ContactMemory | None = None) -> ContactSet:
        """Contact points at configuration ``q`` (runs forward kinematics and coal), matched to ``memory``'s.

        ``memory``: the contacts of the last step (default none: every contact starts sticking, unstretched).

        Each coal contact patch (e.g. the 4 corners of a box face on a plane) shares the law's stiffness and
        damping among its points, so a body's contact stiffness does not depend on how many points coal reports.
        """
        scene = self.scene
        self.parts.forward_kinematics(q)
        self.parts.update_geometry_placements(scene.geometry, self.geometry_data)
        placements = self.geometry_data.oMg
        pairs, points, normals, depths, weights = [], [], [], [], []
        shapes, request, result, patches = self._shapes, self._request, self._result, self._patches
        for k in self.broad_phase():
            geom_a, geom_b = int(self._geom_a[k]), int(self._geom_b[k])
            shape_a, shape_b = shapes[geom_a], shapes[geom_b]
            placement_a, placement_b = placements[geom_a], placements[geom_b]
            transform_a = coal.Transform3s(placement_a.rotation, placement_a.translation)
            transform_b = coal.Transform3s(placement_b.rotation, placement_b.translation)
            result.clear()
            if not coal.collide(shape_a, transform_a, shape_b, transform_b, request, result):
                continue
            if not converged(result, self._max_depth[k]):
                result.clear()
                if not coal.collide(shape_a, transform_a, shape_b, transform_b, self._fallback, result):
                    continue
            coal.computeContactPatch(shape_a, transform_a, shape_b, transform_b, result, self._patch_request, patches)
            for p in range(patches.numContactPatches()):
                patch = patches.getContactPatch(p)
                size = patch.size()
                normal = np.asarray(patch.getNormal())
                mid = np.array([patch.getPoint(i) for i in range(size)])
                if size == 1:
                    depth = [-patch.penetration_depth]
                else:  # coal gives every patch point the patch's deepest depth: measure each point's own
                    depth = self._point_depths(k, mid, normal)
                pairs += [k] * size
                points.append(mid)
                normals += [normal] * size
                depths += list(depth)
                weights += [1.0 / size] * size
        depth = np.array(depths)
        keep = depth > 0.0
        if not np.any(keep):
            return empty_contact_set()
        point, normal = np.concatenate(points)[keep], np.array(normals)[keep]
        pair = np.array(pairs, dtype=int)[keep]
        local = self._in_frame_b(pair, point)
        displacement, was_sliding = self._recall(pair, local, normal, memory or _NO_MEMORY)
        weight = np.array(weights)[keep]
        return ContactSet(
            pair,
            point,
            normal,
            depth[keep],
            self._pair_friction[pair],
            displacement,
            weight,
            local,
            was_sliding=was_sliding,
        )

    def _point_depths(self, k: int, points: np.ndarray, normal: np.ndarray) -> np.ndarray:
        """Penetration at each point of a multi-point patch, from signed distances to both shapes.

        The overlap of two locally planar surfaces at ``x`` is ``-(sd_a(x) + sd_b(x))`` wherever ``x`` lies along
        the normal.  At a polygon corner the nearest feature of a box is a side face, so the overlap is measured
        at two points moved inward (toward the patch centroid) and extrapolated linearly back to the corner.
        """
        pair = self.scene.pairs[k]
        inward = points.sum(axis=0) / len(points) - points
        inward -= np.outer(inward @ normal, normal)
        length = np.sqrt((inward * inward).sum(axis=1))
        offsets = inward * (np.minimum(1e-3, 0.125 * length) / np.maximum(length, 1e-300))[:, None]
        probes = np.concatenate((points + offsets, points + 2 * offsets))
        overlap = -(self._signed_distance(pair.geom_a, probes) + self._signed_distance(pair.geom_b, probes))
        near, far = overlap[: len(points)], overlap[len(points) :]
        return 2 * near - far

    def _signed_distance(self, geom: int, points: np.ndarray) -> np.ndarray:
        """Signed distance [m] of world points to a geometry (negative inside).

        Closed form for boxes, half-spaces, spheres, cylinders and capsules; coal's GJK/EPA for other shapes (coal's
        EPA puts a point inside a cylinder at its side wall's distance even where a flat end is nearer: a can standing
        on its pedestal read a 21.7 mm overlap at 9 um and was thrown off).
        """
        placement = self.geometry_data.oMg[geom]
        shape = self.scene.geometry.geometryObjects[geom].geometry
        local = (points - placement.translation) @ placement.rotation
        if isinstance(shape, coal.Box):
            excess = np.abs(local) - shape.halfSide
            outside = np.sqrt((np.maximum(excess, 0.0) ** 2).sum(axis=1))
            return outside + np.minimum(excess.max(axis=1), 0.0)
        if isinstance(shape, coal.Halfspace):
            return local @ shape.n - shape.d
        if isinstance(shape, coal.Sphere):
            return np.sqrt((local * local).sum(axis=1)) - shape.radius
        if isinstance(shape, coal.Cylinder):  # axis along local z
            radial = np.sqrt(local[:, 0] * local[:, 0] + local[:, 1] * local[:, 1]) - shape.radius
            axial = np.abs(local[:, 2]) - shape.halfLength
            outside_radial, outside_axial = np.maximum(radial, 0.0), np.maximum(axial, 0.0)
            outside = np.sqrt(outside_radial * outside_radial + outside_axial * outside_axial)
            return outside + np.minimum(np.maximum(radial, axial), 0.0)
        if isinstance(shape, coal.Capsule):  # segment along local z
            along = local[:, 2] - np.clip(local[:, 2], -shape.halfLength, shape.halfLength)
            return np.sqrt(local[:, 0] * local[:, 0] + local[:, 1] * local[:, 1] + along * along) - shape.radius
        transform = coal.Transform3s(placement.rotation, placement.translation)
        return np.array([-self._overlap([(shape, transform)], point) for point in points])

    def _overlap(self, shapes: list, point: np.ndarray) -> float:
        probe, placement, request, result = (
            self._probe,
            self._probe_placement,
            self._distance_request,
            self._distance_result,
        )
        placement.setTranslation(point)
        total = 0.0
        for shape, shape_placement in shapes:
            result.clear()
            total += coal.distance(probe, placement, shape, shape_placement, request, result)
        return -total

    def _in_frame_b(self, pair: np.ndarray, point: np.ndarray) -> np.ndarray:
        """Contact points expressed in the joint frame of their body b."""
        placement = self.parts.placement
        return np.array([placement(int(j)).actInv(p) for j, p in zip(self._joint_b[pair], point)])

    def _recall(
        self, pair: np.ndarray, local: np.ndarray, normal: np.ndarray, memory: ContactMemory
    ) -> tuple[np.ndarray, np.ndarray]:
        """Tangential displacement and sliding flag of each contact carried over from the last step.

        A contact matches the nearest remembered point of the same pair within ``match_radius`` (on body b); a point
        coal did not report last step (patches change size as a body rocks) inherits the mean displacement of its
        pair, so that a sticking patch keeps its anchor, and slides if any point of its pair slid.  A new contact
        starts with no displacement, sticking.
        """
        old_pair, old_local, old_u, old_sliding = memory.pair, memory.local_b, memory.displacement, memory.sliding
        if len(old_pair) == 0:
            return np.zeros_like(local), np.zeros(len(pair), dtype=bool)
        same_pair = pair[:, None] == old_pair[None, :]
        gap = local[:, None, :] - old_local[None, :, :]
        distance = np.where(same_pair, (gap * gap).sum(axis=2), np.inf)
        nearest = distance.argmin(axis=1)
        matched = distance[np.arange(len(pair)), nearest] <= self.match_radius**2
        u = old_u[nearest]
        sliding = old_sliding[nearest] & matched
        if not matched.all():
            u[~matched] = 0.0
            for i in np.flatnonzero(~matched & same_pair.any(axis=1)):
                u[i] = old_u[same_pair[i]].mean(axis=0)
                sliding[i] = old_sliding[same_pair[i]].any()
        projected = u - (u * normal).sum(axis=1)[:, None] * normal  # onto the new tangent plane ...
        length, new_length = np.sqrt((u * u).sum(axis=1)), np.sqrt((projected * projected).sum(axis=1))
        return projected * (length / np.maximum(new_length, 1e-300))[:, None], sliding  # ... keeping its length

    @staticmethod
    def remember(contacts: ContactSet, displacement: np.ndarray, sliding: np.ndarray) -> ContactMemory:
        """The memory a step leaves: its contacts' end-of-step tangential displacements and slide flags."""
        return ContactMemory(contacts.pair, contacts.local_b, displacement, sliding)

    # ------------------------------------------------------------------ kinematics of the contact points
    def jacobians(self, contacts: ContactSet) -> np.ndarray:
        """Relative point Jacobians J_b(p) - J_a(p), shape (m, 3, nv), world-aligned.

        Needs :meth:`SceneParts.compute_joint_jacobians` at the current ``q`` in :attr:`parts` (the engine calls it once
        per step).
        """
        jacobians = np.zeros((len(contacts), 3, self.scene.nv))
        for i, columns, rows, sign in self._point_jacobians(contacts):
            if sign > 0:
                jacobians[i, :, columns] = rows
            else:
                jacobians[i, :, columns] -= rows
        return jacobians

    def _point_jacobians(self, contacts: ContactSet):
        """Each contact's point Jacobians on its bodies' parts: (contact, the part's slice of v, its 3 rows, sign).

        Body b's (sign +1: a point fixed on it, Pinocchio's frame Jacobian of that placement), then body a's (sign
        -1), each where its joint is not 0 (the environment or the fixed palm).
        """
        parts, identity = self.parts, _IDENTITY3
        for i, k in enumerate(contacts.pair):
            joint_b, joint_a = int(self._joint_b[k]), int(self._joint_a[k])
            if joint_b:
                columns, jacobian = parts.point_jacobian(joint_b, pin.SE3(identity, contacts.local_b[i]))
                yield i, columns, jacobian[:3], 1.0
            if joint_a:
                placement = pin.SE3(identity, parts.placement(joint_a).actInv(contacts.point[i]))
                columns, jacobian = parts.point_jacobian(joint_a, placement)
                yield i, columns, jacobian[:3], -1.0

    def broad_phase(self) -> np.ndarray:
        """The pairs whose bounding spheres come within reach, and those of an unbounded shape, in pair order.

        At the last placements (``detect`` runs them).  Pairs apart get no contact from the narrow phase either: the
        compiled engine skips them the same way (``src/detect.cpp``).
        """
        if not len(self._reach):
            return np.zeros(0, dtype=int)
        placements = self.geometry_data.oMg
        centres = np.array([placement.act(centre) for placement, (centre, _) in zip(placements, self._bounds)])
        apart = np.linalg.norm(centres[self._geom_a] - centres[self._geom_b], axis=1) > self._near
        return np.flatnonzero(~(self._bounded & apart))

    def part_jacobians(self, contacts: ContactSet) -> sparse.csr_array:
        """The relative point Jacobians of :meth:`jacobians` stacked, (3m, nv), sparse.

        Each contact's rows hold only the columns of the one or two parts it touches (:mod:`~bhgrasp.sim.part_system`).
        """
        nv = self.scene.nv
        rows, columns, values = [], [], []
        for i, part_columns, block, sign in self._point_jacobians(contacts):
            index = np.arange(part_columns.start, part_columns.stop)
            rows.append(np.repeat(3 * i + np.arange(3), len(index)))
            columns.append(np.tile(index, 3))
            values.append((sign * block).ravel())
        if not rows:
            return sparse.csr_array((3 * len(contacts), nv))
        triplets = (np.concatenate(values), (np.concatenate(rows), np.concatenate(columns)))
        return sparse.csr_array(sparse.coo_array(triplets, shape=(3 * len(contacts), nv)))  # duplicates summed


__all__ = ["ContactEngine"]
