"""Where the pads of an opposed grasp go, and the checks a placed grasp must pass.

Each finger's sampled reach, its pad, a row of pads along a layout, the contact under each pad.
"""

from __future__ import annotations

import itertools
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from typing import Any

import coal
import numpy as np
import pinocchio as pin
from scipy.spatial import cKDTree

from bhgrasp.errors import InputError, UnreachableError
from bhgrasp.grasp.candidates import (
    GraspCandidate,
    flexing_joints,
    least_lever,
    lifts,
    rate_grasp,
)
from bhgrasp.grasp.probes import HandClearance, ObjectProbe, bounding_radius, first_hit
from bhgrasp.model.couplings import refuse_couplings
from bhgrasp.model.hand import Hand
from bhgrasp.model.hand_ik import ik

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


class Placement:
    """Pads on one object: the contacts of each finger layout (traced once each), and the checks of a placement."""

    def __init__(self, hand: Hand, item: Any, radii: dict[str, float], reach: FingerReach, tolerance: float) -> None:
        """Probe ``item`` (world pose) for ``hand``'s pads of ``radii`` [m], reachable within ``tolerance`` [m]."""
        self.hand, self.item, self.radii, self.reach, self.tolerance = hand, item, radii, reach, tolerance
        self.shape, self.pose = item.geometry(), item.pose
        self.probe, self.shapes = ObjectProbe(self.shape, self.pose), HandClearance(hand)
        self.rest = np.clip(np.zeros(hand.nq), hand.lower, hand.upper)
        self.knuckle = knuckles(hand, self.rest)
        self.span = bounding_radius(self.shape) + 0.02
        self.centre = self.pose.translation
        self.traced: dict[tuple, tuple | None] = {}
        self.nearest: dict[tuple, tuple[float, int]] = {}

    def layouts(self, split: tuple, axis: np.ndarray, height: float, u: np.ndarray) -> Iterator[tuple | None]:
        """Each shift of the two rows (:func:`row_shifts`): the fingers' contacts, normals and IK seed.

        ``None`` where a pad is out of its finger's reach or its line misses the object.
        """
        sides = [row_offsets(row, self.knuckle, u) for row in split]
        for shifts in itertools.product(*(row_shifts(side, self.knuckle, self.centre, u) for side in sides)):
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
        if np.any(np.minimum(q - hand.lower, hand.upper - q)[flexing_joints(hand, group)] < checks.joint_margin):
            return "joint limits"
        if shapes.nearest_other(q, group, shape, pose) < checks.clearance:
            return "another link on the object"
        if least_lever(hand, group, contact_points, q) < checks.singularity_margin:
            return "singular finger"
        if not all(self.probe.flat_around(p, n, checks.edge_margin) for p, n in zip(contact_points, outward)):
            return "contact near an edge"
        if checks.lift and not lifts(
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
        away = {f: movable_normal(hand, q, f, normals[f]) for f in group}
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


def row_offsets(row: Sequence[str], knuckle: dict[str, np.ndarray], u: np.ndarray) -> list[tuple[str, float]]:
    """The row's fingers with their offsets [m] along ``u``, centred.

    Ordered as their knuckles lie along ``u``, each from the last by their knuckles' distance (fingers side by side,
    as they leave the palm).
    """
    ordered = sorted(row, key=lambda f: float(knuckle[f] @ u))
    gaps = [float(np.linalg.norm(knuckle[b] - knuckle[a])) for a, b in itertools.pairwise(ordered)]
    positions = np.concatenate(([0.0], np.cumsum(gaps)))
    return list(zip(ordered, positions - positions.mean()))


def movable_normal(hand: Hand, q: np.ndarray, finger: str, normal: np.ndarray) -> np.ndarray:
    """The unit direction nearest ``normal`` that the finger's pad can move along at ``q`` (J J^+ n, normalised).

    ``normal`` itself for a finger that moves its pad in 3-D; its part in the plane for one that flexes in a plane.
    """
    jacobian = hand.fingertip_jacobian(q, finger)[:, hand.finger_indices(finger)]
    direction = jacobian @ np.linalg.lstsq(jacobian, normal, rcond=1e-9)[0]
    return direction / np.linalg.norm(direction)


def row_shifts(row: list[tuple[str, float]], knuckle: dict[str, np.ndarray], centre: np.ndarray, u: np.ndarray) -> list:
    """Shifts [m] of a row along ``u``: none, and each that puts one of its fingers level with its knuckle.

    A finger that flexes in a plane through its knuckle reaches only that plane.
    """
    shifts = {0.0} | {round(float((knuckle[f] - centre) @ u) - offset, 9) for f, offset in row}
    return sorted(shifts)


__all__ = [
    "PAD_ITERATIONS",
    "SIDES",
    "SLOT_TOLERANCE",
    "Checks",
    "FingerReach",
    "Placement",
    "knuckles",
    "movable_normal",
    "pad_radii",
    "row_offsets",
    "row_shifts",
]
