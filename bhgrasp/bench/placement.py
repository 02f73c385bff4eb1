"""Where the grasp benchmark puts the hand over an object: rules of the object's shape and the hand's geometry.

**Along the F3 axis (hand y)**, :func:`grasp_offset`:

- a sphere or an upright cylinder, at a spread where F1's and F2's closing planes meet inside the hand
  (:func:`closing_planes_meet`; the three-finger spread of 60 deg puts them 14.4 mm towards F3): its axis there.
  Each finger then presses towards the axis within its own closing plane, which holds the finger's spread axis, so
  the back-drivable spread carries no torque.  At the former 0.45 rad spread the planes met 52 mm off the axis; the
  squeeze opened the spread 0.1 rad, and a 1.5 N push closed it again and let the 45 mm ball out.  F3, the nearer,
  touches first and pushes the object the few millimetres to F1 and F2;
- otherwise (a box, F1 and F2 facing F3 on parallel planes), where F3's touch angle equals F1's, so that the fingers,
  closing at one rate, arrive together: bisection, each touch angle itself a bisection on coal's distance between
  the finger's collision shapes and the object.

**The height**, :func:`grasp_clearance`: the lowest, on a 2 mm grid from the knuckles on the object's top, at which
every finger, closing from the pre-shape, first touches the object's side (:func:`grasp_ready`: not a face looking
up, :func:`faces_up`; in a precision grasp with its fingertip) and touches it before the stand
(:func:`stand_clearance`).  The object stands on a stand of its own footprint (:func:`~bhgrasp.bench.trial.setup`),
whose sides continue the object's: with the knuckles on the 5 cm box's top the closing fingers pass beside the box and
meet the stand first (coal: 17-30 mm deep at the angle they would reach the box; simulated, the distal links pressed
the stand with 122-227 N while the knuckles held the box with 20 N); with the knuckles on the can's top, F3's inner
link lands on its rim and presses it onto its stand.  A low object can leave no height (the 3 cm flat box: its top
until 18 mm, then its stand).
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

    def first_touch(self, finger: str, centre: np.ndarray) -> tuple[str, np.ndarray] | None:
        """The link of ``finger`` that touches the object first, and where on the object (its frame [m]).

        ``None`` if the finger closes without touching it.
        """
        angle = self.touch(finger, centre)
        if angle >= self.closed:
            return None
        q = self.configuration(angle)
        pin.updateGeometryPlacements(self.hand.model, self.model_data, self.geometry, self.data, q)
        placement = coal.Transform3s(_FLIP, centre)
        nearest = (np.inf, "", np.zeros(3))
        for i in self.shapes[finger]:
            result = coal.DistanceResult()
            shape = self.geometry.geometryObjects[i]
            gap = coal.distance(
                shape.geometry, coal_transform(self.data.oMg[i]), self.shape, placement, self._request, result
            )
            if gap < nearest[0]:
                nearest = (gap, shape.name, _FLIP.T @ (np.asarray(result.getNearestPoint2()) - centre))
        return nearest[1], nearest[2]

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


@functools.lru_cache(maxsize=64)
def closing_planes_meet(spread: float) -> float | None:
    """Where [m, hand y] F1's and F2's closing planes cross the hand's y axis, F3's plane, at ``spread`` [rad].

    A finger closes in the vertical plane normal to its proximal joint's axis; a force in that plane has no moment
    about the finger's spread axis, which lies in it.  ``None`` where the planes are parallel (spread 0) or cross
    outside the hand, behind the spread axes or beyond F3's knuckle (spread below 0.45 rad on the BH8-280).
    """
    hand = bh.BarrettHand()
    data = hand.model.createData()
    pin.forwardKinematics(hand.model, data, hand.configuration(F1_spread=spread, F2_spread=spread))
    proximal = data.oMi[hand.model.getJointId("F1_proximal")]
    (x, y), (ax, ay) = proximal.translation[:2], proximal.rotation[:2, 2]  # the joint's origin and axis, hand frame
    spread_axis = data.oMi[hand.model.getJointId("F1_spread")].translation[1]
    knuckle = data.oMi[hand.model.getJointId("F3_proximal")].translation[1]
    if abs(ay) < 1e-9:
        return None
    meet = float(y + x * ax / ay)  # the point (0, meet) of the plane (p - origin) . axis = 0
    return meet if spread_axis <= meet < knuckle else None


@functools.lru_cache(maxsize=256)
def grasp_offset(item: BenchObject, spread: float, clearance: float, opening: float) -> float:
    """The object's offset [m] along the hand's y axis (towards F3): where the closing planes meet, or the fingers.

    Where F1's and F2's closing planes meet, or else where F3 and F1 touch it at the same angle.
    A sphere or an upright cylinder, pressed by each finger towards its axis, loads the back-drivable spread with no
    torque when that axis lies in F1's and F2's closing planes (:func:`closing_planes_meet`): there, where they
    meet.  A box's faces, F1 and F2 facing F3 at spread 0 (parallel planes), leave the offset free: there the
    fingers should arrive together, where F3's touch angle equals F1's.  ``clearance``: the knuckles
    (:func:`hand_depth`) to the object's top [m]; ``opening``: the pre-shape's proximal angle [rad].  Computed once
    per process for each set of arguments.
    """
    meet = closing_planes_meet(spread) if item.kind != "box" else None
    if meet is not None:
        return meet
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


def faces_up(item: BenchObject, point: np.ndarray, tolerance: float = 1e-4) -> bool:
    """Whether the object's surface at ``point`` (its frame [m]) faces up.

    The top face or rim of a box or cylinder, a sphere above its equator: a closing finger that lands there presses
    the object onto its stand.
    """
    if item.kind == "sphere":
        return bool(point[2] > tolerance)
    return bool(point[2] >= item.half_extents[2] - tolerance)


def grasp_centre(item: BenchObject, spread: float, clearance: float, opening: float) -> np.ndarray:
    """The object's centre [m] in the hand frame (z down the palm's normal) where :func:`grasp_offset` puts it."""
    depth = hand_depth(spread, opening) + clearance + item.half_extents[2]
    return np.array([0.0, grasp_offset(item, spread, clearance, opening), depth])


def touch_angles(item: BenchObject, spread: float, clearance: float, opening: float) -> dict[str, float]:
    """Each finger's proximal angle [rad] at its first touch, the hand placed as :func:`grasp_centre` says.

    The finger's closed limit (2.4 rad) for a finger that closes without touching the object.
    """
    reach = _reach(item, spread, opening)
    centre = grasp_centre(item, spread, clearance, opening)
    return {finger: reach.touch(finger, centre) for finger in reach.hand.fingers}


def first_touches(item: BenchObject, spread: float, clearance: float, opening: float) -> dict | None:
    """Each finger's first touch of the object, ``finger -> (link, point)`` (the object's frame [m]).

    The hand as :func:`grasp_offset` places it for ``clearance`` [m]; ``None`` if a finger closes without touching
    the object.
    """
    reach = _reach(item, spread, opening)
    centre = grasp_centre(item, spread, clearance, opening)
    touches = {finger: reach.first_touch(finger, centre) for finger in reach.hand.fingers}
    return None if any(t is None for t in touches.values()) else touches


def grasp_ready(item: BenchObject, spread: float, clearance: float, opening: float, grasp: str) -> bool:
    """Whether every finger, closing, first touches the object's side, not a face looking up (:func:`faces_up`).

    In a ``precision`` grasp each must touch it first with its distal link (the fingertip).
    """
    touches = first_touches(item, spread, clearance, opening)
    if touches is None:
        return False
    return all(
        not faces_up(item, point) and (grasp != "precision" or "distal" in link) for link, point in touches.values()
    )


@functools.lru_cache(maxsize=256)
def grasp_clearance(
    item: BenchObject, spread: float, grasp: str, opening: float, highest: float = 0.06
) -> float | None:
    """The knuckles' height [m] above the object's top for a ``grasp`` ('power' or 'precision'), by one rule.

    The lowest height on a 2 mm grid from the knuckles on the object's top (0) up to ``highest`` at which, closing
    from ``opening`` [rad]:

    - every finger first touches the object's side, not its top face or a sphere above the equator (a finger that
      lands there presses the object onto its stand), and in a precision grasp with its fingertip
      (:func:`grasp_ready`);
    - every finger touches the object before the stand (:func:`stand_clearance` at least 0 on the object's top,
      :data:`STAND_MARGIN` once raised).

    ``None`` if no height qualifies; computed once per process for each set of arguments.
    """
    for clearance in np.arange(0.0, highest + 1e-9, 0.002):
        clearance = float(clearance)
        margin = 0.0 if clearance == 0.0 else STAND_MARGIN
        if not grasp_ready(item, spread, clearance, opening, grasp):
            continue
        if stand_clearance(item, spread, clearance, opening) >= margin:
            return clearance
    return None


__all__ = [
    "STAND_HEIGHT",
    "STAND_MARGIN",
    "closing_planes_meet",
    "faces_up",
    "first_touches",
    "grasp_centre",
    "grasp_clearance",
    "grasp_offset",
    "grasp_ready",
    "hand_depth",
    "stand_clearance",
    "touch_angles",
]
