"""How far the grasp benchmark opens the hand over an object: the pre-shape, or wider where the open hand meets it.

The hand comes down over an object with every finger at :data:`~bhgrasp.bench.protocol.PRESHAPE` (proximal 0.8 rad,
the distal at a third).  A large object reaches into that open hand: a ball of 70 mm radius meets F3's open fingertip,
3.5-7.7 mm deep, at every height of the height rule's grid at which F1 and F2 reach it (its top up to 40 mm), so no
top-down height qualifies there (:func:`~bhgrasp.bench.height.stand_clearance` refuses a finger that touches the
object before it closes).

The rule (:func:`top_down`), the same for both grasps: at the pre-shape wherever the height rule finds a height there.
Where it finds none and the open hand meets the object on its way down (:func:`way_in_gap`: the open fingers' least
distance from the object over the last :data:`~bhgrasp.bench.protocol.APPROACH` of the descent, with the knuckles on
its top, below :data:`~bhgrasp.bench.height.STAND_MARGIN`), the fingers open further,
:data:`~bhgrasp.bench.height.SWEEP` at a time, to the first opening at which they clear it by ``STAND_MARGIN`` there
(:func:`widened`; at most to the proximal joints' lower limit), and the height rule runs again at that opening; the
height it finds must leave the open fingers ``STAND_MARGIN`` off the object all the way down to it too.  The search
stops at that first clearing opening: a closing finger passes the same angles from any wider one (on the 70 mm ball
its first touches are the same from 0.4 rad, tested).  The margin and the steps are the height and heading rules'.
Where the rule came from, and which object sets test it: :mod:`~bhgrasp.bench.protocol`.
"""

from __future__ import annotations

import functools

import numpy as np

from bhgrasp.bench.height import DESCENT_STEP, STAND_MARGIN, SWEEP, grasp_clearance
from bhgrasp.bench.objects import BenchObject
from bhgrasp.bench.placement import grasp_centre
from bhgrasp.bench.protocol import APPROACH, PRESHAPE
from bhgrasp.bench.reach import reach_of


def way_in_gap(item: BenchObject, spread: float, clearance: float, opening: float) -> float:
    """The open fingers' least distance [m] from the object on the hand's way down to ``clearance`` (negative: in it).

    Every finger's links at proximal ``opening`` [rad] (the distal at a third), the hand placed as
    :func:`~bhgrasp.bench.placement.grasp_centre` puts it for ``clearance`` [m] and up to
    :data:`~bhgrasp.bench.protocol.APPROACH` above, every :data:`~bhgrasp.bench.height.DESCENT_STEP` (coal's
    distances).
    """
    reach = reach_of(item, spread, PRESHAPE)  # its distances take the fingers' angle: one Reach for every opening
    centre = grasp_centre(item, spread, clearance, opening)
    return min(
        reach.distance(finger, opening, centre + np.array([0.0, 0.0, back]))  # higher: the object further along z
        for back in np.arange(0.0, APPROACH + 1e-9, DESCENT_STEP)
        for finger in reach.hand.fingers
    )


@functools.lru_cache(maxsize=256)
def top_down(item: BenchObject, spread: float, grasp: str, table: bool = False) -> tuple[float, float] | None:
    """(opening [rad], clearance [m]) of the top-down grasp the rules find (module docstring), or ``None``.

    The clearance is the knuckles' height above the object's top (:func:`~bhgrasp.bench.height.grasp_clearance` at
    that opening); computed once per process for each set of arguments.
    """
    clearance = grasp_clearance(item, spread, grasp, PRESHAPE, table=table)
    if clearance is not None:
        return PRESHAPE, clearance
    opening = widened(item, spread)
    if opening is None:
        return None
    clearance = grasp_clearance(item, spread, grasp, opening, table=table)
    if clearance is None or way_in_gap(item, spread, clearance, opening) < STAND_MARGIN:
        return None
    return opening, clearance


@functools.lru_cache(maxsize=256)
def widened(item: BenchObject, spread: float) -> float | None:
    """The opening [rad] at which the open fingers clear the object, where they meet it at the pre-shape.

    ``None`` where the open hand clears the object at the pre-shape with the knuckles on its top
    (:func:`way_in_gap` at least :data:`~bhgrasp.bench.height.STAND_MARGIN`), or where no opening down to the
    proximal joints' lower limit does; else the first, :data:`~bhgrasp.bench.height.SWEEP` at a time, that does.
    """
    if way_in_gap(item, spread, 0.0, PRESHAPE) >= STAND_MARGIN:
        return None
    hand = reach_of(item, spread, PRESHAPE).hand
    widest = max(float(hand.lower[hand.joint_index(f"{finger}_proximal")]) for finger in hand.fingers)
    for step in range(1, int((PRESHAPE - widest) / SWEEP + 1e-9) + 1):
        opening = round(PRESHAPE - step * SWEEP, 9)
        if way_in_gap(item, spread, 0.0, opening) >= STAND_MARGIN:
            return opening
    return None


__all__ = ["top_down", "way_in_gap", "widened"]
