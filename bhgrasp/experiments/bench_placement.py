"""Where the grasp benchmark puts the hand over an object: so that its fingers reach the object together.

A closing BH8-280 is not symmetric about its palm centre: F3's knuckle is fixed on one side, F1's and F2's turn on
the spread on the other.  Centred over a 35 mm ball at the 60 deg spread, F3 touches it at a proximal angle of
1.23 rad and F1/F2 at 1.41 rad, so F3 pushes the ball away before the others arrive and it rolls off.  With every
finger closing at the same rate (the close command), the fingers arrive together when their touch angles agree:
:func:`grasp_offset` finds the object's offset along the F3 axis (hand y) where F3's touch angle equals F1's, by
bisection, each touch angle itself a bisection on coal's distance between the finger's collision shapes and the
object.
"""

from __future__ import annotations

import itertools

import coal
import numpy as np
import pinocchio as pin

import bhgrasp as bh
from bhgrasp.experiments.bench_objects import BenchObject

_FLIP = pin.rpy.rpyToMatrix(np.pi, 0.0, 0.0)  # world <- palm-down hand: an upright object's axes in the hand frame


class _Reach:
    """The proximal angle at which each finger first touches an object placed in the hand frame."""

    def __init__(self, item: BenchObject, spread: float, opening: float, closed: float = 2.4) -> None:
        self.hand = bh.BarrettHand()
        self.geometry = self.hand.collision_model()
        self.data = pin.GeometryData(self.geometry)
        self.model_data = self.hand.model.createData()
        self.shape = item.body(0.8).geometry()
        self.spread, self.opening, self.closed = spread, opening, closed
        self.shapes = {finger: [i for i, g in enumerate(self.geometry.geometryObjects)
                                if g.name.startswith(finger) and "knuckle" not in g.name]
                       for finger in self.hand.fingers}  # fmt: skip

    def distance(self, finger: str, angle: float, centre: np.ndarray) -> float:
        """Distance [m] from the finger's links to the object at ``centre`` with every finger at ``angle``."""
        q = self.hand.configuration(F1_spread=self.spread, F2_spread=self.spread,
                                    **{f"{f}_proximal": angle for f in self.hand.fingers},
                                    **{f"{f}_distal": angle / 3 for f in self.hand.fingers})  # fmt: skip
        pin.updateGeometryPlacements(self.hand.model, self.model_data, self.geometry, self.data, q)
        placement = coal.Transform3s(_FLIP, centre)
        nearest = np.inf
        for i in self.shapes[finger]:
            frame = self.data.oMg[i]
            result = coal.DistanceResult()
            gap = coal.distance(self.geometry.geometryObjects[i].geometry, coal.Transform3s(frame.rotation,
                                frame.translation), self.shape, placement, coal.DistanceRequest(), result)  # fmt: skip
            nearest = min(nearest, gap)
        return nearest

    def touch(self, finger: str, centre: np.ndarray) -> float:
        """The first proximal angle [rad] at which ``finger`` touches (``closed`` if it never does)."""
        low, high = self.opening, self.closed
        if self.distance(finger, low, centre) <= 0.0:
            return low
        if self.distance(finger, high, centre) > 0.0:
            return high
        for _ in range(30):
            middle = 0.5 * (low + high)
            low, high = (middle, high) if self.distance(finger, middle, centre) > 0.0 else (low, middle)
        return high


def _deepest_corner(shape: coal.CollisionGeometry, placement: pin.SE3) -> float:
    """The largest z [m] of a shape's local bounding-box corners placed by ``placement``."""
    shape.computeLocalAABB()
    box = shape.aabb_local
    return max(placement.act(np.array(corner))[2] for corner in itertools.product(*zip(box.min_, box.max_)))


def hand_depth(spread: float, opening: float) -> float:
    """How far [m] below the hand base (hand frame z) its lowest non-finger shape reaches.

    That is the knuckle housings (0.091 m), 11 mm beyond the palm surface; the benchmark's clearances start there.
    """
    reach = _Reach(BenchObject("sphere", (0.01,), 0.1), spread, opening)
    q = reach.hand.configuration(F1_spread=spread, F2_spread=spread)
    pin.updateGeometryPlacements(reach.hand.model, reach.model_data, reach.geometry, reach.data, q)
    shapes = reach.geometry.geometryObjects
    return max(_deepest_corner(item.geometry, reach.data.oMg[i]) for i, item in enumerate(shapes)
               if not any(part in item.name for part in ("proximal", "distal")))  # fmt: skip


def grasp_offset(item: BenchObject, spread: float, clearance: float, opening: float) -> float:
    """The object's offset [m] along the hand's y axis (towards F3) at which F3 and F1 touch it at the same angle.

    ``clearance``: the knuckles (:func:`hand_depth`) to the object's top [m]; ``opening``: the pre-shape's
    proximal angle [rad].
    """
    reach = _Reach(item, spread, opening)
    depth = hand_depth(spread, opening) + clearance + item.half_extents[2]  # the object's centre, hand frame z

    def imbalance(offset: float) -> float:  # > 0: F1 arrives later than F3
        centre = np.array([0.0, offset, depth])
        return reach.touch("F1", centre) - reach.touch("F3", centre)

    # F3 is on +y: moving the object to -y delays F3.  Far off-centre a finger misses the object altogether, so
    # the sign change nearest the centre is bracketed on a 5 mm grid first.
    grid = np.linspace(-0.04, 0.04, 17)
    signs = np.sign([imbalance(float(y)) for y in grid])
    changes = [i for i in range(16) if signs[i] * signs[i + 1] <= 0.0]
    if not changes:
        return 0.0  # no balance inside the palm: keep it centred
    i = min(changes, key=lambda i: abs(grid[i] + grid[i + 1]))
    low, high = float(grid[i]), float(grid[i + 1])
    for _ in range(25):
        middle = 0.5 * (low + high)
        low, high = (low, middle) if imbalance(middle) > 0.0 else (middle, high)
    return 0.5 * (low + high)


__all__ = ["grasp_offset", "hand_depth"]
