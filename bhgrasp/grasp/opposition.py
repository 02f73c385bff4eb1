"""Grasp synthesis for any hand: fingertip pads opposed across the object, placed by IK from sampled reach.

:func:`~bhgrasp.grasp.synthesis.grasp_candidates` casts each finger's line of approach, which assumes the BH8-280's
layout (fingers that flex in a plane, spread joints named ``*spread*``).  :func:`opposed_grasps` assumes nothing of
the hand's layout (the Allegro's thumb, a gripper written in a notebook):

1. **reach**: ``samples`` configurations drawn uniformly inside the joint limits (seeded) give each finger a cloud of
   fingertip positions and the joint values that reach them (a k-d tree per finger);
2. **layouts**: a grasp axis ``d`` (``directions`` horizontal directions, and the object's horizontal axes), a height
   along world z, and a layout direction ``u`` in the plane normal to ``d`` (``tilts`` angles); the grasping fingers
   split into two sides, each side's fingers in a row along ``u``, ordered by their knuckles (first joints) along
   ``u`` and spaced as their knuckles are, the row centred or shifted to put one finger level with its knuckle (a
   finger that flexes in a plane reaches only that plane); each contact is the first point of the object along a
   line parallel to ``-d`` (or ``+d``, the other side), moved until the pad's centre lies on the finger's slot (a
   curved face tilts the normal, and the pad with it) (sphere tracing on coal distances, :data:`TOLERANCE`);
3. **reachability**: every pad centre (contact + pad radius x outward normal) must lie within ``reach_tolerance`` of
   its finger's cloud; the IK (:func:`~bhgrasp.model.hand_ik.ik`, 1e-6 m) starts from the nearest samples' joint
   values, the idle fingers at rest (zero, clipped to the limits);
4. **the same checks as the approach-line search**: the other collision shapes keep ``clearance`` from the object, the
   grasping joints ``joint_margin`` from their limits, each contact Jacobian ``singularity_margin`` from singular,
   the contacts ``edge_margin`` from an edge, the pads lift the object by ``lift`` without sliding; then force
   closure, the Ferrari-Canny epsilon and the weight test rank the candidates
   (:class:`~bhgrasp.grasp.synthesis.GraspCandidate`);
5. **pushing**: a pad must be able to move along its normal to within the friction cone's half-angle (J J^+ n within
   atan(mu) of n): a finger that flexes in a plane, on a face tilted out of that plane, pushes the object sideways
   and slides (measured: three planar fingers on a 30 mm can, pads 39 deg off their planes, lifted it 11 mm off
   the request with 27-29 sliding samples);
6. **approach**: the pre-grasp configuration has the pads ``standoff`` out along the normals, the approach's target
   ``closing`` into the object (both by IK from the contact configuration; for a finger that flexes in a plane,
   along the normal's part in that plane, J J^+ n): a joint-space approach between them closes each pad onto its
   contact.

The pads are the spheres centred on the fingertip frames in the hand's collision model (the Allegro's 12 mm tips,
the BH8-280's 10 mm pads).  World frame, metres and radians.
"""

from __future__ import annotations

import itertools
from collections import Counter
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from typing import Any

import coal
import numpy as np
import pinocchio as pin
from scipy.spatial import cKDTree

from bhgrasp._validation import as_positive, as_vector
from bhgrasp.errors import InputError, UnreachableError
from bhgrasp.grasp.probes import HandClearance, ObjectProbe
from bhgrasp.grasp.synthesis import (
    GraspCandidate,
    _default_heights,
    _finger_sets,
    _flexing,
    _least_lever,
    _lifts,
    rate_grasp,
)
from bhgrasp.model.couplings import refuse_couplings
from bhgrasp.model.hand import Hand
from bhgrasp.model.hand_ik import ik

TOLERANCE = 1e-5  # [m] how close to the surface a traced line stops
PAD_ITERATIONS = 40  # line moves that put a pad centre on its slot (each shrinks the miss by pad / face radius)
SLOT_TOLERANCE = 1e-8  # [m] how far off its slot a pad centre may stay (well inside the IK's 1e-6 m)
SIDES = (1.0, -1.0)


class FingerReach:
    """Where each finger's pad can go: fingertip positions of uniformly drawn configurations, in k-d trees."""

    def __init__(self, hand: Hand, samples: int, rng: np.random.Generator) -> None:
        """Draw ``samples`` configurations inside the limits (world positions of every fingertip at each)."""
        refuse_couplings(hand.couplings, "the opposition search (one IK per finger)")
        self.q = rng.uniform(hand.lower, hand.upper, size=(samples, hand.nq))
        tips = np.array([hand.fingertip_positions(q) for q in self.q])  # (samples, fingers, 3)
        self.trees = {finger: cKDTree(tips[:, k]) for k, finger in enumerate(hand.fingers)}

    def nearest(self, finger: str, point: np.ndarray) -> tuple[float, int]:
        """Distance [m] from ``point`` to the finger's nearest sampled pad position, and that sample's index."""
        distance, index = self.trees[finger].query(point)
        return float(distance), int(index)


def pad_radii(hand: Hand) -> dict[str, float]:
    """Each finger's pad radius [m]: the collision sphere centred on its fingertip frame.

    Raises:
        InputError: A finger has no such sphere (pass ``pad_radius``).
    """
    geometry, model = hand.collision_model(), hand.model
    radii = {}
    for finger, frame_name in hand.fingertip_frames.items():
        frame = model.frames[model.getFrameId(frame_name)]
        for item in geometry.geometryObjects:
            offset = (frame.placement.inverse() * item.placement).translation
            on_tip = item.parentJoint == frame.parentJoint and np.linalg.norm(offset) < 1e-9
            if on_tip and isinstance(item.geometry, coal.Sphere):
                radii[finger] = float(item.geometry.radius)
                break
        else:
            raise InputError(
                f"finger {finger!r} has no collision sphere centred on its fingertip frame {frame_name!r}: pass "
                "`pad_radius` [m], the radius of the pad the fingertip frame is the centre of"
            )
    return radii


def knuckles(hand: Hand, q: np.ndarray) -> dict[str, np.ndarray]:
    """World position [m] of each finger's first joint at ``q`` (where the finger leaves the palm)."""
    refuse_couplings(hand.couplings, "the opposition search (one IK per finger)")
    data = hand.model.createData()
    pin.forwardKinematics(hand.model, data, q)
    placement = hand.base_placement
    return {
        finger: placement.act(data.oMi[hand.model.getJointId(hand.finger_joints(finger)[0])].translation)
        for finger in hand.fingers
    }


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
        if distance < TOLERANCE:
            normal = point - nearest
            return nearest, normal / float(np.linalg.norm(normal))
        t += distance - 0.5 * TOLERANCE  # stop outside, where the nearest point gives the normal
        if t > reach:
            return None
    return None


def opposed_grasps(hand: Hand, item: Any, mu: float = 0.6, **options: Any) -> list[GraspCandidate]:
    """Every candidate the search finds (module docstring), best first; the options are :func:`search`'s."""
    return search(hand, item, mu, **options)[0]


@dataclass(frozen=True)
class Checks:
    """What a candidate must pass (:func:`search`'s arguments of the same names)."""

    mu: float
    clearance: float
    edge_margin: float
    joint_margin: float
    standoff: float
    closing: float
    squeeze: float
    gravity: np.ndarray
    lift: float
    singularity_margin: float

    @property
    def lift_offset(self) -> np.ndarray:
        """The lift as an object twist-displacement (position [m], rotation [rad]): ``lift`` against gravity."""
        return np.concatenate((-self.lift * self.gravity / np.linalg.norm(self.gravity), np.zeros(3)))


def search(
    hand: Hand,
    item: Any,
    mu: float = 0.6,
    fingers: Sequence[str] | None = None,
    directions: int = 8,
    heights: Sequence[float] | None = None,
    tilts: int = 8,
    pad_radius: float | None = None,
    clearance: float = 1.5e-3,
    edge_margin: float = 5e-3,
    joint_margin: float = 0.05,
    standoff: float = 0.02,
    closing: float = 0.008,
    squeeze: float = 5.0,
    gravity: Any = (0.0, 0.0, -9.81),
    lift: float = 0.01,
    singularity_margin: float = 2e-3,
    samples: int = 4000,
    reach_tolerance: float = 0.01,
    rng: int = 0,
) -> tuple[list[GraspCandidate], Counter]:
    """Every candidate the search finds (module docstring), best first, and how many layouts each check rejected.

    Args:
        hand: Any hand (its world frame: the object's pose is in it).
        item: A convex rigid object with ``geometry()``, ``pose`` and ``mass``.
        mu: Friction coefficient of the quality and the weight test.
        fingers: The grasping fingers (default: every subset of two or more).
        directions: Number of horizontal grasp axes, evenly over 180 deg (the object's horizontal axes are added;
            0: those alone, e.g. across a box's faces).
        heights: Heights [m] of the grasp above the object's centre (default: 5 across the middle half).
        tilts: Number of layout directions of a side's row of fingers, evenly over 180 deg in the face.
        pad_radius: Pad radius [m] of every finger (default: each finger's collision sphere, :func:`pad_radii`).
        clearance, edge_margin, joint_margin, squeeze, gravity, lift, singularity_margin: As for
            :func:`~bhgrasp.grasp.synthesis.grasp_candidates`.
        standoff: How far [m] the pre-grasp configuration's pads stand off their contacts along the normals.
        closing: How deep [m] into the object the approach's target puts the pads (the squeeze's preload).
        samples: Configurations drawn for the reach clouds.
        reach_tolerance: How far [m] a pad centre may be from its finger's cloud to be tried by the IK.
        rng: Seed of the draws (same seed, same candidates).
    """
    checks = Checks(
        as_positive(mu, "mu"),
        float(clearance),
        float(edge_margin),
        float(joint_margin),
        as_positive(standoff, "standoff"),
        as_positive(closing, "closing"),
        float(squeeze),
        as_vector(gravity, "gravity", 3),
        float(lift),
        float(singularity_margin),
    )
    sets = _finger_sets(hand, fingers)
    if pad_radius is None:
        radii = pad_radii(hand)
    else:
        radii = dict.fromkeys(hand.fingers, as_positive(pad_radius, "pad_radius"))
    reach = FingerReach(hand, int(as_positive(samples, "samples")), np.random.default_rng(rng))
    placing = Placement(hand, item, radii, reach, float(reach_tolerance))
    shape, pose = item.geometry(), item.pose
    heights = _default_heights(shape, pose) if heights is None else [float(h) for h in heights]
    axes = _grasp_axes(pose, directions)
    candidates, seen, rejected = [], set(), Counter()
    for group in sets:
        for split in _splits(group):
            rows = range(tilts if max(map(len, split)) > 1 else 1)  # one finger a side: no row to tilt
            for axis, height, tilt in itertools.product(axes, heights, rows):
                for placed in placing.layouts(split, axis, height, _layout(axis, tilt, tilts)):
                    if placed is None:
                        rejected["out of reach"] += 1
                        continue
                    points, normals, seed = placed
                    key = (group, tuple(np.round(np.concatenate([points[f] for f in group]), 4)))
                    if key in seen:
                        continue
                    seen.add(key)
                    outcome = placing.check(group, points, normals, seed, height, checks)
                    if isinstance(outcome, str):
                        rejected[outcome] += 1
                    else:
                        candidates.append(outcome)
    candidates.sort(key=lambda c: c.score, reverse=True)
    return candidates, rejected


class Placement:
    """Pads on one object: the contacts of each finger layout (traced once each), and the checks of a placement."""

    def __init__(self, hand: Hand, item: Any, radii: dict[str, float], reach: FingerReach, tolerance: float) -> None:
        """Probe ``item`` (world pose) for ``hand``'s pads of ``radii`` [m], reachable within ``tolerance`` [m]."""
        self.hand, self.item, self.radii, self.reach, self.tolerance = hand, item, radii, reach, tolerance
        self.shape, self.pose = item.geometry(), item.pose
        self.probe, self.shapes = ObjectProbe(self.shape, self.pose), HandClearance(hand)
        self.rest = np.clip(np.zeros(hand.nq), hand.lower, hand.upper)
        self.knuckle = knuckles(hand, self.rest)
        self.span = _bounding_radius(self.shape) + 0.02
        self.centre = self.pose.translation
        self.traced: dict[tuple, tuple | None] = {}
        self.nearest: dict[tuple, tuple[float, int]] = {}

    def layouts(self, split: tuple, axis: np.ndarray, height: float, u: np.ndarray) -> Iterator[tuple | None]:
        """Each shift of the two rows (:func:`_shifts`): the fingers' contacts, normals and IK seed.

        ``None`` where a pad is out of its finger's reach or its line misses the object.
        """
        sides = [_row(row, self.knuckle, u) for row in split]
        for shifts in itertools.product(*(_shifts(side, self.knuckle, self.centre, u) for side in sides)):
            points, normals, seed = {}, {}, self.rest.copy()
            for side, row, shift in zip(SIDES, sides, shifts):
                for finger, offset in row:
                    hit = self.contact(
                        axis, side, height * np.array([0.0, 0.0, 1.0]) + (offset + shift) * u, self.radii[finger]
                    )
                    if hit is None:
                        break
                    distance, index = self.reached(finger, hit)
                    if distance > self.tolerance:
                        break
                    points[finger], normals[finger] = hit
                    joints = self.hand.finger_indices(finger)
                    seed[joints] = self.reach.q[index, joints]
                else:
                    continue
                break
            yield (points, normals, seed) if len(points) == sum(map(len, split)) else None

    def reached(self, finger: str, hit: tuple) -> tuple[float, int]:
        """How far [m] the finger's pad centre on ``hit`` is from its reach cloud, and the nearest sample (cached)."""
        key = (finger, id(hit))  # a traced hit is one object, kept in ``traced``
        if key not in self.nearest:
            self.nearest[key] = self.reach.nearest(finger, hit[0] + self.radii[finger] * hit[1])
        return self.nearest[key]

    def contact(self, axis: np.ndarray, side: float, slot: np.ndarray, radius: float) -> tuple | None:
        """The contact on the ``side`` face along ``axis`` whose pad centre lies on ``slot``, and its outward normal.

        ``slot``: a point [m] of the plane normal to ``axis``, from the object's centre.  ``None`` if the line misses.
        """
        key = (*np.round(axis, 12), side, *np.round(slot, 9), radius)
        if key not in self.traced:
            line, hit = slot.copy(), None
            for _ in range(PAD_ITERATIONS):  # a curved face tilts the normal: move the line so the pad is on slot
                start = self.centre + side * self.span * axis + line
                hit = first_hit(self.probe, start, -side * axis, 2.0 * self.span)
                if hit is None:
                    break
                pad = hit[0] + radius * hit[1] - self.centre
                miss = (pad - (pad @ axis) * axis) - slot
                if np.linalg.norm(miss) < SLOT_TOLERANCE:
                    break
                line -= miss
            self.traced[key] = hit
        return self.traced[key]

    def check(self, group, points, normals, seed, height, checks: Checks) -> GraspCandidate | str:
        """The candidate of these contacts, or the name of the first check it fails."""
        hand, shape, pose, shapes = self.hand, self.shape, self.pose, self.shapes
        outward = np.array([normals[f] for f in group])
        contact_points = np.array([points[f] for f in group])
        pads = {f: points[f] + self.radii[f] * normals[f] for f in group}
        try:
            q = ik(hand, pads, seed, tolerance=1e-6, max_iterations=25).q
        except UnreachableError:
            return "IK did not converge"
        if np.any(np.minimum(q - hand.lower, hand.upper - q)[_flexing(hand, group)] < checks.joint_margin):
            return "joint limits"
        if shapes.nearest_other(q, group, shape, pose) < checks.clearance:
            return "another link on the object"
        if _least_lever(hand, group, contact_points, q) < checks.singularity_margin:
            return "singular finger"
        if not all(self.probe.flat_around(p, n, checks.edge_margin) for p, n in zip(contact_points, outward)):
            return "contact near an edge"
        if checks.lift and not _lifts(
            hand,
            group,
            contact_points,
            -outward,
            q,
            shapes,
            shape,
            pose,
            checks.lift_offset,
            checks.clearance,
            checks.joint_margin,
        ):
            return "cannot lift"
        away = {f: _movable(hand, q, f, normals[f]) for f in group}
        if min(away[f] @ normals[f] for f in group) < 1.0 / np.hypot(1.0, checks.mu):
            return "pad pushes outside its friction cone"
        try:
            q_pregrasp = ik(hand, {f: pads[f] + checks.standoff * away[f] for f in group}, q, tolerance=1e-6).q
            q_close = ik(hand, {f: pads[f] - checks.closing * away[f] for f in group}, q, tolerance=1e-6).q
        except UnreachableError:
            return "no pre-grasp or approach target"
        if shapes.nearest_other(q_pregrasp, (), shape, pose) < checks.clearance:
            return "pre-grasp touches the object"
        return rate_grasp(
            hand,
            self.item,
            group,
            contact_points,
            -outward,
            q,
            q_pregrasp,
            height,
            checks.mu,
            checks.squeeze,
            checks.gravity,
            q_close=q_close,
        )


def opposed_grasp(hand: Hand, item: Any, mu: float = 0.6, **options: Any) -> GraspCandidate:
    """The best candidate of :func:`search` (same arguments).

    Raises:
        UnreachableError: No candidate; the message gives the object and what was searched.
    """
    candidates, rejected = search(hand, item, mu, **options)
    if not candidates:
        counts = ", ".join(f"{reason}: {count}" for reason, count in rejected.most_common()) or "none tried"
        raise UnreachableError(
            f"no grasp of {type(item).__name__} at {np.round(item.pose.translation, 4).tolist()} m by {hand.name}: no "
            f"searched axis, height and finger layout passes every check (layouts rejected: {counts}); move the "
            "object into the fingers' reach, or give other `fingers`, `heights` or more `samples`"
        )
    return candidates[0]


def _grasp_axes(pose: pin.SE3, directions: int) -> list[np.ndarray]:
    """Horizontal unit grasp axes: ``directions`` over 180 deg, then the object's own horizontal axes."""
    angles = np.pi * np.arange(int(directions)) / max(int(directions), 1)
    axes = [np.array([np.cos(a), np.sin(a), 0.0]) for a in angles]
    for column in pose.rotation.T:
        if abs(column[2]) < 1e-6 and all(abs(abs(column @ a) - 1.0) > 1e-9 for a in axes):
            axes.append(column / np.linalg.norm(column))
    return axes


def _layout(axis: np.ndarray, tilt: int, tilts: int) -> np.ndarray:
    """Unit direction of a side's row of fingers, ``tilt`` of ``tilts`` steps over 180 deg from the horizontal.

    In the plane normal to ``axis``.
    """
    across = np.cross([0.0, 0.0, 1.0], axis)
    angle = np.pi * tilt / max(int(tilts), 1)
    return np.cos(angle) * across + np.sin(angle) * np.array([0.0, 0.0, 1.0])


def _splits(group: tuple[str, ...]) -> list[tuple[tuple[str, ...], tuple[str, ...]]]:
    """Every way to put the fingers on two opposite sides, at least one on each (each split once)."""
    splits = []
    for size in range(1, len(group)):
        for first in itertools.combinations(group, size):
            second = tuple(f for f in group if f not in first)
            splits.append((first, second))
    return splits


def _row(row: Sequence[str], knuckle: dict[str, np.ndarray], u: np.ndarray) -> list[tuple[str, float]]:
    """The row's fingers with their offsets [m] along ``u``, centred.

    Ordered as their knuckles lie along ``u``, each from the last by their knuckles' distance (fingers side by side,
    as they leave the palm).
    """
    ordered = sorted(row, key=lambda f: float(knuckle[f] @ u))
    gaps = [float(np.linalg.norm(knuckle[b] - knuckle[a])) for a, b in itertools.pairwise(ordered)]
    positions = np.concatenate(([0.0], np.cumsum(gaps)))
    return list(zip(ordered, positions - positions.mean()))


def _movable(hand: Hand, q: np.ndarray, finger: str, normal: np.ndarray) -> np.ndarray:
    """The unit direction nearest ``normal`` that the finger's pad can move along at ``q`` (J J^+ n, normalised).

    ``normal`` itself for a finger that moves its pad in 3-D; its part in the plane for one that flexes in a plane.
    """
    jacobian = hand.fingertip_jacobian(q, finger)[:, hand.finger_indices(finger)]
    direction = jacobian @ np.linalg.lstsq(jacobian, normal, rcond=1e-9)[0]
    return direction / np.linalg.norm(direction)


def _shifts(row: list[tuple[str, float]], knuckle: dict[str, np.ndarray], centre: np.ndarray, u: np.ndarray) -> list:
    """Shifts [m] of a row along ``u``: none, and each that puts one of its fingers level with its knuckle.

    A finger that flexes in a plane through its knuckle reaches only that plane.
    """
    shifts = {0.0} | {round(float((knuckle[f] - centre) @ u) - offset, 9) for f, offset in row}
    return sorted(shifts)


def _bounding_radius(shape: coal.ShapeBase) -> float:
    shape.computeLocalAABB()
    return float(np.linalg.norm(np.maximum(np.abs(shape.aabb_local.min_), np.abs(shape.aabb_local.max_))))


__all__ = [
    "TOLERANCE",
    "Checks",
    "FingerReach",
    "Placement",
    "first_hit",
    "knuckles",
    "opposed_grasp",
    "opposed_grasps",
    "pad_radii",
    "search",
]
