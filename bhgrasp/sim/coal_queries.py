"""coal's collision queries as the contact detection asks them: tolerances, fresh requests, converged results.

Both engines ask each pair with GJK and EPA at :data:`NARROW_TOLERANCE` and ask again at :data:`FALLBACK_TOLERANCE`
when the answer did not converge (:func:`converged`) or reports a depth no contact of the two shapes can have
(:func:`plausible_depth`); :mod:`bhgrasp.sim.contact` (Python) and ``src/engine.cpp`` (compiled, given both
tolerances) do the same.
"""

from __future__ import annotations

import coal
import numpy as np

NARROW_TOLERANCE = 1e-10  # GJK/EPA: coal's default 1e-6 tilts a box-on-box normal by up to 0.027 (1.5 deg)
# At 1e-10 coal 3.0.3's EPA may stop unconverged (a box edge in a cylinder: depth -1.8e308, point 0); such a query is
# asked again at coal's default tolerance, which converged there (depth 0.53 mm, as coal.distance gives).
# It may also stop at a depth no contact has: a can's rim on its stand read 307 mm at 1e-10 (0.029 mm at 1e-8 and 1e-6),
# so a depth beyond the smaller shape's bounding diameter is asked again too.
FALLBACK_TOLERANCE = 1e-6
MAX_DEPTH = 1.0  # [m] a reported penetration beyond this is a failed query, not a contact (half-spaces, planes)


def converged(result: coal.CollisionResult, max_depth: float = MAX_DEPTH) -> bool:
    """Whether every contact of a collision query has a finite depth within ``max_depth`` [m] (EPA converged)."""
    for i in range(result.numContacts()):
        depth = result.getContact(i).penetration_depth
        if not abs(depth) <= max_depth:
            return False
    return True


def bounding_sphere(shape: coal.CollisionGeometry) -> tuple[np.ndarray, float]:
    """A sphere holding ``shape``: its centre in the shape's frame [m] and radius [m] (inf, centre 0: unbounded).

    coal's ``aabb_center`` and ``aabb_radius``, measured on a copy (the scene's shapes untouched: its signature reads
    them).
    """
    shape = shape.clone()
    shape.computeLocalAABB()
    radius, centre = float(shape.aabb_radius), np.array(shape.aabb_center)
    if not (np.isfinite(radius) and np.isfinite(centre).all()):
        return np.zeros(3), np.inf
    return centre, radius


def plausible_depth(radius_a: float, radius_b: float) -> float:
    """The deepest penetration [m] a query of two shapes may report: the smaller one's bounding diameter.

    From their bounding spheres' radii [m] (:func:`bounding_sphere`); at most :data:`MAX_DEPTH` (a half-space has no
    bound).
    """
    return min(2.0 * min(radius_a, radius_b), MAX_DEPTH)


def fresh_request(template: coal.CollisionRequest, tolerance: float = NARROW_TOLERANCE) -> coal.CollisionRequest:
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


__all__ = [
    "FALLBACK_TOLERANCE",
    "MAX_DEPTH",
    "NARROW_TOLERANCE",
    "bounding_sphere",
    "converged",
    "fresh_request",
    "plausible_depth",
]
