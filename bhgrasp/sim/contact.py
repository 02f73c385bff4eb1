"""Contacts: detection with coal (contact patches) and the spring-damper + Coulomb friction force law.

Thesis 4.2 models contact as a spring (4.5)-(4.7) pushing the bodies apart along the contact normal.  Here every
contact point ``i`` between body ``a`` and body ``b`` (normal ``n`` from a to b, depth ``d >= 0``) gets a force
on ``b`` (and its opposite on ``a``, at the same point):

- normal: ``f_n = max(0, k d + c d_dot)`` (linear), or ``max(0, d^e (k + c d_dot))`` (Hunt-Crossley); never pulls;
- tangential, stick-slip (default): an elastic tangential displacement ``u`` (a spring anchored where the contact
  began to stick) gives ``f_t = -k_t u - c_t v_t``; when ``|f_t| > mu f_n`` the contact slides, ``f_t`` is
  projected onto the cone and the anchor follows so that ``k_t |u| = mu f_n``.  A contact that sticks has zero
  creep at equilibrium (no velocity is needed to hold a tangential load);
- tangential, regularised (option, for comparison): ``f_t = -mu f_n tanh(|v_t| / v_s) v_t / |v_t|``, which must
  creep to hold a load.

For the simulator's linearly-implicit step the force is written as ``f(v+) = f0 - D J v+`` (the spring evaluated
at the end of the step): :meth:`ContactEngine.linear_parts` and :meth:`ContactEngine.linearise` give ``f0`` and ``D``,
:meth:`ContactEngine.jacobians` the relative Jacobians ``J``; :meth:`ContactEngine.classify` is the active-set rule.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Literal

import coal
import numpy as np
import pinocchio as pin

from bhgrasp._validation import as_positive, as_real
from bhgrasp.errors import InputError
from bhgrasp.sim.scene import Scene

LOCAL_WORLD_ALIGNED = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
_IDENTITY3 = np.eye(3)


@dataclass(frozen=True)
class SpringDamper:
    """The contact force law and its parameters.

    Attributes:
        stiffness: Normal stiffness k [N/m] (Hunt-Crossley: [N/m^e]).
        damping: Normal damping c [N s/m] (Hunt-Crossley: [N s/m^(e+1)]).
        friction: Coulomb coefficient of the hand's finger pads (a pair uses the smaller of its two surfaces').
        tangential_stiffness: k_t [N/m] of the stick spring; default ``stiffness``.
        tangential_damping: c_t [N s/m]; default ``damping``.
        normal_law: ``"linear"`` or ``"hunt-crossley"``.
        exponent: Hunt-Crossley exponent e (1.5 for Hertzian spheres).
        friction_law: ``"stick-slip"`` (true static friction) or ``"tanh"`` (regularised, creeps).
        slip_velocity: v_s of the tanh law [m/s].
    """

    stiffness: float = 1e4
    damping: float = 20.0
    friction: float = 0.8
    tangential_stiffness: float | None = None
    tangential_damping: float | None = None
    normal_law: Literal["linear", "hunt-crossley"] = "linear"
    exponent: float = 1.5
    friction_law: Literal["stick-slip", "tanh"] = "stick-slip"
    slip_velocity: float = 1e-3

    def __post_init__(self) -> None:
        as_positive(self.stiffness, "stiffness")
        as_real(self.damping, "damping")
        as_real(self.friction, "friction")
        as_positive(self.exponent, "exponent")
        as_positive(self.slip_velocity, "slip_velocity")
        if self.tangential_stiffness is not None:
            as_positive(self.tangential_stiffness, "tangential_stiffness")
        if self.tangential_damping is not None:
            as_real(self.tangential_damping, "tangential_damping")
        if self.normal_law not in ("linear", "hunt-crossley"):
            raise InputError(f"`normal_law` must be 'linear' or 'hunt-crossley', got {self.normal_law!r}")
        if self.friction_law not in ("stick-slip", "tanh"):
            raise InputError(f"`friction_law` must be 'stick-slip' or 'tanh', got {self.friction_law!r}")

    @property
    def k_t(self) -> float:
        """Tangential stiffness [N/m]."""
        return self.stiffness if self.tangential_stiffness is None else self.tangential_stiffness

    @property
    def c_t(self) -> float:
        """Tangential damping [N s/m]."""
        return self.damping if self.tangential_damping is None else self.tangential_damping


@dataclass(frozen=True)
class Contact:
    """One contact point, as a user inspects it (world frame, SI units).

    Attributes:
        body_a: Name of the body the normal points away from (hand link, environment, first object).
        body_b: Name of the body the force ``force`` acts on (an object); ``-force`` acts on ``body_a``.
        point: Contact point [m] (midway between the two surfaces).
        normal: Unit normal from a to b.
        depth: Penetration [m] (>= 0).
        normal_force: f_n [N] (>= 0).
        tangential_force: f_t [N], perpendicular to ``normal``.
        sticking: Whether the tangential force is inside the friction cone (no sliding).
    """

    body_a: str
    body_b: str
    point: np.ndarray
    normal: np.ndarray
    depth: float
    normal_force: float
    tangential_force: np.ndarray
    sticking: bool

    @property
    def force(self) -> np.ndarray:
        """Total force on ``body_b`` [N]."""
        return self.normal_force * self.normal + self.tangential_force

    @property
    def point_a(self) -> np.ndarray:
        """Deepest point of body a's surface inside body b [m]."""
        return self.point + 0.5 * self.depth * self.normal

    @property
    def point_b(self) -> np.ndarray:
        """Deepest point of body b's surface inside body a [m]."""
        return self.point - 0.5 * self.depth * self.normal


@dataclass(frozen=True)
class ContactMemory:
    """What a run carries from one step to the next about its contacts (part of :class:`~bhgrasp.sim.state.State`).

    Attributes:
        pair: (m,) collision-pair index of each remembered contact.
        local_b: (m, 3) the contact point in its body b's joint frame [m] (contacts are matched by position on b).
        displacement: (m, 3) end-of-step tangential spring displacement u [m].
        sliding: (m,) whether the contact ended the step sliding (the next step starts it sliding).
        native: The compiled engine's copy of the same memory (``None`` when built in Python), so that a run of
            the compiled engine hands it on without converting the arrays back and forth.
    """

    pair: np.ndarray
    local_b: np.ndarray
    displacement: np.ndarray
    sliding: np.ndarray
    native: Any = field(default=None, compare=False, repr=False)

    @classmethod
    def empty(cls) -> ContactMemory:
        """No contact remembered (the start of a run, or contacts cleared)."""
        return cls(np.zeros(0, int), np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0, bool))

    def __len__(self) -> int:
        return len(self.pair)

    def __reduce__(self) -> tuple:
        """Copies and pickles keep the arrays; the compiled engine rebuilds its native copy from them."""
        return type(self), (self.pair, self.local_b, self.displacement, self.sliding)


@dataclass
class ContactSet:
    """The contact points of one instant as arrays (m contacts); ``contacts`` gives :class:`Contact` records."""

    pair: np.ndarray  # (m,) collision-pair index
    point: np.ndarray  # (m, 3) [m]
    normal: np.ndarray  # (m, 3) unit, a -> b
    depth: np.ndarray  # (m,) [m]
    friction: np.ndarray  # (m,) mu
    displacement: np.ndarray  # (m, 3) tangential elastic displacement u at the start of the step [m]
    weight: np.ndarray  # (m,) share of its patch's stiffness and damping: 1 / (points in the patch)
    local_b: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))  # (m, 3) points in b's joint frame [m]
    force: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))  # (m, 3) on b [N]
    sticking: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=bool))
    was_sliding: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=bool))  # (m,) slid the last step

    def __post_init__(self) -> None:
        m = len(self.pair)
        if len(self.force) != m:  # detected, forces not computed yet
            self.force = np.zeros((m, 3))
            self.sticking = np.zeros(m, dtype=bool)
        if len(self.was_sliding) != m:
            self.was_sliding = np.zeros(m, dtype=bool)

    def __len__(self) -> int:
        return len(self.pair)

    def normal_forces(self) -> np.ndarray:
        """f_n per contact [N]."""
        return np.einsum("ij,ij->i", self.force, self.normal) if len(self) else np.zeros(0)

    def records(self, scene: Scene) -> list[Contact]:
        """The contacts as :class:`Contact` records with body names."""
        records = []
        for i, k in enumerate(self.pair):
            pair = scene.pairs[k]
            f_n = float(self.force[i] @ self.normal[i])
            records.append(
                Contact(
                    pair.body_a,
                    pair.body_b,
                    self.point[i].copy(),
                    self.normal[i].copy(),
                    float(self.depth[i]),
                    f_n,
                    self.force[i] - f_n * self.normal[i],
                    bool(self.sticking[i]),
                )
            )
        return records


_NARROW_TOLERANCE = 1e-10  # GJK/EPA: coal's default 1e-6 tilts a box-on-box normal by up to 0.027 (1.5 deg)
# At 1e-10 coal 3.0.3's EPA may stop unconverged (a box edge in a cylinder: depth -1.8e308, point 0); such a query is
# asked again at coal's default tolerance, which converged there (depth 0.53 mm, as coal.distance gives).
_FALLBACK_TOLERANCE = 1e-6
_MAX_DEPTH = 1.0  # [m] a reported penetration beyond this is a failed query, not a contact


def _converged(result: coal.CollisionResult) -> bool:
    """Whether every contact of a collision query has a finite, plausible depth (EPA converged)."""
    for i in range(result.numContacts()):
        depth = result.getContact(i).penetration_depth
        if not abs(depth) <= _MAX_DEPTH:
            return False
    return True


def _fresh_request(template: coal.CollisionRequest, tolerance: float = _NARROW_TOLERANCE) -> coal.CollisionRequest:
    """A collision request of our own with ``template``'s settings (Pinocchio may store GJK guesses in its own).

    GJK and EPA run to 1e-10: with coal's default 1e-6, the normal of a box resting on a box came out up to 0.027
    off the true one (two flush faces, ~1e-9 rad apart), and which way depended on the query before.
    """
    request = coal.CollisionRequest()
    request.enable_contact = template.enable_contact
    request.num_max_contacts = template.num_max_contacts
    request.security_margin = template.security_margin
    request.break_distance = template.break_distance
    request.gjk_tolerance = request.epa_tolerance = tolerance
    return request


def empty_contact_set() -> ContactSet:
    """A set with no contacts."""
    return ContactSet(
        np.zeros(0, int), np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0), np.zeros(0), np.zeros((0, 3)), np.zeros(0)
    )


class ContactEngine:
    """Detects contacts of a scene and computes their forces; remembers each contact's tangential displacement.

    Contacts are matched from one step to the next by collision pair and by position on body b (within
    ``match_radius``), so that a sticking contact keeps its tangential spring.
    """

    def __init__(self, scene: Scene, law: SpringDamper, match_radius: float = 3e-3) -> None:
        """Prepare detection for every collision pair of ``scene``."""
        self.scene = scene
        self.law = law
        self.match_radius = as_positive(match_radius, "match_radius")
        self._pair_friction = np.array([pair.friction(law.friction) for pair in scene.pairs])
        self._joint_a = np.array([pair.joint_a for pair in scene.pairs], dtype=int)
        self._joint_b = np.array([pair.joint_b for pair in scene.pairs], dtype=int)
        self.memory = ContactMemory.empty()  # the contacts of the last step (restored from each step's State)
        # Every pair is tested by coal's free functions with requests of our own: Pinocchio's per-pair collision
        # functors keep GJK state from call to call (at a degenerate contact, two faces flush, the witness and with
        # it the patch depended on the configurations queried before: a box resting flat on its pedestal gave a
        # 4-point patch or a 1-point patch), and their default GJK tolerance (1e-6) decided near the threshold
        # whether a pair touched at all.  The free functions start afresh every time, as the compiled engine does.
        geometry, data = scene.geometry, scene.geometry_data
        self._narrow = [
            (
                geometry.geometryObjects[pair.geom_a].geometry, geometry.geometryObjects[pair.geom_b].geometry,
                pair.geom_a, pair.geom_b, _fresh_request(data.collisionRequests[pair.index]),
                data.contactPatchRequests[pair.index], coal.CollisionResult(), coal.ContactPatchResult(),
            )
            for pair in scene.pairs
        ]  # fmt: skip
        self._fallback = [_fresh_request(request, _FALLBACK_TOLERANCE) for _, _, _, _, request, *_ in self._narrow]
        self._probe = coal.Sphere(1e-12)  # a point, for signed-distance queries
        self._probe_placement = coal.Transform3s()
        self._distance_request, self._distance_result = coal.DistanceRequest(), coal.DistanceResult()

    def reset(self) -> None:
        """Forget every contact (a new run)."""
        self.memory = ContactMemory.empty()

    # ------------------------------------------------------------------ detection
    def detect(self, q: np.ndarray) -> ContactSet:
        """Contact points at configuration ``q`` (runs forward kinematics and coal), matched to the last step's.

        Each coal contact patch (e.g. the 4 corners of a box face on a plane) shares the law's stiffness and
        damping among its points, so a body's contact stiffness does not depend on how many points coal reports.
        """
        scene = self.scene
        pin.updateGeometryPlacements(scene.model, scene.data, scene.geometry, scene.geometry_data, q)
        placements = scene.geometry_data.oMg
        pairs, points, normals, depths, weights = [], [], [], [], []
        for k in range(len(self._narrow)):
            shape_a, shape_b, geom_a, geom_b, request, patch_request, result, patches = self._narrow[k]
            placement_a, placement_b = placements[geom_a], placements[geom_b]
            transform_a = coal.Transform3s(placement_a.rotation, placement_a.translation)
            transform_b = coal.Transform3s(placement_b.rotation, placement_b.translation)
            result.clear()
            if not coal.collide(shape_a, transform_a, shape_b, transform_b, request, result):
                continue
            if not _converged(result):
                result.clear()
                if not coal.collide(shape_a, transform_a, shape_b, transform_b, self._fallback[k], result):
                    continue
            coal.computeContactPatch(shape_a, transform_a, shape_b, transform_b, result, patch_request, patches)
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
        displacement, was_sliding = self._recall(pair, local, normal)
        weight = np.array(weights)[keep]
        return ContactSet(
            pair, point, normal, depth[keep], self._pair_friction[pair], displacement, weight, local,
            was_sliding=was_sliding,
        )  # fmt: skip

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

        Closed form for boxes, half-spaces and spheres; coal's GJK/EPA for other shapes.
        """
        placement = self.scene.geometry_data.oMg[geom]
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
        placements = self.scene.data.oMi
        return np.array([placements[int(j)].actInv(p) for j, p in zip(self._joint_b[pair], point)])

    def _recall(self, pair: np.ndarray, local: np.ndarray, normal: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Tangential displacement and sliding flag of each contact carried over from the last step.

        A contact matches the nearest remembered point of the same pair within ``match_radius`` (on body b); a point
        coal did not report last step (patches change size as a body rocks) inherits the mean displacement of its
        pair, so that a sticking patch keeps its anchor, and slides if any point of its pair slid.  A new contact
        starts with no displacement, sticking.
        """
        memory = self.memory
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

    def remember(self, contacts: ContactSet, displacement: np.ndarray, sliding: np.ndarray) -> None:
        """Store the end-of-step tangential displacements and slide flags (once per step, forces final)."""
        self.memory = ContactMemory(contacts.pair.copy(), contacts.local_b.copy(), displacement.copy(), sliding.copy())

    # ------------------------------------------------------------------ kinematics of the contact points
    def jacobians(self, contacts: ContactSet) -> np.ndarray:
        """Relative point Jacobians J_b(p) - J_a(p), shape (m, 3, nv), world-aligned.

        Needs ``pin.computeJointJacobians`` at the current ``q`` (the simulator calls it once per step).
        """
        model, data = self.scene.model, self.scene.data
        jacobians = np.zeros((len(contacts), 3, model.nv))
        identity = _IDENTITY3
        for i, k in enumerate(contacts.pair):
            joint_b, joint_a = int(self._joint_b[k]), int(self._joint_a[k])
            if joint_b:  # a point fixed on body b: Pinocchio's frame Jacobian of that placement
                placement = pin.SE3(identity, contacts.local_b[i])
                jacobians[i] = pin.getFrameJacobian(model, data, joint_b, placement, LOCAL_WORLD_ALIGNED)[:3]
            if joint_a:  # 0 = the environment or the fixed palm
                placement = pin.SE3(identity, data.oMi[joint_a].actInv(contacts.point[i]))
                jacobians[i] -= pin.getFrameJacobian(model, data, joint_a, placement, LOCAL_WORLD_ALIGNED)[:3]
        return jacobians

    # ------------------------------------------------------------------ force law
    def forces(
        self, contacts: ContactSet, velocity: np.ndarray, dt: float = 0.0
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Explicit forces on body b, given relative point velocities (m, 3) [m/s].

        With ``dt`` > 0 the stick spring is evaluated at the end of the step (displacement + dt v_t).

        Returns:
            Forces (m, 3) [N], sticking flags (m,), end-of-step tangential displacements (m, 3) [m].
        """
        law = self.law
        normal = contacts.normal
        v_n = np.einsum("ij,ij->i", velocity, normal)
        v_t = velocity - v_n[:, None] * normal
        depth_rate = -v_n
        weight = contacts.weight
        if law.normal_law == "linear":
            f_n = weight * (law.stiffness * contacts.depth + law.damping * depth_rate)
        else:
            f_n = weight * contacts.depth**law.exponent * (law.stiffness + law.damping * depth_rate)
        f_n = np.maximum(f_n, 0.0)
        cone = contacts.friction * f_n
        if law.friction_law == "tanh":
            speed = np.linalg.norm(v_t, axis=1)
            direction = np.divide(v_t, speed[:, None], out=np.zeros_like(v_t), where=speed[:, None] > 0)
            f_t = -(cone * np.tanh(speed / law.slip_velocity))[:, None] * direction
            sticking = speed < law.slip_velocity
            displacement = np.zeros_like(v_t)
        else:
            displacement = contacts.displacement + dt * v_t
            f_t = -weight[:, None] * (law.k_t * displacement + law.c_t * v_t)
            f_t, sticking, displacement = self.project_on_cone(f_t, cone, displacement, weight)
        forces = f_n[:, None] * normal + f_t
        return forces, sticking, displacement

    # ------------------------------------------------------------------ linearly-implicit form (the simulator)
    def linear_parts(self, contacts: ContactSet, dt: float) -> tuple:
        """Per step, for the implicit solve: ``f0`` and gains ``D`` of the normal law alone and with the stick spring.

        The spring is evaluated at the end of a step of ``dt`` [s]: ``f(v+) = f0 - D J v+``.
        """
        law = self.law
        normal, depth, weight = contacts.normal, contacts.depth, contacts.weight
        outer = normal[:, :, None] * normal[:, None, :]
        if law.normal_law == "linear":
            force = weight * law.stiffness * depth
            gain = weight * (law.stiffness * dt + law.damping)
        else:
            power = depth**law.exponent
            force = weight * law.stiffness * power
            gain = weight * (law.exponent * law.stiffness * depth ** (law.exponent - 1.0) * dt + law.damping * power)
        f0 = force[:, None] * normal
        gains = gain[:, None, None] * outer
        if law.friction_law == "stick-slip":
            f0_stick = f0 - (weight * law.k_t)[:, None] * contacts.displacement
            gains_stick = gains + (weight * (law.k_t * dt + law.c_t))[:, None, None] * (_IDENTITY3 - outer)
        else:
            f0_stick, gains_stick = f0, gains
        return f0, gains, f0_stick, gains_stick

    def linearise(self, parts: tuple, status: np.ndarray, slide_force: np.ndarray):
        """Contact force ``f(v+) = f0 - D J v+`` of each contact in its status (0 off, 1 stick, 2 slide)."""
        f0, gains, f0_stick, gains_stick = parts
        stick = (status == 1)[:, None]
        f_0 = np.where(stick, f0_stick, f0 + slide_force)
        d = np.where(stick[:, :, None], gains_stick, gains)
        off = status == 0
        if off.any():
            f_0[off], d[off] = 0.0, 0.0
        return f_0, d

    def start_status(
        self, contacts: ContactSet, parts: tuple, start_velocity: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """The active set a step starts from: the previous step's stick/slip state.

        A contact that ended the last step sliding and still slips (faster than ``1e-6`` m/s) starts sliding, its
        kinetic friction on the cone of the normal force predicted at the start-of-step velocity, against the slip;
        every other contact starts sticking.  (Starting a fast slider sticking gives it a huge stick force on the
        first pass, which pitches the body and unloads its trailing contacts for the step.  Predicting slip of new
        contacts from the start velocity instead would over-predict it for light bodies whose implicit step stops
        the slip with a small force.)

        Returns:
            Status per contact (1 stick, 2 slide) and the sliding contacts' tangential forces (m, 3) [N].
        """
        m = len(contacts)
        status, slide = np.ones(m, dtype=int), np.zeros((m, 3))
        if self.law.friction_law != "stick-slip" or not contacts.was_sliding.any():
            return status, slide
        f0, gains, _, _ = parts
        normal = contacts.normal
        predicted = f0 - (gains @ start_velocity[:, :, None])[:, :, 0]  # the normal law alone
        cone = contacts.friction * np.maximum((predicted * normal).sum(axis=1), 0.0)
        v_t = start_velocity - (start_velocity * normal).sum(axis=1)[:, None] * normal
        speed = np.sqrt((v_t * v_t).sum(axis=1))
        sliding = contacts.was_sliding & (speed > 1e-6) & (cone > 0.0)
        status[sliding] = 2
        slide[sliding] = -v_t[sliding] * (cone[sliding] / speed[sliding])[:, None]
        return status, slide

    def classify(
        self,
        contacts: ContactSet,
        forces: np.ndarray,
        status: np.ndarray,
        start_velocity: np.ndarray,
        relative: np.ndarray | None = None,
        may_stick: np.ndarray | None = None,
    ) -> tuple[np.ndarray, np.ndarray]:
        """Drop pulling contacts; turn sticking contacts outside the cone into sliding ones (force on the cone).

        A sliding contact in ``may_stick`` whose end-of-step slip ``relative`` runs along its kinetic friction (the
        friction would have reversed the slip: it overshoots) sticks instead.  With the tanh law every contact
        "slides" with the regularised force of its start-of-step slip velocity.
        """
        normal = contacts.normal
        normal_force = (forces * normal).sum(axis=1)
        tangential = forces - normal_force[:, None] * normal
        new_status = np.where(normal_force > 0.0, status, 0)
        cone = contacts.friction * np.maximum(normal_force, 0.0)
        slide = np.zeros_like(forces)
        if self.law.friction_law == "tanh":
            v_t = start_velocity - np.einsum("ij,ij->i", start_velocity, normal)[:, None] * normal
            speed = np.linalg.norm(v_t, axis=1)
            scale = np.divide(np.tanh(speed / self.law.slip_velocity), speed, out=np.zeros_like(speed), where=speed > 0)
            slide = -(cone * scale)[:, None] * v_t
            new_status[new_status == 1] = 2
            return new_status, slide
        magnitude = np.sqrt((tangential * tangential).sum(axis=1))
        sliding = (new_status > 0) & ((magnitude > cone * (1 + 1e-9)) | (status == 2))
        if relative is not None and may_stick is not None:
            v_t = relative - (relative * normal).sum(axis=1)[:, None] * normal
            overshoot = may_stick & (status == 2) & (new_status > 0) & ((tangential * v_t).sum(axis=1) > 0.0)
            new_status[overshoot] = 1
            sliding &= ~overshoot
        if sliding.any():
            new_status[sliding] = 2
            # Kinetic friction lies on the cone, along the direction the sticking spring was pulling.
            slide[sliding] = tangential[sliding] * (cone[sliding] / np.maximum(magnitude[sliding], 1e-300))[:, None]
        return new_status, slide

    def end_displacement(
        self, contacts: ContactSet, relative: np.ndarray, forces: np.ndarray, status: np.ndarray, dt: float
    ) -> np.ndarray:
        """End-of-step tangential spring displacement: integrated while sticking, on the cone edge when sliding."""
        normal = contacts.normal
        v_t = relative - (relative * normal).sum(axis=1)[:, None] * normal
        displacement = contacts.displacement + dt * v_t
        sliding = status == 2
        if sliding.any():
            f_n = (forces[sliding] * normal[sliding]).sum(axis=1)
            tangential = forces[sliding] - f_n[:, None] * normal[sliding]
            displacement[sliding] = -tangential / (contacts.weight[sliding, None] * self.law.k_t)
        displacement[status == 0] = 0.0
        return displacement

    def project_on_cone(
        self, f_t: np.ndarray, cone: np.ndarray, displacement: np.ndarray, weight: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Clip tangential forces to ``|f_t| <= cone``; a sliding contact's anchor follows (w k_t |u| = cone)."""
        magnitude = np.linalg.norm(f_t, axis=1)
        sticking = magnitude <= cone
        sliding = ~sticking
        if np.any(sliding):
            direction = f_t[sliding] / magnitude[sliding, None]
            f_t = f_t.copy()
            f_t[sliding] = cone[sliding, None] * direction
            displacement = displacement.copy()
            displacement[sliding] = -f_t[sliding] / (weight[sliding, None] * self.law.k_t)
        return f_t, sticking, displacement
