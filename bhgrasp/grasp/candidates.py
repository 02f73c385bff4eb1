"""A candidate grasp, how it is rated, and the checks both grasp searches share.

The searches: :mod:`~bhgrasp.grasp.synthesis` (lines of approach) and :mod:`~bhgrasp.grasp.opposition` (any hand).
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import coal
import numpy as np
import pinocchio as pin

from bhgrasp._validation import require_name
from bhgrasp.errors import InputError
from bhgrasp.grasp.forces import ContactForceQP
from bhgrasp.grasp.frames import grasp_map
from bhgrasp.grasp.manipulability import SLIDE_TOLERANCE, manipulable_space
from bhgrasp.grasp.quality import GraspQuality, grasp_quality
from bhgrasp.model.hand import Hand


@dataclass(frozen=True)
class GraspCandidate:
    """One grasp: contacts (world), the configurations that make it, and its quality.

    Attributes:
        fingers: The grasping fingers.
        points: (n, 3) contact points on the object's surface [m]; normals: (n, 3) unit normals into the object.
        q_contact: Joint positions [rad] with each pad touching its point; q_pregrasp: the same with each finger's
            first non-spread (proximal) joint opened by ``opening`` (clipped to the limits), where an approach starts.
            The other joints stay at their contact values, as in the thesis' scene
            (:func:`~bhgrasp.scenarios.box_grasp.box_grasp`): a joint-space approach barely moves the BH8-280's
            distal joints (3.8e-5 kg m^2 against the drive's 0.05 N m s/rad, a 3 s time constant at Kp = 400 /s^2),
            so an opened distal joint is still ~0.2 rad short when its pad touches, away from the planned grasp.
        spread: The spread joints' mean [rad] in ``q_contact`` (the approach lines were cast at a searched spread;
            the IK then places the pads); height: the contacts' height above the object's centre [m].
        quality: Force closure, epsilon [N] ...; holds_weight: the QP holds the weight inside the cones;
            weight_margin: its smallest mu f_n - |f_t| [N] (negative: outside a cone).
        q_close: The approach's target (pads pressed into the object), where the search plans one
            (:func:`~bhgrasp.grasp.opposition.opposed_grasps`); ``None``: the supervisor's default.
    """

    fingers: tuple[str, ...]
    points: np.ndarray
    normals: np.ndarray
    q_contact: np.ndarray
    q_pregrasp: np.ndarray
    spread: float
    height: float
    quality: GraspQuality
    holds_weight: bool
    weight_margin: float
    q_close: np.ndarray | None = None

    @property
    def score(self) -> tuple[float, bool, float]:
        """The ranking: epsilon first, then whether the weight is held, then its margin."""
        return (self.quality.epsilon, self.holds_weight, self.weight_margin)


def rate_grasp(
    hand: Hand,
    item: Any,
    fingers: Sequence[str],
    points: np.ndarray,
    normals: np.ndarray,
    q: np.ndarray,
    q_pregrasp: np.ndarray,
    height: float,
    mu: float,
    squeeze: float,
    gravity: Any,
    q_close: np.ndarray | None = None,
) -> GraspCandidate:
    """A :class:`GraspCandidate` of these contacts (``normals`` into the object) with its quality and weight test."""
    quality = grasp_quality(points, normals, item.pose.translation, mu)
    weight = ContactForceQP(len(fingers), mu).solve(
        grasp_map(points, normals, item.pose.translation),
        np.concatenate((-item.mass * np.asarray(gravity, dtype=float), np.zeros(3))),
        np.tile([0.0, 0.0, float(squeeze)], (len(fingers), 1)),
    )
    spreads = [q[i] for i, name in enumerate(hand.joint_names) if "spread" in name]
    spread = float(np.mean(spreads)) if spreads else 0.0
    feasible, margin = bool(weight.feasible), float(-weight.cone_violation)
    return GraspCandidate(
        tuple(fingers), points, normals, q, q_pregrasp, spread, height, quality, feasible, margin, q_close
    )


def least_lever(hand: Hand, fingers: Sequence[str], points: np.ndarray, q: np.ndarray) -> float:
    """The smallest singular value [m/rad] over the fingers of their contact point's Jacobian on their own joints."""
    levers = []
    for finger, point in zip(fingers, points):
        jacobian = hand.point_jacobian(q, hand.fingertip_frames[finger], point)[:3][:, hand.finger_indices(finger)]
        levers.append(np.linalg.svd(jacobian, compute_uv=False).min())
    return float(min(levers))


def lifts(hand, group, points, normals, q, shapes, shape, pose, offset, clearance, joint_margin) -> bool:
    """Whether the pads alone move the object by ``offset`` (first order): no sliding, joints off their limits."""
    space = manipulable_space(
        hand, q, points, normals, [hand.fingertip_frames[f] for f in group], pose.translation, group
    )
    if np.max(space.sliding(offset)) > SLIDE_TOLERANCE:
        return False
    step, joints = space.joint_map @ offset, flexing_joints(hand, group)
    for fraction in (0.5, 1.0):
        q_moved = q + fraction * step
        if np.any(np.minimum(q_moved - hand.lower, hand.upper - q_moved)[joints] < joint_margin):
            return False
        moved = pin.SE3(pose.rotation, pose.translation + fraction * offset[:3])
        if shapes.nearest_other(q_moved, group, shape, moved) < clearance:
            return False
    return True


def proximal_mask(hand: Hand) -> np.ndarray:
    """1.0 at each finger's first non-spread joint (the one a pre-grasp opens), 0.0 elsewhere."""
    mask = np.zeros(hand.nq)
    for finger in hand.fingers:
        flexing = [joint for joint in hand.finger_joints(finger) if "spread" not in joint]
        if flexing:
            mask[hand.joint_index(flexing[0])] = 1.0
    return mask


def flexing_joints(hand: Hand, fingers: Sequence[str]) -> np.ndarray:
    """Configuration indices of the fingers' flexing joints (a spread joint may rest on its stop, which holds it)."""
    joints = joints_of(hand, fingers)
    return np.array([j for j in joints if "spread" not in hand.joint_names[j]], dtype=int)


def joints_of(hand: Hand, fingers: Sequence[str]) -> np.ndarray:
    """Configuration indices of the fingers' joints."""
    return np.concatenate([hand.finger_indices(f) for f in fingers])


def finger_sets(hand: Hand, fingers: Sequence[str] | None) -> list[tuple[str, ...]]:
    """The finger groups a search tries, the largest first.

    ``fingers`` (checked, two or more) if given, else every group of two or more of the hand's fingers.
    """
    if fingers is not None:
        chosen = tuple(require_name(f, hand.fingers, "finger") for f in fingers)
        if len(chosen) < 2:
            raise InputError(f"`fingers` must name at least two fingers, got {list(fingers)}")
        return [chosen]
    return [group for size in range(len(hand.fingers), 1, -1) for group in itertools.combinations(hand.fingers, size)]


def default_heights(shape: coal.ShapeBase, pose: pin.SE3) -> list[float]:
    """The contact heights [m] a search tries on ``shape`` at ``pose`` (world z, relative to the pose).

    Five across the middle half of the vertical extent of its bounding box.
    """
    shape.computeLocalAABB()
    corners = np.array(list(itertools.product(*zip(shape.aabb_local.min_, shape.aabb_local.max_))))
    z = (corners @ pose.rotation.T)[:, 2]
    return list(np.linspace(0.25 * z.min(), 0.25 * z.max(), 5))


__all__ = [
    "GraspCandidate",
    "default_heights",
    "finger_sets",
    "flexing_joints",
    "joints_of",
    "least_lever",
    "lifts",
    "proximal_mask",
    "rate_grasp",
]
