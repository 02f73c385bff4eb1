"""Whether a grasped object's motion clears its surroundings: the support it starts on, a table, a wall.

A motion of the grasp supervisor (:class:`~bhgrasp.motion.trajectories.PoseMotion`: a minimum-jerk offset of the
object's pose, rotating about a fixed world axis through its origin) is checked before anything is simulated, at
``samples`` evenly spaced poses along the path, by coal's signed distance between the object's shape and each fixed
shape.  A turn of an object resting on its support drives an edge into it: :func:`check_clearance` refuses such a motion
with the smallest lift (added to the offset) that clears the path.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import coal
import numpy as np
import pinocchio as pin

from bhgrasp._validation import as_vector
from bhgrasp.errors import InputError, UnreachableError

CONTACT_TOLERANCE = 1e-4  # [m] a path may come this close to (or touch by this much) a fixed shape: resting contact


def path_clearance(
    shape: coal.CollisionGeometry, start: pin.SE3, offset: Any, fixed: Sequence[Any], samples: int = 21
) -> tuple[float, float, str]:
    """The smallest signed distance [m] from the moving ``shape`` to the ``fixed`` shapes along the path.

    Args:
        shape: The object's coal shape, placed by its pose.
        start: The object's pose when the motion starts (world).
        offset: (dx [m], dtheta [rad]) of the motion, world.
        fixed: Fixed shapes with ``geometry()``, ``placement`` and ``name`` (e.g.
            :class:`~bhgrasp.model.objects.FixedBox`; an unnamed one is called "environment<i>", as the scene calls it).
        samples: Poses checked along the path (the start and the end included).

    Returns:
        The distance (negative: penetration), the path fraction where it occurs, and that shape's name.
    """
    offset = as_vector(offset, "offset", 6)
    if int(samples) < 2:
        raise InputError(f"`samples` must be at least 2 (the start and the end), got {samples}")
    worst = (np.inf, 0.0, "")
    request, result = coal.DistanceRequest(), coal.DistanceResult()
    for index, item in enumerate(fixed):
        geometry, placement = item.geometry(), coal.Transform3s(item.placement)
        name = getattr(item, "name", None) or f"environment{index}"
        for fraction in np.linspace(0.0, 1.0, int(samples)):
            # the supervisor's path at blend ``fraction``: x_0 + b dx, exp(b dtheta) R_0 (PoseMotion)
            pose = coal.Transform3s(
                pin.exp3(fraction * offset[3:]) @ start.rotation, start.translation + fraction * offset[:3]
            )
            result.clear()
            distance = coal.distance(shape, pose, geometry, placement, request, result)
            if distance < worst[0]:
                worst = (float(distance), float(fraction), name)
    return worst


def check_clearance(
    shape: coal.CollisionGeometry, start: pin.SE3, offset: Any, fixed: Sequence[Any], samples: int = 21
) -> None:
    """Refuse a motion that drives the object into a fixed shape, naming it and the lift that would clear the path.

    Raises:
        UnreachableError: The path penetrates a fixed shape by more than :data:`CONTACT_TOLERANCE`; the message gives
            the shape, how deep, where along the path, and the smallest extra lift (up to 5 cm, 0.1 mm resolution)
            after which the same motion clears everything; ``result`` is that lifted offset (``None`` if none does).
    """
    offset = as_vector(offset, "offset", 6)
    start_gap = path_clearance(shape, start, np.zeros(6), fixed, 2)[0]
    allowed = min(start_gap, 0.0) - CONTACT_TOLERANCE  # resting contact (or a start already pressed in) is fine
    distance, fraction, name = path_clearance(shape, start, offset, fixed, samples)
    if distance >= allowed:
        return
    lift = _smallest_lift(shape, start, offset, fixed, samples, allowed)
    lifted = None if lift is None else offset + np.array([0.0, 0.0, lift, 0.0, 0.0, 0.0])
    advice = (
        f"lift the object by {1e3 * lift:.1f} mm more (offset {np.round(lifted, 5).tolist()})"
        if lift is not None
        else "no lift up to 5 cm clears it"
    )
    raise UnreachableError(
        f"the motion {np.round(offset, 6).tolist()} (dx [m], dtheta [rad]) drives the object {1e3 * -distance:.2f} mm "
        f"into {name} at {100 * fraction:.0f} % of its path; {advice}",
        lifted,
    )


def _smallest_lift(shape, start, offset, fixed, samples, allowed) -> float | None:
    """The smallest extra rise [m] along world z that clears the path (bisection to 0.1 mm), or None up to 5 cm."""

    def clears(lift: float) -> bool:
        lifted = offset + np.array([0.0, 0.0, lift, 0.0, 0.0, 0.0])
        return path_clearance(shape, start, lifted, fixed, samples)[0] >= allowed

    low, high = 0.0, 0.05
    if not clears(high):
        return None
    while high - low > 1e-4:
        middle = 0.5 * (low + high)
        low, high = (low, middle) if clears(middle) else (middle, high)
    return high


__all__ = ["CONTACT_TOLERANCE", "check_clearance", "path_clearance"]
