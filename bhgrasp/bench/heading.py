"""Where the open hand starts over a trial's object, and which way it faces among neighbours.

:func:`hand_base`: the mounted hand's base, palm down at the grasp height of the rules of
:mod:`~bhgrasp.bench.height` and :mod:`~bhgrasp.bench.placement` (or, where they find none, palm sideways in a side
pinch, :mod:`~bhgrasp.bench.side`), ``approach`` back along its way in, turned by ``heading`` about the object's
vertical axis.  Turning about that axis leaves the grasp of an upright primitive as it is when the
object is symmetric about it: any heading for a sphere or an upright cylinder, a half turn for a box or a box's mesh
(:func:`headings`).  Any other mesh keeps heading 0: its facets (a meshed cylinder's 64 sides, an icosphere) or its
shape need not share its plan's symmetry.  The trial's shake turns with the hand
(:func:`~bhgrasp.bench.trial.shake_force`), so a turned trial is the same test.

Among neighbours (:mod:`~bhgrasp.bench.neighbours`) the hand takes the first of these headings, in order of size,
whose :func:`heading_clearance` is at least :data:`CLEAR`; if none is, the clearest (:func:`clearest_heading`).  A
rule of the hand's geometry and the neighbours' poses: :data:`CLEAR` and :data:`HEADING_STEP` were set before any trial
ran with them, not chosen on the benchmark's trials.  The way down is checked from
:data:`~bhgrasp.bench.protocol.APPROACH`; where no heading is clear the start may rise higher
(:func:`~bhgrasp.bench.neighbours.raised`), and that stretch is not checked.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Sequence

import coal
import numpy as np
import pinocchio as pin

from bhgrasp._validation import as_real
from bhgrasp.bench.height import DESCENT_STEP, SWEEP
from bhgrasp.bench.objects import MESHED
from bhgrasp.bench.placement import grasp_offset
from bhgrasp.bench.protocol import APPROACH, Trial
from bhgrasp.bench.reach import ORIENTATIONS, hand_depth
from bhgrasp.bench.side import approach_of, closing_fingers, top_grasp, trial_opening, trial_reach, way_in
from bhgrasp.grasp.probes import coal_transform
from bhgrasp.model.objects import RigidObject

CLEAR = 0.01  # [m] the least distance to every neighbour on the way down and while closing that takes a heading
HEADING_STEP = math.radians(15.0)  # [rad] the headings tried for a round object


def hand_base(trial: Trial, approach: float = 0.0, heading: float = 0.0) -> pin.SE3:
    """The hand base (world) ``approach`` [m] back along its way in from the trial's grasp, turned ``heading`` [rad].

    From above (:func:`~.side.approach_of`): palm down, the fingers together at the grasp's offset along F3's axis
    (:func:`~.placement.grasp_offset`), the knuckles the height rule's clearance above the object's top
    (:func:`~.side.top_grasp`, at its opening), ``approach`` above.  In a side pinch: palm sideways
    (:data:`~.reach.SIDEWAYS`), the object where :func:`~.side.side_centre` puts it, ``approach`` back along the
    palm's normal.  The object's axis is the world z axis, the heading a turn about it.  A heading other than 0 or a
    half turn assumes what the object stands on is symmetric under it: a table, as among neighbours (a round
    object's square stand is not).

    Raises:
        InputError: A non-finite ``approach`` or ``heading``.
    """
    approach, heading = as_real(approach, "approach", False), as_real(heading, "heading", False)
    item, spread = trial.item, trial.preshape_spread
    if approach_of(trial) == "side":
        _, centre = trial_reach(trial)
        rotation = ORIENTATIONS["side"]
        origin = np.array([0.0, 0.0, item.half_extents[2]]) - rotation @ centre - approach * way_in(trial)
        base = pin.SE3(rotation, origin)
    else:
        opening, clearance = top_grasp(trial)  # one rule for both grasps
        grasp_height = 2 * item.half_extents[2] + clearance + hand_depth(spread, opening)
        rotation = pin.rpy.rpyToMatrix(math.pi, 0.0, 0.0)  # palm down
        offset = np.array([0.0, grasp_offset(item, spread, clearance, opening), 0.0])
        base = pin.SE3(rotation, np.array([0.0, 0.0, grasp_height + approach]) - rotation @ offset)
    if heading == 0.0:
        return base
    return pin.SE3(pin.rpy.rpyToMatrix(0.0, 0.0, heading), np.zeros(3)) * base


def headings(trial: Trial) -> list[float]:
    """The headings [rad] that leave the trial's grasp as it is, by size: 0, +15 deg, -15 deg, ... (module doc)."""
    item = trial.item
    if item.kind == "box" and item.mesh in ("", MESHED):  # a box's hull is symmetric under a half turn too
        return [0.0, math.pi]
    if item.mesh:
        return [0.0]
    steps = round(math.pi / HEADING_STEP)
    turns = [0.0]
    for k in range(1, steps):
        turns += [k * HEADING_STEP, -k * HEADING_STEP]
    return [*turns, math.pi]


def heading_clearance(trial: Trial, neighbours: Sequence[RigidObject], heading: float) -> float:
    """The hand's least distance [m] from the neighbours at ``heading`` (negative: it would press into one).

    Over the open hand's way down from :data:`~bhgrasp.bench.protocol.APPROACH` above its grasp (every
    :data:`~bhgrasp.bench.height.DESCENT_STEP`, every collision shape of the hand) and each finger's close from the
    trial's opening to its first touch of the object (the finger's links, in :data:`~bhgrasp.bench.height.SWEEP`
    steps; coal's distances, the distal at a third of the proximal as before the TorqueSwitch breaks away).  The
    neighbours where they rest.
    """
    shapes = [(shape, coal_transform(body.pose)) for body in neighbours for shape in body.collision_shapes()]
    request, nearest, bases = coal.DistanceRequest(), math.inf, {}
    for height, placed in hand_poses(trial):
        base = bases.get(height)
        if base is None:
            base = bases[height] = hand_base(trial, height, heading)
        for link, placement in placed:
            frame = coal_transform(base * placement)
            for shape, where in shapes:
                nearest = min(nearest, coal.distance(link, frame, shape, where, request, coal.DistanceResult()))
    return nearest


@functools.lru_cache(maxsize=64)
def hand_poses(trial: Trial) -> tuple[tuple[float, tuple[tuple[coal.CollisionGeometry, pin.SE3], ...]], ...]:
    """The hand poses :func:`heading_clearance` measures, whatever the heading, once per trial and process.

    ``(distance back along the way in [m], ((a hand shape, its placement in the hand base frame), ...))``: the open
    hand every :data:`~bhgrasp.bench.height.DESCENT_STEP` on its way in, all its shapes; each finger's links in
    :data:`~bhgrasp.bench.height.SWEEP` steps of its close to its first touch of the object.
    """
    reach, centre = trial_reach(trial)
    opening = trial_opening(trial)
    every = list(range(len(reach.geometry.geometryObjects)))
    poses: list[tuple[float, float, list[int]]] = []  # (back along the way in, proximal angle, the shapes)
    for height in np.arange(0.0, APPROACH + 1e-9, DESCENT_STEP):
        poses.append((float(height), opening, every))
    for finger in closing_fingers(trial):  # a side pinch's F3 stays open
        touch = reach.touch(finger, centre)
        for angle in [*np.arange(opening + SWEEP, touch, SWEEP), touch]:
            poses.append((0.0, float(angle), reach.shapes[finger]))
    placed = []
    for height, angle, measured in poses:
        q = reach.configuration(angle)
        pin.updateGeometryPlacements(reach.hand.model, reach.model_data, reach.geometry, reach.data, q)
        shapes = tuple((reach.geometry.geometryObjects[i].geometry, pin.SE3(reach.data.oMg[i])) for i in measured)
        placed.append((height, shapes))
    return tuple(placed)


def clearest_heading(trial: Trial, neighbours: Sequence[RigidObject]) -> tuple[float, float]:
    """(heading [rad], its clearance [m]): the first of :func:`headings` clear by :data:`CLEAR`, else the clearest."""
    best = (0.0, -math.inf)
    for heading in headings(trial):
        clearance = heading_clearance(trial, neighbours, heading)
        if clearance >= CLEAR:
            return heading, clearance
        if clearance > best[1]:
            best = (heading, clearance)
    return best


__all__ = [
    "CLEAR",
    "DESCENT_STEP",
    "HEADING_STEP",
    "clearest_heading",
    "hand_base",
    "hand_poses",
    "heading_clearance",
    "headings",
]
