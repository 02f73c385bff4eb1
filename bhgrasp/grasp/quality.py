"""Force closure and grasp quality: closure margin, Ferrari-Canny epsilon, grasp wrench space volume.

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
from dataclasses import dataclass
from typing import Any

import numpy as np

from bhgrasp._validation import as_positive, as_real
from bhgrasp.errors import BhgraspError
from bhgrasp.grasp.cones import friction_cone_edges
from bhgrasp.grasp.frames import checked_grasp_matrix, grasp_map

LP_TOLERANCE = 1e-10  # HiGHS primal/dual feasibility tolerance of the force-closure LP
CLOSURE_TOLERANCE = 1e-9  # default margin above which a grasp counts as force closure


def default_torque_scale(grasp_matrix: Any) -> float:
    """Largest distance [m] from the reference to a contact point, read from ``G``; 1.0 if every distance is 0.

    For ``G_i = [[R_i], [skew(d_i) R_i]]``, ``|d_i| = ||G_i[3:]||_F / sqrt(2)`` (``R_i`` is orthogonal).
    """
    grasp_matrix = checked_grasp_matrix(grasp_matrix)
    lever = np.linalg.norm(grasp_matrix[3:].reshape(3, -1, 3), axis=(0, 2)).max() / math.sqrt(2.0)
    return float(lever) if lever > 0.0 else 1.0


def primitive_wrenches(grasp_matrix: Any, mu: float, facets: int = 8, torque_scale: float | None = None) -> np.ndarray:
    """Primitive wrenches (6, n * facets): each unit pyramid edge of each contact mapped by ``G_i``.

    Column ``i * facets + j`` is ``G_i e_j`` (:func:`~bhgrasp.grasp.cones.friction_cone_edges`) with its torque rows
    divided by ``torque_scale`` [m], so both halves are in newtons.

    Args:
        grasp_matrix: ``G`` (6, 3n) from :func:`~bhgrasp.grasp.frames.grasp_map`.
        mu: Friction coefficient, finite and >= 0.
        facets: Edges per linearised cone, >= 3.
        torque_scale: Length [m] that divides the torques; by default :func:`default_torque_scale` (the largest
            reference-to-contact distance), which makes the result independent of the unit of length.
    """
    grasp_matrix = checked_grasp_matrix(grasp_matrix)
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


__all__ = [
    "GraspQuality",
    "default_torque_scale",
    "ferrari_canny",
    "force_closure_margin",
    "grasp_quality",
    "grasp_wrench_space_volume",
    "is_force_closure",
    "primitive_wrenches",
]
