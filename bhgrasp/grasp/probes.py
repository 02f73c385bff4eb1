"""Geometric queries of grasp planning: rays against an object, and the hand's clearance from it (coal distances).

:class:`ObjectProbe` finds where a line of approach meets an object's surface (1 mm steps, then bisection to
:data:`SURFACE_TOLERANCE`), the outward normal there, and whether the surface is flat around a point (no edge within
a margin).  :class:`HandClearance` gives the least distance from an object to every collision shape of a hand except
the fingertip pads that grasp it (a link body must not touch beside a pad).  :func:`contact_geometries` finds the
collision geometry each contact lies on, :func:`pressed_face` the face of a box a contact presses.  World frame,
metres.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import coal
import numpy as np
import pinocchio as pin

from bhgrasp.errors import InputError
from bhgrasp.model.hand import Hand

SURFACE_TOLERANCE = 1e-5  # [m] the ray's bisection
TRACE_TOLERANCE = 1e-5  # [m] how close to the surface a traced line stops


class ObjectProbe:
    """Rays against an object (world frame): the first surface point along a horizontal line, its outward normal."""

    def __init__(self, shape: coal.ShapeBase, pose: pin.SE3) -> None:
        """Probe ``shape`` placed at ``pose`` (world <- object)."""
        self.shape, self.placement = shape, coal_transform(pose)
        self.point, self.at = coal.Sphere(1e-9), coal.Transform3s()
        self.request, self.result = coal.DistanceRequest(), coal.DistanceResult()

    def distance(self, point: np.ndarray) -> tuple[float, np.ndarray]:
        """Signed distance [m] from ``point`` to the surface (negative inside), and the surface's nearest point."""
        self.result.clear()
        self.at.setTranslation(point)
        distance = coal.distance(self.point, self.at, self.shape, self.placement, self.request, self.result)
        return float(distance), np.asarray(self.result.getNearestPoint2())

    def landing(self, start: np.ndarray, direction: np.ndarray, z: float) -> tuple[np.ndarray, np.ndarray] | None:
        """The first point of the object along ``start + t direction`` (t >= -0.3 m) at height ``z``, and its normal."""
        if not direction.any():
            return None
        at = lambda t: np.array([*(start + t * direction), z])  # noqa: E731
        ts = np.linspace(-0.3, 0.3, 601)  # 1 mm steps through the hand's reach
        inside = [self.distance(at(t))[0] <= 0.0 for t in ts]
        if not any(inside):
            return None
        first = int(np.argmax(inside))
        if first == 0:
            return None
        low, high = ts[first - 1], ts[first]
        while high - low > SURFACE_TOLERANCE:
            middle = 0.5 * (low + high)
            low, high = (middle, high) if self.distance(at(middle))[0] > 0.0 else (low, middle)
        outside = at(low)
        nearest = self.distance(outside)[1]
        normal = outside - nearest
        length = float(np.linalg.norm(normal))
        if length < 1e-12:
            return None
        return nearest, normal / length

    def flat_around(self, point: np.ndarray, normal: np.ndarray, margin: float) -> bool:
        """Whether the surface normal stays within 30 deg of ``normal`` ``margin`` away along both tangents."""
        helper = np.array([1.0, 0.0, 0.0]) if abs(normal[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
        first = np.cross(normal, helper)
        first /= np.linalg.norm(first)
        for tangent in (first, np.cross(normal, first)):
            for sign in (1.0, -1.0):
                outside = point + sign * margin * tangent + margin * normal  # above the surface, beside the contact
                nearest = self.distance(outside)[1]
                direction = outside - nearest
                if direction @ normal < np.cos(np.radians(30.0)) * np.linalg.norm(direction):
                    return False
        return True


class HandClearance:
    """The hand's collision shapes against an object: how close all but the grasping pads come to it."""

    def __init__(self, hand: Hand) -> None:
        """Index the hand's collision shapes and which of them is each finger's pad (a sphere on the tip's link)."""
        self.hand = hand
        self.geometry = hand.collision_model()
        self.data = pin.GeometryData(self.geometry)
        self.model_data = hand.model.createData()
        self.base = hand.base_placement
        tips = {
            hand.model.frames[hand.model.getFrameId(frame)].parentJoint: finger
            for finger, frame in hand.fingertip_frames.items()
        }
        self.pad_of = {}
        for index, item in enumerate(self.geometry.geometryObjects):
            if isinstance(item.geometry, coal.Sphere) and item.parentJoint in tips:
                self.pad_of[index] = tips[item.parentJoint]

    def nearest_other(self, q: np.ndarray, fingers: Sequence[str], shape: coal.ShapeBase, pose: pin.SE3) -> float:
        """The least distance [m] from the object to any hand shape but the pads of ``fingers``."""
        pin.forwardKinematics(self.hand.model, self.model_data, q)
        pin.updateGeometryPlacements(self.hand.model, self.model_data, self.geometry, self.data)
        placement = coal_transform(pose)
        request, result = coal.DistanceRequest(), coal.DistanceResult()
        nearest = np.inf
        for index, item in enumerate(self.geometry.geometryObjects):
            if self.pad_of.get(index) in fingers:
                continue
            result.clear()
            world = self.base * self.data.oMg[index]
            distance = coal.distance(item.geometry, coal_transform(world), shape, placement, request, result)
            nearest = min(nearest, float(distance))
        return nearest


def coal_transform(placement: pin.SE3) -> coal.Transform3s:
    """``placement`` as coal's transform."""
    return coal.Transform3s(placement.rotation, placement.translation)


def contact_geometries(
    hand: Hand, geometry: pin.GeometryModel, q: np.ndarray, points: np.ndarray, links: list[str]
) -> list[int]:
    """The geometry carrying each contact, in order: on the contact link's joint, the one nearest the contact point."""
    model = hand.model
    geometry_data = pin.GeometryData(geometry)
    pin.updateGeometryPlacements(model, pin.Data(model), geometry, geometry_data, q)
    probe, request, result = coal.Sphere(1e-9), coal.DistanceRequest(), coal.DistanceResult()
    pads = []
    for point, link in zip(points, links):
        joint = model.frames[model.getFrameId(link)].parentJoint if model.existFrame(link) else -1
        candidates = [g for g, item in enumerate(geometry.geometryObjects) if item.parentJoint == joint]
        if not candidates:
            raise InputError(f"link {link!r} is not a hand frame carrying collision geometry; contacts lie on one")
        distances = []
        for g in candidates:
            result.clear()
            distances.append(
                coal.distance(
                    geometry.geometryObjects[g].geometry,
                    coal_transform(hand.base_placement * geometry_data.oMg[g]),
                    probe,
                    coal.Transform3s(np.eye(3), point),
                    request,
                    result,
                )
            )
        pads.append(candidates[int(np.argmin(distances))])
    return pads


def pressed_face(shape: coal.CollisionGeometry, rotation: np.ndarray, normal: Any) -> str:
    """The face of a box ``shape`` (turned by ``rotation``) that a contact of world ``normal`` (into it) presses on.

    The face whose outward normal is closest to -normal: e.g. "+y" (robust where the contact straddles an edge).
    """
    if not isinstance(shape, coal.Box):
        return ""
    outward = -(rotation.T @ np.asarray(normal, dtype=float))  # object frame
    axis = int(np.argmax(np.abs(outward)))
    return f"{'+' if outward[axis] >= 0 else '-'}{'xyz'[axis]}"


def first_hit(probe: ObjectProbe, start: np.ndarray, direction: np.ndarray, reach: float) -> tuple | None:
    """The first surface point of a convex object along ``start + t direction`` (0 <= t <= reach), and its normal.

    Sphere tracing: each step is the distance to the surface.  ``None`` if the line misses (or starts inside).
    """
    t = 0.0
    for _ in range(200):
        point = start + t * direction
        distance, nearest = probe.distance(point)
        if distance < 0.0:
            return None  # started inside
        if distance < TRACE_TOLERANCE:
            normal = point - nearest
            return nearest, normal / float(np.linalg.norm(normal))
        t += distance - 0.5 * TRACE_TOLERANCE  # stop outside, where the nearest point gives the normal
        if t > reach:
            return None
    return None


def bounding_radius(shape: coal.ShapeBase) -> float:
    """The radius [m] of the sphere about ``shape``'s origin that holds its bounding box."""
    shape.computeLocalAABB()
    return float(np.linalg.norm(np.maximum(np.abs(shape.aabb_local.min_), np.abs(shape.aabb_local.max_))))


__all__ = [
    "SURFACE_TOLERANCE",
    "TRACE_TOLERANCE",
    "HandClearance",
    "ObjectProbe",
    "bounding_radius",
    "coal_transform",
    "contact_geometries",
    "first_hit",
    "pressed_face",
]
