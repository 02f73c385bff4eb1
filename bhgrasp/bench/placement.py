"""Where the grasp benchmark puts the hand over an object: so that its fingers reach the object together.

A closing BH8-280 is not symmetric about its palm centre: F3's knuckle is fixed on one side, F1's and F2's turn on
the spread on the other.  Centred over a 35 mm ball at the 60 deg spread, F3 touches it at a proximal angle of
1.23 rad and F1/F2 at 1.41 rad, so F3 pushes the ball away before the others arrive and it rolls off.  With every
finger closing at the same rate (the close command), the fingers arrive together when their touch angles agree:
:func:`grasp_offset` finds the object's offset along the F3 axis (hand y) where F3's touch angle equals F1's, by
bisection, each touch angle itself a bisection on coal's distance between the finger's collision shapes and the
object.

The object stands on a stand of its own footprint (:func:`~bhgrasp.bench.trial.setup`), whose sides
continue the object's.  With the knuckles on the 5 cm box's top the closing fingers pass beside the box and meet the
stand first (coal: 17-30 mm deep at the angle they would reach the box; simulated, the distal links press the stand
with 122-227 N while the knuckles hold the box with 20 N, and the lifted box lies loose in the fingers).
:func:`grasp_clearance` raises the hand from a grasp's nominal height only where a finger, closing, would meet the
stand before the object (:func:`stand_clearance` below 0), and then until every finger touches the object before
the stand with :data:`STAND_MARGIN` to spare; the benchmark applies it to power grasps only.
"""

from __future__ import annotations

import functools
import itertools

import coal
import numpy as np
import pinocchio as pin

import bhgrasp as bh
from bhgrasp.bench.objects import BenchObject
from bhgrasp.grasp.probes import coal_transform

_FLIP = pin.rpy.rpyToMatrix(np.pi, 0.0, 0.0)  # world <- palm-down hand: an upright object's axes in the hand frame
STAND_HEIGHT = 0.2  # [m] the stand under the object (its top the table plane z = 0)
STAND_MARGIN = 0.003  # [m] the fingers' least distance from the stand when they touch the object (~3x the contact's
# 1 mm penetration under the power close)
_SWEEP = 0.01  # [rad] the close's proximal steps in :func:`stand_clearance`


class _Reach:
    """The proximal angle at which each finger first touches an object placed in the hand frame."""

    def __init__(self, item: BenchObject, spread: float, opening: float, closed: float = 2.4) -> None:
        self.hand = bh.BarrettHand()
        hand = self.hand
        self._spread = [hand.joint_index(f"{f}_spread") for f in ("F1", "F2")]
        self._proximal = [hand.joint_index(f"{f}_proximal") for f in hand.fingers]
        self._distal = [hand.joint_index(f"{f}_distal") for f in hand.fingers]
        self._lower, self._upper = hand.lower, hand.upper
        self._request = coal.DistanceRequest()
        self._touches: dict[tuple, float] = {}
        self.geometry = self.hand.collision_model()
        self.data = pin.GeometryData(self.geometry)
        self.model_data = self.hand.model.createData()
        self.shape = item.body(0.8).geometry()
        self.spread, self.opening, self.closed = spread, opening, closed
        self.shapes = {
            finger: [
                i
                for i, g in enumerate(self.geometry.geometryObjects)
                if g.name.startswith(finger) and "knuckle" not in g.name
            ]
            for finger in self.hand.fingers
        }

    def distance(self, finger: str, angle: float, centre: np.ndarray, shape: coal.ShapeBase | None = None) -> float:
        """Distance [m] from the finger's links to the object at ``centre`` with every finger at ``angle``.

        ``shape``: another shape placed at ``centre`` (axes as the object's) instead of the object.
        """
        q = self.configuration(angle)
        pin.updateGeometryPlacements(self.hand.model, self.model_data, self.geometry, self.data, q)
        placement = coal.Transform3s(_FLIP, centre)
        shape = self.shape if shape is None else shape
        nearest = np.inf
        for i in self.shapes[finger]:
            frame = self.data.oMg[i]
            result = coal.DistanceResult()
            gap = coal.distance(
                self.geometry.geometryObjects[i].geometry,
                coal_transform(frame),
                shape,
                placement,
                self._request,
                result,
            )
            nearest = min(nearest, gap)
        return nearest

    def configuration(self, angle: float) -> np.ndarray:
        """Every finger at proximal ``angle`` [rad], the distal at a third, both spreads at ``spread``.

        As ``hand.configuration(...)`` builds it, without its per-joint checks (the search calls it ~10^5 times a
        trial); outside the joint limits it raises as that does.
        """
        q = self.hand.neutral()
        q[self._spread] = self.spread
        q[self._proximal] = angle
        q[self._distal] = angle / 3
        if not ((q >= self._lower).all() and (q <= self._upper).all()):  # the checked call names the joint, raises
            fingers = self.hand.fingers
            return self.hand.configuration(
                F1_spread=self.spread,
                F2_spread=self.spread,
                **{f"{f}_proximal": angle for f in fingers},
                **{f"{f}_distal": angle / 3 for f in fingers},
            )
        return q

    def touch(self, finger: str, centre: np.ndarray) -> float:
        """The first proximal angle [rad] at which ``finger`` touches (``closed`` if it never does), once per place."""
        key = (finger, *map(float, centre))
        found = self._touches.get(key)
        if found is None:
            found = self._touches[key] = self._touch(finger, centre)
        return found

    def _touch(self, finger: str, centre: np.ndarray) -> float:
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


@functools.lru_cache(maxsize=64)
def _reach(item: BenchObject, spread: float, opening: float) -> _Reach:
    """The :class:`_Reach` of ``item`` at ``spread`` and ``opening``, built once per process (its touches kept)."""
    return _Reach(item, spread, opening)


@functools.lru_cache(maxsize=64)
def hand_depth(spread: float, opening: float) -> float:
    """How far [m] below the hand base (hand frame z) its lowest non-finger shape reaches.

    That is the knuckle housings (0.091 m), 11 mm beyond the palm surface; the benchmark's clearances start there.
    """
    reach = _reach(BenchObject("sphere", (0.01,), 0.1), spread, opening)
    q = reach.hand.configuration(F1_spread=spread, F2_spread=spread)
    pin.updateGeometryPlacements(reach.hand.model, reach.model_data, reach.geometry, reach.data, q)
    shapes = reach.geometry.geometryObjects
    return max(
        _deepest_corner(item.geometry, reach.data.oMg[i])
        for i, item in enumerate(shapes)
        if not any(part in item.name for part in ("proximal", "distal"))
    )


@functools.lru_cache(maxsize=256)
def grasp_offset(item: BenchObject, spread: float, clearance: float, opening: float) -> float:
    """The object's offset [m] along the hand's y axis (towards F3) at which F3 and F1 touch it at the same angle.

    ``clearance``: the knuckles (:func:`hand_depth`) to the object's top [m]; ``opening``: the pre-shape's
    proximal angle [rad].  Computed once per process for each set of arguments.
    """
    reach = _reach(item, spread, opening)
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


def stand_clearance(item: BenchObject, spread: float, clearance: float, opening: float) -> float:
    """The fingers' least distance [m] from the stand up to where each first touches the object (negative: apart).

    The hand as :func:`grasp_offset` places it for ``clearance`` [m] (knuckles to the object's top); each finger
    closes from ``opening`` [rad] with the distal at a third of the proximal (before the TorqueSwitch breaks away),
    in :data:`_SWEEP` steps, to its first touch of the object (bisected).  A finger that never touches the object
    counts as ``-inf``: the hand does not grasp it from there.
    """
    reach = _reach(item, spread, opening)
    offset = grasp_offset(item, spread, clearance, opening)
    centre = np.array([0.0, offset, hand_depth(spread, opening) + clearance + item.half_extents[2]])
    stand = coal.Box(*(2 * item.half_extents[:2]), STAND_HEIGHT)
    stand_centre = centre + np.array([0.0, 0.0, item.half_extents[2] + 0.5 * STAND_HEIGHT])  # below it: hand +z
    nearest = np.inf
    for finger in reach.hand.fingers:
        angles = np.arange(opening, reach.closed + 1e-9, _SWEEP)
        touching = [reach.distance(finger, float(a), centre) <= 0.0 for a in angles]
        if not any(touching) or touching[0]:
            return -np.inf
        k = int(np.argmax(touching))
        low, high = float(angles[k - 1]), float(angles[k])
        for _ in range(20):
            middle = 0.5 * (low + high)
            low, high = (middle, high) if reach.distance(finger, middle, centre) > 0.0 else (low, middle)
        swept = [*angles[:k], high]  # the stand is met on the way, or at the touch
        nearest = min(nearest, *(reach.distance(finger, float(a), stand_centre, stand) for a in swept))
    return nearest


def grasp_clearance(item: BenchObject, spread: float, nominal: float, opening: float, highest: float = 0.06) -> float:
    """The knuckles' height [m] above the object's top: ``nominal``, raised only if the fingers would meet the stand.

    ``nominal`` if there every finger, closing, touches the object before the stand (:func:`stand_clearance` at
    least 0, however small the gap); otherwise the lowest height on a 2 mm grid above ``nominal`` up to ``highest``
    at which :func:`stand_clearance` is at least :data:`STAND_MARGIN`, and ``nominal`` if there is none (the fingers
    meet the stand at every height, or miss the object: the 3 cm flat box at spread 0, whose side the closing
    fingertips cross below its bottom up to 44 mm and not at all above).
    """
    if stand_clearance(item, spread, nominal, opening) >= 0.0:
        return nominal
    for clearance in np.arange(nominal + 0.002, highest + 1e-9, 0.002):
        if stand_clearance(item, spread, float(clearance), opening) >= STAND_MARGIN:
            return float(clearance)
    return nominal


__all__ = ["STAND_HEIGHT", "STAND_MARGIN", "grasp_clearance", "grasp_offset", "hand_depth", "stand_clearance"]
