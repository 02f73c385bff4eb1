"""Grasp synthesis: fingertip contacts, spread and pre-grasp configuration for an object, best quality first.

For a hand and a convex object (:class:`~bhgrasp.model.objects.Box`, :class:`~bhgrasp.model.objects.Cylinder`,
:class:`~bhgrasp.model.objects.Sphere` ... placed by its ``pose`` in the hand's world), :func:`grasp_candidates`
searches the spread joints (every joint named ``*spread*`` at one value) and the contact height along the palm normal:

1. **where each finger lands**: a finger closes in a plane; the horizontal line through its fingertip at two
   flexions (every non-spread joint at 0.6, then 1.4 rad, clipped to the limits) is cast at the contact height
   toward the object, and its first point on the surface (coal distances, 0.01 mm) is the finger's contact;
2. **reachability**: the fingertip frames (the pads' centres) go one pad radius out along the surface normal there,
   and the IK (:func:`~bhgrasp.model.hand_ik.ik`, 1e-6 m) must reach them inside the joint limits, away from a kinematic
   singularity (every joint of a grasping finger moves its contact: ``singularity_margin``);
3. **only the pads touch**: every other collision shape of the hand keeps ``clearance`` from the object (a link
   body pressing beside the pad makes several contacts whose forces the grasp controller does not distribute), also
   while the grasp lifts the object by ``lift`` (first order: the joints move by P dx, P = J_h^+ G^T, and the
   object by dx, checked half-way and at the end), where the contacts must not slide and the flexing joints keep
   ``joint_margin`` from their limits (a spread joint may rest on its stop).  Fingertips that touch a wall
   near-parallel to the distal link are close to straight (a 10 mm lift turns the BH8-280's distal links by
   ~0.25 rad), and their link boxes, which stand 0.4 mm proud of the 10 mm pads and reach 12 mm to either side of
   them, swing onto the wall: the link then touches at two points, which cannot both stick while it turns, and the
   pad slides;
4. **quality**: force closure and the Ferrari-Canny epsilon of the frictional point contacts
   (:func:`~bhgrasp.grasp.quality.grasp_quality`, torques over the largest contact distance), and whether the
   contact-force QP holds the object's weight against gravity with ``squeeze`` newtons per contact inside cones
   of ``mu`` (its margin: the smallest mu f_n - |f_t| over contacts [N]).

Two point contacts never close a grasp (nothing resists a turn about the line between them): their epsilon is 0,
and whether (and by how much) they hold the weight ranks them.  :func:`synthesize` returns the best candidate or raises
:class:`~bhgrasp.errors.UnreachableError` naming why none was found.
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from typing import Any

import numpy as np

from bhgrasp._validation import as_positive
from bhgrasp.errors import UnreachableError
from bhgrasp.grasp.candidates import (
    GraspCandidate,
    default_heights,
    finger_sets,
    flexing_joints,
    least_lever,
    lifts,
    proximal_mask,
    rate_grasp,
)
from bhgrasp.grasp.probes import HandClearance, ObjectProbe
from bhgrasp.model.hand import Hand
from bhgrasp.model.hand_ik import ik

NO_GRASP = (
    "at no searched spread and height do the fingers reach it with their pads alone (move the object toward the "
    "fingers, or give other `spreads` / `heights`)"
)  # why no candidate was found
FLEXIONS = (0.6, 1.4)  # [rad] the two closings that give a finger's line of approach


def grasp_candidates(
    hand: Hand,
    item: Any,
    mu: float = 0.6,
    fingers: Sequence[str] | None = None,
    spreads: Sequence[float] | None = None,
    heights: Sequence[float] | None = None,
    pad_radius: float = 0.010,
    clearance: float = 1.5e-3,
    edge_margin: float = 5e-3,
    joint_margin: float = 0.05,
    opening: float = 0.3,
    squeeze: float = 5.0,
    gravity: Any = (0.0, 0.0, -9.81),
    lift: float = 0.01,
    singularity_margin: float = 2e-3,
) -> list[GraspCandidate]:
    """Every reachable candidate (module docstring), best first.

    Args:
        hand: The hand (its world frame: the object's pose is in it).
        item: A rigid object with ``geometry()``, ``pose`` and ``mass``.
        mu: Friction coefficient of the quality and the weight test.
        fingers: The grasping fingers (default: all); every subset of two or more is searched if ``None``.
        spreads: Values [rad] of the spread joints (default: 0 to 90 deg in 10 deg steps, inside their limits).
        heights: Contact heights [m] above the object's centre along the world z (default: 5 across the middle
            half of the object's height).
        pad_radius: Radius [m] of the fingertip pads (the packaged Barrett URDF's 10 mm).
        clearance: Least distance [m] of every other collision shape of the hand from the object, at the contact
            configuration and along the ``lift``: 1 mm beyond the ~0.5 mm the pads sink under a 5 N squeeze in the
            10 kN/m contacts of the thesis' scene (measured on the box and can: lifts that keep 1.1-1.3 mm put the link
            bodies on the object, 1.4 mm and more do not).
        edge_margin: Least distance [m] of a contact from an edge of the surface (a pad rolls; at an edge it rolls
            off): the normals ``edge_margin`` away on the surface, along both tangents, stay within 30 deg.
        joint_margin: Least distance [rad] of every flexing joint from its limits at the contact configuration and
            along the lift (a joint on its stop cannot move one way).  Spread joints may rest on a stop, which then
            holds them (the thesis' pinch has its spread at 0): the grasp's manipulable space refuses the motions
            that would need them to move off it.
        opening: Opening [rad] of the pre-grasp configuration's proximal joints.
        squeeze: Desired normal force [N] per contact of the weight test.
        gravity: World gravity [m/s^2] of the weight test.
        lift: How far [m] against ``gravity`` the grasp must lift the object with its pads alone (module docstring;
            0: no lift check).
        singularity_margin: Least smallest singular value [m/rad] of each finger's contact Jacobian on its joints:
            a fingertip over its spread axis cannot be moved by the spread joint, which is then driven by the pad's
            friction alone (measured: a cube's T-grasp with F1 and F2 over their knuckles diverges as it closes).
    """
    as_positive(mu, "mu")
    pad_radius, clearance = as_positive(pad_radius, "pad_radius"), float(clearance)
    down = np.asarray(gravity, dtype=float)
    lift_offset = np.concatenate((-float(lift) * down / np.linalg.norm(down), np.zeros(3)))
    sets = finger_sets(hand, fingers)
    spread_joints = [i for i, name in enumerate(hand.joint_names) if "spread" in name]
    spreads = _default_spreads(hand, spread_joints) if spreads is None else [float(s) for s in spreads]
    shape, pose = item.geometry(), item.pose
    heights = default_heights(shape, pose) if heights is None else [float(h) for h in heights]
    probe = ObjectProbe(shape, pose)
    shapes = HandClearance(hand)
    candidates = []
    for spread, height in itertools.product(spreads, heights):
        q_spread = _with_spread(hand, spread_joints, spread)
        landing = _landings(hand, probe, q_spread, sets, pose.translation[2] + height)
        for group in sets:
            if any(landing[f] is None for f in group):
                continue
            points = np.array([landing[f][0] for f in group])
            outward = np.array([landing[f][1] for f in group])
            q = _pads_reached(hand, group, points, outward, pad_radius, q_spread)
            if q is None:
                continue
            if shapes.nearest_other(q, group, shape, pose) < clearance:
                continue
            if np.any(np.minimum(q - hand.lower, hand.upper - q)[flexing_joints(hand, group)] < joint_margin):
                continue
            if least_lever(hand, group, points, q) < singularity_margin:
                continue
            if not all(probe.flat_around(p, n, edge_margin) for p, n in zip(points, outward)):
                continue
            if lift and not lifts(
                hand, group, points, -outward, q, shapes, shape, pose, lift_offset, clearance, joint_margin
            ):
                continue
            candidates.append(_candidate(hand, item, group, points, -outward, q, height, mu, opening, squeeze, gravity))
    candidates.sort(key=lambda c: c.score, reverse=True)
    return candidates


def _landings(hand: Hand, probe: ObjectProbe, q_spread: np.ndarray, sets: list, z: float) -> dict:
    """Where each finger of ``sets`` lands at height ``z`` [m] along its line of approach (``None``: it misses)."""
    return {f: probe.landing(*_approach_line(hand, q_spread, f), z) for f in {f for group in sets for f in group}}


def _pads_reached(hand: Hand, group, points, outward, pad_radius: float, q_spread) -> np.ndarray | None:
    """The IK's configuration with ``group``'s pad centres one ``pad_radius`` out from ``points``, or ``None``."""
    try:
        targets = {f: p + pad_radius * n for f, p, n in zip(group, points, outward)}
        return ik(hand, targets, q_spread, tolerance=1e-6).q
    except UnreachableError:
        return None


def synthesize(hand: Hand, item: Any, mu: float = 0.6, **options: Any) -> GraspCandidate:
    """The best candidate of :func:`grasp_candidates` (same arguments).

    Raises:
        UnreachableError: No candidate: no spread and height lets the fingers reach the object with their pads
            alone; the message gives the object and what was searched.
    """
    candidates = grasp_candidates(hand, item, mu, **options)
    if not candidates:
        raise UnreachableError(
            f"no grasp of {type(item).__name__} at {np.round(item.pose.translation, 4).tolist()} m: {NO_GRASP}"
        )
    return candidates[0]


def _candidate(hand, item, group, points, normals, q, height, mu, opening, squeeze, gravity):
    q_pregrasp = np.clip(q - opening * proximal_mask(hand), hand.lower, hand.upper)
    return rate_grasp(hand, item, group, points, normals, q, q_pregrasp, height, mu, squeeze, gravity)


def _default_spreads(hand: Hand, joints: list[int]) -> list[float]:
    if not joints:
        return [0.0]
    low, high = max(hand.lower[j] for j in joints), min(hand.upper[j] for j in joints)
    return [s for s in np.radians(np.arange(0.0, 91.0, 10.0)) if low <= s <= high] or [low]


def _with_spread(hand: Hand, joints: list[int], spread: float) -> np.ndarray:
    q = np.clip(np.full(hand.nq, np.mean(FLEXIONS)), hand.lower, hand.upper)
    q[joints] = spread
    return q


def _approach_line(hand: Hand, q_spread: np.ndarray, finger: str) -> tuple[np.ndarray, np.ndarray]:
    """A finger's line of approach: a point and a unit direction in the horizontal (world x-y) plane."""
    flexing = np.array(["spread" not in name for name in hand.joint_names])
    tips = []
    for flexion in FLEXIONS:
        q = np.where(flexing, flexion, q_spread)
        tips.append(hand.fingertip_positions(np.clip(q, hand.lower, hand.upper))[hand.fingers.index(finger)])
    start, end = tips[0].copy(), tips[1].copy()
    direction = (end - start)[:2]
    norm = float(np.linalg.norm(direction))
    return start[:2], (direction / norm if norm > 1e-9 else np.zeros(2))


__all__ = ["FLEXIONS", "NO_GRASP", "GraspCandidate", "grasp_candidates", "rate_grasp", "synthesize"]
