"""Grasp analysis: contact frames, grasp map, hand Jacobian, friction cones, force closure and grasp quality.

Thesis chapter 5, (5.1)-(5.19), re-derived (the printed equations have typos).  Conventions:

* Contact i is a point ``p_i`` (world, [m]) with a unit normal ``n_i`` pointing INTO the object: the direction
  in which the finger pushes.  Its contact frame ``R_i = [t1_i, t2_i, n_i]`` (columns, world coordinates) is
  right-handed and orthonormal; :func:`contact_frames` fixes the tangents.
* Point contact with friction: the finger applies the force ``R_i f_i`` [N] to the object, with
  ``f_i = (f_t1, f_t2, f_n)`` in the contact frame inside the friction cone
  ``FC_i = {sqrt(f_t1^2 + f_t2^2) <= mu f_n}`` (5.6).  Contact forces are stacked ``f = (f_1, ..., f_n)``, (3n,).
* The object wrench is ``(force [N], torque [N m] about a reference point r)``, world-aligned, e.g. about the
  object's centre of mass: ``wrench = G f`` with the grasp map ``G = [G_1 ... G_n]``,
  ``G_i = [[R_i], [skew(p_i - r) R_i]]`` (6, 3) (5.8)-(5.12).
* The object twist ``x_dot_o = (v_r, omega)`` [m/s, rad/s] is the velocity of the object point at ``r`` and the
  angular velocity, world-aligned.  The contact point of the object moves with ``v_r + omega x (p_i - r)``, in
  contact coordinates ``G_i^T x_dot_o``: ``G^T`` is the dual (velocity) map of ``G``.
* The hand Jacobian ``J_h`` (3n, nv) maps joint velocities to the velocities of the finger points at the contacts
  in contact coordinates, ``R_i^T J_p,i v`` (5.14)-(5.17).  A contact that neither slips nor separates (no
  rolling either: the point is fixed on both bodies) imposes the grasp constraint ``G^T x_dot_o = J_h v`` (5.19).

Against the printed thesis: the lever in (5.10) is ``p_i - r`` (reference to contact), with the selection
``W_i`` of (5.5) keeping only the force columns of ``A_i``; for point contacts ``J_h,i`` of (5.17)/(5.19) is
(3, nv), not (6, l), and ``B_i`` reduces to ``R_i^T [I, -skew(p_i - o)]`` acting on the link's spatial velocity.

Force closure (Definition 5.1) is decided on linearised cones: each cone is replaced by the pyramid with
``facets`` edges inscribed in it, which is conservative (a grasp in closure with the pyramids is in closure with
the exact cones, not always the converse).  The grasp wrench space is the convex hull of the primitive wrenches
(the pyramid edges mapped by ``G_i``, unit-norm contact forces); its inscribed-ball radius about the origin is the
L1 Ferrari-Canny quality epsilon.  Torques are divided by a length ``torque_scale`` [m] before forces and torques
are compared; epsilon and the volume depend on it, force closure does not.

``import bhgrasp.grasp`` does not import scipy: the LP and the convex hull import it when they are called.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from bhgrasp._native import optional_core
from bhgrasp._validation import as_array, as_positive, as_real, as_vector
from bhgrasp.errors import BhgraspError, InputError
from bhgrasp.hand import Hand

TANGENT_SWITCH = 0.9  # |n . x| above which the tangent t1 is built from the world y-axis instead of the x-axis
ZERO_NORMAL = 1e-12  # a normal shorter than this is rejected as zero
LP_TOLERANCE = 1e-10  # HiGHS primal/dual feasibility tolerance of the force-closure LP
CLOSURE_TOLERANCE = 1e-9  # default margin above which a grasp counts as force closure


# ------------------------------------------------------------------ contact geometry
def contact_frames(normals: Any) -> np.ndarray:
    """Right-handed orthonormal contact frames ``R_i = [t1_i, t2_i, n_i]`` (columns, world), shape (n, 3, 3).

    ``n_i`` is the normalised normal.  ``t1_i`` is the world x-axis projected onto the tangent plane and
    normalised, ``t1 = normalise(a - (a . n) n)`` with ``a = x``, unless the normal is within about 26 degrees of
    the x-axis (``|n_x| > 0.9``), where ``a = y``; ``t2 = n x t1``.  So the frame is deterministic, depends
    continuously on the normal except across the switch ``|n_x| = 0.9``, and is the identity for ``n = +z``.

    Args:
        normals: Contact normals (world, pointing into the object), shape (n, 3); need not be unit vectors.

    Raises:
        InputError: Wrong shape, or a zero or non-finite normal (the message names the contact index).
    """
    normals = _rows(normals, "normals")
    core = optional_core()
    if core is None:
        return _frames(_unit_normals(normals))
    frames, zero = core.contact_frames(normals, ZERO_NORMAL, TANGENT_SWITCH)  # src/sensing.cpp, _frames' twin
    if zero >= 0:
        _unit_normals(normals)  # raises InputError naming the zero normals
    return frames.reshape(-1, 3, 3)


def _frames(unit: np.ndarray) -> np.ndarray:
    """:func:`contact_frames` of validated unit normals (n, 3): t1, t2 = n x t1 written out component-wise."""
    switch = np.abs(unit[:, 0]) > TANGENT_SWITCH
    axis = np.zeros_like(unit)
    axis[~switch, 0] = 1.0
    axis[switch, 1] = 1.0
    t1 = axis - np.einsum("ij,ij->i", axis, unit)[:, None] * unit
    t1 /= np.sqrt(np.einsum("ij,ij->i", t1, t1))[:, None]
    frames = np.empty((unit.shape[0], 3, 3))
    frames[:, :, 0], frames[:, :, 2] = t1, unit
    nx, ny, nz = unit.T
    ax, ay, az = t1.T
    frames[:, 0, 1], frames[:, 1, 1], frames[:, 2, 1] = ny * az - nz * ay, nz * ax - nx * az, nx * ay - ny * ax
    return frames


def grasp_map(points: Any, normals: Any, reference: Any) -> np.ndarray:
    """Grasp map ``G`` (6, 3n): object wrench (force [N], torque [N m] about ``reference``) = ``G f``.

    ``G_i = [[R_i], [skew(p_i - r) R_i]]`` with ``R_i`` from :func:`contact_frames`, so that the wrench is
    ``(sum R_i f_i, sum (p_i - r) x R_i f_i)`` (thesis (5.8)-(5.12)).

    Args:
        points: Contact points, world [m], shape (n, 3).
        normals: Contact normals into the object, world, shape (n, 3).
        reference: Point the torque is taken about (e.g. the object's centre of mass), world [m], shape (3,).
    """
    points, normals = _contacts(points, normals)
    return _grasp_map(points, contact_frames(normals), as_vector(reference, "reference", 3))


def _grasp_map(points: np.ndarray, frames: np.ndarray, reference: np.ndarray) -> np.ndarray:
    """:func:`grasp_map` from validated points (n, 3) and their contact frames (n, 3, 3)."""
    levers = _skew_rows(points - reference)  # (n, 3, 3)
    blocks = np.concatenate([frames, levers @ frames], axis=1)  # (n, 6, 3)
    return blocks.transpose(1, 0, 2).reshape(6, 3 * points.shape[0])


def hand_jacobian(hand: Hand, q: Any, points: Any, links: Sequence[str] | str, normals: Any) -> np.ndarray:
    """Hand Jacobian ``J_h`` (3n, nv): velocities of the finger points at the contacts, in contact coordinates.

    Rows ``3i:3i+3`` are ``R_i^T J_p,i`` where ``J_p,i = J_lin - skew(p_i - o) J_ang`` is the world translational
    Jacobian of the point ``p_i`` fixed on link frame ``links[i]`` (origin ``o``), thesis (5.14)-(5.17).  With
    the object twist at the reference of :func:`grasp_map`, a fixed contact obeys ``G^T x_dot_o = J_h v`` (5.19).

    Args:
        hand: The hand.
        q: Configuration, shape (nq,).
        points: Contact points, world [m], shape (n, 3), at configuration ``q``.
        links: Frame name of the link carrying each contact (e.g. ``"F3_distal_link"``), n names; a single name
            puts every contact on that link.
        normals: Contact normals into the object, world, shape (n, 3).

    Raises:
        InputError: Bad shapes or values, a wrong number of links, or an unknown frame name.
    """
    points, normals = _contacts(points, normals)
    count = points.shape[0]
    if isinstance(links, str):
        links = [links] * count
    if not isinstance(links, Sequence) or len(links) != count or not all(isinstance(link, str) for link in links):
        raise InputError(f"`links` must be {count} frame name(s), one per contact, got {links!r}")
    return _hand_jacobian(hand, q, points, links, contact_frames(normals))


def _hand_jacobian(hand: Hand, q: Any, points: np.ndarray, links: Sequence[str], frames: np.ndarray) -> np.ndarray:
    """:func:`hand_jacobian` from validated points, link names and contact frames (n, 3, 3)."""
    jacobians = hand.point_jacobians(q, links, points)  # (n, 3, nv), one kinematics pass
    return np.einsum("nji,njk->nik", frames, jacobians).reshape(3 * len(links), hand.nv)


def grasp_constraint_residual(grasp_matrix: Any, jacobian: Any, object_twist: Any, v: Any) -> np.ndarray:
    """Residual of the grasp constraint (5.19), ``J_h v - G^T x_dot_o``, shape (3n,) [m/s], contact coordinates.

    Zero when every contact point is fixed on both the finger and the object (no slip, no rolling).

    Args:
        grasp_matrix: ``G`` (6, 3n) from :func:`grasp_map`.
        jacobian: ``J_h`` (3n, nv) from :func:`hand_jacobian`.
        object_twist: ``(v_r [m/s], omega [rad/s])`` of the object at the reference point, world-aligned, (6,).
        v: Joint velocities, shape (nv,).
    """
    grasp_matrix = _grasp_matrix(grasp_matrix)
    jacobian = as_array(jacobian, "jacobian", (grasp_matrix.shape[1], None))
    twist = as_vector(object_twist, "object_twist", 6)
    v = as_vector(v, "v", jacobian.shape[1])
    return jacobian @ v - grasp_matrix.T @ twist


# ------------------------------------------------------------------ friction cones
def friction_cone_edges(mu: float, facets: int = 8) -> np.ndarray:
    """Unit edges of the pyramid inscribed in the friction cone, contact frame, shape (facets, 3).

    Edge j is ``(mu cos th_j, mu sin th_j, 1) / sqrt(1 + mu^2)`` with ``th_j = 2 pi j / facets``: every edge lies
    on the exact cone, so the pyramid is inside it (conservative).  For ``mu = 0`` all edges are the normal.

    Raises:
        InputError: ``mu`` not finite and >= 0, or ``facets`` not an integer >= 3.
    """
    mu, facets = _mu(mu), _facets(facets)
    angles = 2.0 * np.pi * np.arange(facets) / facets
    edges = np.column_stack([mu * np.cos(angles), mu * np.sin(angles), np.ones(facets)])
    return edges / math.sqrt(1.0 + mu * mu)


def friction_pyramid(mu: float, facets: int = 8) -> tuple[np.ndarray, np.ndarray]:
    """Half-space form ``A f <= b`` (``b = 0``) of the pyramid of :func:`friction_cone_edges`, contact frame.

    Facet j joins edges j and j+1: ``d_j . f_t <= mu cos(pi / facets) f_n`` with ``d_j`` the unit tangent at the
    mid-angle ``2 pi (j + 1/2) / facets``; rows of ``A`` are normalised, so ``A f`` is the signed distance [N]
    of ``f`` to each facet plane.  For ``mu > 0`` the rows imply ``f_n >= 0`` (they sum to a negative multiple of
    ``f_n``); for ``mu = 0`` they only give ``f_t = 0``, and ``f_n >= 0`` must be added by the caller.

    Returns:
        ``(A, b)``: ``A`` (facets, 3) and ``b`` (facets,) zeros.
    """
    mu, facets = _mu(mu), _facets(facets)
    angles = 2.0 * np.pi * (np.arange(facets) + 0.5) / facets
    rows = np.column_stack([np.cos(angles), np.sin(angles), np.full(facets, -mu * math.cos(math.pi / facets))])
    return rows / np.linalg.norm(rows, axis=1, keepdims=True), np.zeros(facets)


def in_friction_cone(f: Any, mu: float, margin: float = 0.0) -> bool:
    """Whether a contact force lies in the exact (second-order) friction cone.

    Tests ``f_n >= 0`` and ``sqrt(f_t1^2 + f_t2^2) <= mu f_n - margin``.

    Args:
        f: Contact force ``(f_t1, f_t2, f_n)`` [N] in the contact frame, shape (3,).
        mu: Friction coefficient, finite and >= 0.
        margin: Required clearance [N] (> 0: strictly inside by that much; < 0: a tolerance).
    """
    f = as_vector(f, "f", 3)
    mu, margin = _mu(mu), as_real(margin, "margin", nonnegative=False)
    return bool(f[2] >= 0.0 and math.hypot(f[0], f[1]) <= mu * f[2] - margin)


# ------------------------------------------------------------------ force closure and quality
def default_torque_scale(grasp_matrix: Any) -> float:
    """Largest distance [m] from the reference to a contact point, read from ``G``; 1.0 if every distance is 0.

    For ``G_i = [[R_i], [skew(d_i) R_i]]``, ``|d_i| = ||G_i[3:]||_F / sqrt(2)`` (``R_i`` is orthogonal).
    """
    grasp_matrix = _grasp_matrix(grasp_matrix)
    lever = np.linalg.norm(grasp_matrix[3:].reshape(3, -1, 3), axis=(0, 2)).max() / math.sqrt(2.0)
    return float(lever) if lever > 0.0 else 1.0


def primitive_wrenches(grasp_matrix: Any, mu: float, facets: int = 8, torque_scale: float | None = None) -> np.ndarray:
    """Primitive wrenches (6, n * facets): each unit pyramid edge of each contact mapped by ``G_i``.

    Column ``i * facets + j`` is ``G_i e_j`` (:func:`friction_cone_edges`) with its torque rows divided by
    ``torque_scale`` [m], so both halves are in newtons.

    Args:
        grasp_matrix: ``G`` (6, 3n) from :func:`grasp_map`.
        mu: Friction coefficient, finite and >= 0.
        facets: Edges per linearised cone, >= 3.
        torque_scale: Length [m] that divides the torques; by default :func:`default_torque_scale` (the largest
            reference-to-contact distance), which makes the result independent of the unit of length.
    """
    grasp_matrix = _grasp_matrix(grasp_matrix)
    edges = friction_cone_edges(mu, facets)
    scale = default_torque_scale(grasp_matrix) if torque_scale is None else as_positive(torque_scale, "torque_scale")
    count = grasp_matrix.shape[1] // 3
    blocks = grasp_matrix.reshape(6, count, 3)
    wrenches = np.einsum("rik,jk->rij", blocks, edges).reshape(6, count * edges.shape[0])
    wrenches[3:] /= scale
    return wrenches


def force_closure_margin(grasp_matrix: Any, mu: float, facets: int = 8) -> float:
    """Force-closure margin s*: the largest s such that some ``lam >= s``, ``sum lam = 1`` balances, ``W lam = 0``.

    ``W`` are the primitive wrenches (:func:`primitive_wrenches`); the LP is solved by HiGHS
    (``scipy.optimize.linprog``).  The grasp (frictional point contacts, inscribed linearised cones) is in force
    closure iff ``rank W = 6`` and s* > 0 (the primitive wrenches positively span R^6).  s* lies in
    ``[0, 1 / (n facets)]``; it is 0.0 when ``rank W < 6`` or when no convex combination balances.  It does not
    depend on the torque scale.

    Raises:
        BhgraspError: The LP solver fails for a reason other than infeasibility.
    """
    wrenches = primitive_wrenches(grasp_matrix, mu, facets)
    if _rank(wrenches) < 6:
        return 0.0
    return _margin(wrenches)


def is_force_closure(grasp_matrix: Any, mu: float, facets: int = 8, tolerance: float = CLOSURE_TOLERANCE) -> bool:
    """Whether the grasp is in force closure: ``rank W = 6`` and :func:`force_closure_margin` > ``tolerance``.

    Frictional point contacts with the cones linearised by inscribed pyramids (conservative: closure with the
    pyramids implies closure with the exact cones).
    """
    tolerance = as_real(tolerance, "tolerance")
    return force_closure_margin(grasp_matrix, mu, facets) > tolerance


def ferrari_canny(grasp_matrix: Any, mu: float, facets: int = 8, torque_scale: float | None = None) -> float:
    """L1 Ferrari-Canny quality epsilon [N]: radius of the largest origin-centred ball in the grasp wrench space.

    The grasp wrench space is the convex hull of :func:`primitive_wrenches` (unit contact forces; torques divided
    by ``torque_scale``, by default the largest reference-to-contact distance: epsilon depends on this choice).
    With the hull's facets ``a . w + b <= 0`` (unit ``a``), epsilon = ``min(-b)`` when the origin is strictly
    inside.  Returns 0.0 when it is not (no force closure): the signed value outside is not a distance and is not
    returned.  So epsilon > 0 iff :func:`is_force_closure`, up to rounding for grasps at the boundary of closure.
    A degenerate hull (primitive wrenches of rank < 6 or affinely flat, a qhull failure) also gives 0.0.
    """
    wrenches = primitive_wrenches(grasp_matrix, mu, facets, torque_scale)
    return _epsilon(_hull(wrenches))


def grasp_wrench_space_volume(
    grasp_matrix: Any, mu: float, facets: int = 8, torque_scale: float | None = None
) -> float:
    """Volume [N^6] of the grasp wrench space (hull of :func:`primitive_wrenches`); 0.0 when degenerate."""
    hull = _hull(primitive_wrenches(grasp_matrix, mu, facets, torque_scale))
    return 0.0 if hull is None else float(hull.volume)


@dataclass(frozen=True)
class GraspQuality:
    """Grasp analysis of one set of contacts (see :func:`grasp_quality`).

    Attributes:
        force_closure: Whether the grasp is in force closure (:func:`is_force_closure`).
        margin: :func:`force_closure_margin`, dimensionless.
        epsilon: L1 Ferrari-Canny quality [N] (:func:`ferrari_canny`).
        volume: Grasp wrench space volume [N^6] (:func:`grasp_wrench_space_volume`).
        rank: Rank of the primitive wrenches (6 is needed for closure).
        torque_scale: Length [m] the torques were divided by.
    """

    force_closure: bool
    margin: float
    epsilon: float
    volume: float
    rank: int
    torque_scale: float


def grasp_quality(
    points: Any,
    normals: Any,
    reference: Any,
    mu: float,
    facets: int = 8,
    torque_scale: float | None = None,
) -> GraspQuality:
    """Force closure, margin, Ferrari-Canny epsilon and wrench-space volume of frictional point contacts.

    Args:
        points: Contact points, world [m], shape (n, 3).
        normals: Contact normals into the object, world, shape (n, 3).
        reference: Torque reference point (e.g. the object's centre of mass), world [m], shape (3,).
        mu: Friction coefficient, finite and >= 0.
        facets: Edges per linearised cone, >= 3.
        torque_scale: Length [m] dividing torques; by default the largest reference-to-contact distance.
    """
    grasp_matrix = grasp_map(points, normals, reference)
    scale = default_torque_scale(grasp_matrix) if torque_scale is None else as_positive(torque_scale, "torque_scale")
    wrenches = primitive_wrenches(grasp_matrix, mu, facets, scale)
    rank = _rank(wrenches)
    margin = _margin(wrenches) if rank == 6 else 0.0
    hull = _hull(wrenches) if rank == 6 else None
    volume = 0.0 if hull is None else float(hull.volume)
    return GraspQuality(margin > CLOSURE_TOLERANCE, margin, _epsilon(hull), volume, rank, scale)


# ------------------------------------------------------------------ helpers
def _rank(wrenches: np.ndarray) -> int:
    return int(np.linalg.matrix_rank(wrenches))


def _margin(wrenches: np.ndarray) -> float:
    from scipy.optimize import linprog

    count = wrenches.shape[1]
    cost = np.zeros(count + 1)
    cost[-1] = -1.0  # maximise s
    equality = np.zeros((7, count + 1))
    equality[:6, :count] = wrenches
    equality[6, :count] = 1.0
    upper = np.hstack([-np.eye(count), np.ones((count, 1))])  # s - lam_j <= 0
    bounds = [(0.0, None)] * count + [(None, None)]
    result = linprog(
        cost,
        A_ub=upper,
        b_ub=np.zeros(count),
        A_eq=equality,
        b_eq=np.r_[np.zeros(6), 1.0],
        bounds=bounds,
        method="highs",
        options={"primal_feasibility_tolerance": LP_TOLERANCE, "dual_feasibility_tolerance": LP_TOLERANCE},
    )
    if result.status == 2:  # infeasible: the origin is not in the hull of the primitive wrenches
        return 0.0
    if result.status != 0:
        raise BhgraspError(f"force-closure LP failed (status {result.status}): {result.message}")
    return max(0.0, float(result.x[-1]))


def _epsilon(hull: Any) -> float:
    """Distance from the origin to the nearest facet plane of ``hull`` if the origin is inside, else 0.0."""
    if hull is None:
        return 0.0
    lengths = np.linalg.norm(hull.equations[:, :6], axis=1)  # qhull's normals are unit; renormalise anyway
    return max(0.0, float(np.min(-hull.equations[:, 6] / lengths)))


def _hull(wrenches: np.ndarray) -> Any:
    """Convex hull of the columns, or ``None`` if they do not span a 6-D body."""
    from scipy.spatial import ConvexHull, QhullError

    if _rank(wrenches) < 6:
        return None
    try:
        return ConvexHull(wrenches.T)
    except (QhullError, ValueError):
        return None


def _grasp_matrix(value: Any) -> np.ndarray:
    matrix = as_array(value, "grasp_matrix", (6, None))
    if matrix.shape[1] == 0 or matrix.shape[1] % 3:
        raise InputError(f"`grasp_matrix` must have shape (6, 3n) with n >= 1, got shape {matrix.shape}")
    return matrix


def _rows(value: Any, name: str) -> np.ndarray:
    try:
        array = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError) as error:
        raise InputError(f"`{name}` must be a numeric array of shape (n, 3), got {value!r}") from error
    if array.ndim != 2 or array.shape[1] != 3 or array.shape[0] < 1:
        raise InputError(f"`{name}` must have shape (n, 3) with n >= 1 contacts, got shape {array.shape}")
    if not np.isfinite(array).all():
        bad = np.flatnonzero(~np.all(np.isfinite(array), axis=1))
        raise InputError(f"`{name}` must be finite, got NaN/inf at contact index {bad.tolist()[:5]}")
    return array


def _unit_normals(normals: Any) -> np.ndarray:
    normals = _rows(normals, "normals")
    lengths = np.sqrt(np.einsum("ij,ij->i", normals, normals))
    bad = np.flatnonzero(lengths < ZERO_NORMAL)
    if bad.size:
        raise InputError(f"`normals` must be non-zero, got a zero normal at contact index {bad.tolist()[:5]}")
    return normals / lengths[:, None]


def _contacts(points: Any, normals: Any) -> tuple[np.ndarray, np.ndarray]:
    points, normals = _rows(points, "points"), _rows(normals, "normals")
    if points.shape != normals.shape:
        raise InputError(
            f"`points` and `normals` must have the same shape (n, 3), got {points.shape} and {normals.shape}"
        )
    return points, normals


def _mu(value: Any) -> float:
    return as_real(value, "mu")


def _facets(value: Any) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 3:
        raise InputError(f"`facets` must be an integer >= 3, got {value!r}")
    return int(value)


def _skew_rows(vectors: np.ndarray) -> np.ndarray:
    result = np.zeros((vectors.shape[0], 3, 3))
    x, y, z = vectors.T
    result[:, 0, 1], result[:, 0, 2] = -z, y
    result[:, 1, 0], result[:, 1, 2] = z, -x
    result[:, 2, 0], result[:, 2, 1] = -y, x
    return result


__all__ = [
    "GraspQuality",
    "contact_frames",
    "default_torque_scale",
    "ferrari_canny",
    "force_closure_margin",
    "friction_cone_edges",
    "friction_pyramid",
    "grasp_constraint_residual",
    "grasp_map",
    "grasp_quality",
    "grasp_wrench_space_volume",
    "hand_jacobian",
    "in_friction_cone",
    "is_force_closure",
    "primitive_wrenches",
]
