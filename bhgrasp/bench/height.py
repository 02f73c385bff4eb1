"""How high the grasp benchmark puts the hand over an object: one rule for both grasps.

:func:`grasp_clearance`: the lowest height, on a 2 mm grid from the knuckles on the object's top, at which every
finger, closing from the pre-shape, first touches the object's side (:func:`grasp_ready`: not a face looking up,
:func:`faces_up`; in a precision grasp with its fingertip) and touches it before the stand (:func:`stand_clearance`).
The object stands on a stand of its own footprint (:func:`~bhgrasp.bench.trial.setup`), whose sides continue the
object's: with the knuckles on the 5 cm box's top the closing fingers pass beside the box and meet the stand first
(coal: 17-30 mm deep at the angle they would reach the box; simulated, the distal links pressed the stand with
122-227 N while the knuckles held the box with 20 N); with the knuckles on the can's top, F3's inner link lands on its
rim and presses it onto its stand.  A low or small object can leave no height (the 3 cm flat box: its top until 18 mm,
then its stand).
"""

from __future__ import annotations

import functools

import coal
import numpy as np

from bhgrasp.bench.objects import BenchObject
from bhgrasp.bench.placement import grasp_centre
from bhgrasp.bench.reach import reach_of

STAND_HEIGHT = 0.2  # [m] the stand under the object (its top the table plane z = 0)
TABLE_REACH = 0.2  # [m] a trial among neighbours: the table around the stand reaches this far from its axis in x, y
STAND_MARGIN = 0.003  # [m] the fingers' least distance from the stand when they touch the object (~3x the contact's
# 1 mm penetration under the power close)
SWEEP = 0.01  # [rad] the close's proximal steps in :func:`stand_clearance`
DESCENT_STEP = 0.005  # [m] the open hand's heights checked on its way down (bench.opening, bench.heading)


def support_box(item: BenchObject, table: bool = False) -> coal.Box:
    """What the object stands on, as a coal box: its stand (its footprint), or the table :data:`TABLE_REACH` around."""
    return coal.Box(*((2 * TABLE_REACH,) * 2 if table else 2 * item.half_extents[:2]), STAND_HEIGHT)


def stand_clearance(item: BenchObject, spread: float, clearance: float, opening: float, table: bool = False) -> float:
    """The fingers' least distance [m] from the stand up to where each first touches the object (negative: apart).

    ``table``: the stand is flush with a table :data:`TABLE_REACH` around (a trial among neighbours): its top is the
    table's.

    The hand as :func:`~bhgrasp.bench.placement.grasp_centre` places it for ``clearance`` [m] (knuckles to the
    object's top); each finger closes from ``opening`` [rad] with the distal at a third of the proximal (before the
    TorqueSwitch breaks away), in :data:`SWEEP` steps, to its first touch of the object (bisected).  A finger that
    never touches the object counts as ``-inf``: the hand does not grasp it from there.
    """
    reach = reach_of(item, spread, opening)
    centre = grasp_centre(item, spread, clearance, opening)
    stand = support_box(item, table)
    stand_centre = centre + np.array([0.0, 0.0, item.half_extents[2] + 0.5 * STAND_HEIGHT])  # below it: hand +z
    nearest = np.inf
    for finger in reach.hand.fingers:
        angles = np.arange(opening, reach.closed + 1e-9, SWEEP)
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


def first_touches(
    item: BenchObject, spread: float, clearance: float, opening: float
) -> dict[str, tuple[str, np.ndarray]] | None:
    """Each finger's first touch of the object, ``finger -> (link, point)`` (the object's frame [m]).

    The hand as :func:`~bhgrasp.bench.placement.grasp_centre` places it for ``clearance`` [m]; ``None`` if a finger
    closes without touching the object.
    """
    reach = reach_of(item, spread, opening)
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
    item: BenchObject, spread: float, grasp: str, opening: float, highest: float = 0.06, table: bool = False
) -> float | None:
    """The knuckles' height [m] above the object's top for a ``grasp`` ('power' or 'precision'), by one rule.

    The lowest height on a 2 mm grid from the knuckles on the object's top (0) up to ``highest`` at which, closing
    from ``opening`` [rad]:

    - every finger first touches the object's side, not its top face or a sphere above the equator (a finger that
      lands there presses the object onto its stand), and in a precision grasp with its fingertip
      (:func:`grasp_ready`);
    - every finger touches the object before the stand (:func:`stand_clearance` at least 0 on the object's top,
      :data:`STAND_MARGIN` once raised).

    ``table``: the stand flush with a table around it (:func:`stand_clearance`).  ``None`` if no height qualifies;
    computed once per process for each set of arguments.
    """
    for clearance in np.arange(0.0, highest + 1e-9, 0.002):
        clearance = float(clearance)
        margin = 0.0 if clearance == 0.0 else STAND_MARGIN
        if not grasp_ready(item, spread, clearance, opening, grasp):
            continue
        if stand_clearance(item, spread, clearance, opening, table) >= margin:
            return clearance
    return None


__all__ = [
    "DESCENT_STEP",
    "STAND_HEIGHT",
    "STAND_MARGIN",
    "SWEEP",
    "TABLE_REACH",
    "faces_up",
    "first_touches",
    "grasp_clearance",
    "grasp_ready",
    "stand_clearance",
    "support_box",
]
