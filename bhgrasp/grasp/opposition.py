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
   curved face tilts the normal, and the pad with it) (sphere tracing on coal distances,
   :data:`~bhgrasp.grasp.probes.TRACE_TOLERANCE`; the rows and pads: :mod:`~bhgrasp.grasp.pad_placement`);
3. **reachability**: every pad centre (contact + pad radius x outward normal) must lie within ``reach_tolerance`` of
   its finger's cloud; the IK (:func:`~bhgrasp.model.hand_ik.ik`, 1e-6 m) starts from the nearest samples' joint
   values, the idle fingers at rest (zero, clipped to the limits);
4. **the same checks as the approach-line search**: the other collision shapes keep ``clearance`` from the object, the
   grasping joints ``joint_margin`` from their limits, each contact Jacobian ``singularity_margin`` from singular,
   the contacts ``edge_margin`` from an edge, the pads lift the object by ``lift`` without sliding; then force
   closure, the Ferrari-Canny epsilon and the weight test rank the candidates
   (:class:`~bhgrasp.grasp.candidates.GraspCandidate`);
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
from typing import Any

import numpy as np
import pinocchio as pin

from bhgrasp._validation import as_positive, as_vector
from bhgrasp.errors import UnreachableError
from bhgrasp.grasp.candidates import (
    GraspCandidate,
    default_heights,
    finger_sets,
)
from bhgrasp.grasp.pad_placement import Checks, FingerReach, Placement, pad_radii
from bhgrasp.model.hand import Hand


def opposed_grasps(hand: Hand, item: Any, mu: float = 0.6, **options: Any) -> list[GraspCandidate]:
    """Every candidate the search finds (module docstring), best first; the options are :func:`search`'s."""
    return search(hand, item, mu, **options)[0]


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
    sets = finger_sets(hand, fingers)
    placing = _placement(hand, item, pad_radius, samples, reach_tolerance, rng)
    shape, pose = item.geometry(), item.pose
    heights = default_heights(shape, pose) if heights is None else [float(h) for h in heights]
    candidates, seen, rejected = [], set(), Counter()
    layouts = _layouts(placing, sets, _grasp_axes(pose, directions), heights, tilts)
    for group, height, placed in layouts:
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


def _placement(hand: Hand, item: Any, pad_radius, samples, reach_tolerance, rng) -> Placement:
    """The pads' placement for ``item``: each finger's pad radius (given, or its collision sphere's), its reach."""
    if pad_radius is None:
        radii = pad_radii(hand)
    else:
        radii = dict.fromkeys(hand.fingers, as_positive(pad_radius, "pad_radius"))
    reach = FingerReach(hand, int(as_positive(samples, "samples")), np.random.default_rng(rng))
    return Placement(hand, item, radii, reach, float(reach_tolerance))


def _layouts(placing: Placement, sets: list, axes: list, heights: list, tilts: int) -> Iterator[tuple]:
    """Every (finger group, height, placed pads or None) of the search.

    In its order: groups, splits, axes, heights, tilts, then the rows' shifts.
    """
    for group in sets:
        for split in _splits(group):
            rows = range(tilts if max(map(len, split)) > 1 else 1)  # one finger a side: no row to tilt
            for axis, height, tilt in itertools.product(axes, heights, rows):
                for placed in placing.layouts(split, axis, height, _layout(axis, tilt, tilts)):
                    yield group, height, placed


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


__all__ = ["opposed_grasp", "opposed_grasps", "search"]
