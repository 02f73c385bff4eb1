"""Where the grasp benchmark puts the hand over an object: rules of the object's shape and the hand's geometry.

**Along the F3 axis (hand y)**, :func:`grasp_offset`:

- a sphere or an upright cylinder, at a spread where F1's and F2's closing planes meet inside the hand
  (:func:`closing_planes_meet`; the three-finger spread of 60 deg puts them 14.4 mm towards F3): its axis there.
  Each finger then presses towards the axis within its own closing plane, which holds the finger's spread axis, so
  the back-drivable spread carries no torque.  At the former 0.45 rad spread the planes met about 60 mm off the
  axis; the squeeze opened the spread 0.1 rad, and a 1.5 N push closed it again and let the 45 mm ball out.  F3,
  the nearer, starts closing later so that the three arrive together (:mod:`~bhgrasp.bench.closing`);
- otherwise (a box, F1 and F2 facing F3 on parallel planes), where F3's touch angle equals F1's, so that the fingers,
  closing at one rate, arrive together: bisection, each touch angle itself a bisection on coal's distance between
  the finger's collision shapes and the object.

**How high**: :mod:`~bhgrasp.bench.height`.  Both build on :mod:`~bhgrasp.bench.reach` (touch angles by coal).
"""

from __future__ import annotations

import functools

import numpy as np
import pinocchio as pin

import bhgrasp as bh
from bhgrasp.bench.objects import BenchObject
from bhgrasp.bench.reach import hand_depth, reach_of


@functools.lru_cache(maxsize=64)
def closing_planes_meet(spread: float) -> float | None:
    """Where [m, hand y] F1's and F2's closing planes cross the hand's y axis, F3's plane, at ``spread`` [rad].

    A finger closes in the vertical plane normal to its proximal joint's axis; a force in that plane has no moment
    about the finger's spread axis, which lies in it.  ``None`` where the planes are parallel (spread 0) or cross
    outside the hand, behind the spread axes or beyond F3's knuckle (on the BH8-280 below atan(25/50) = 0.46 rad).
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
    reach = reach_of(item, spread, opening)
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


def grasp_centre(item: BenchObject, spread: float, clearance: float, opening: float) -> np.ndarray:
    """The object's centre [m] in the hand frame (z down the palm's normal) where :func:`grasp_offset` puts it."""
    depth = hand_depth(spread, opening) + clearance + item.half_extents[2]
    return np.array([0.0, grasp_offset(item, spread, clearance, opening), depth])


def touch_angles(item: BenchObject, spread: float, clearance: float, opening: float) -> dict[str, float]:
    """Each finger's proximal angle [rad] at its first touch, the hand placed as :func:`grasp_centre` says.

    The finger's closed limit (2.4 rad) for a finger that closes without touching the object.
    """
    reach = reach_of(item, spread, opening)
    centre = grasp_centre(item, spread, clearance, opening)
    return {finger: reach.touch(finger, centre) for finger in reach.hand.fingers}


__all__ = ["closing_planes_meet", "grasp_centre", "grasp_offset", "touch_angles"]
