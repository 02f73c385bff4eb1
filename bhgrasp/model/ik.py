"""Inverse kinematics of one finger in closed form (the Barrett fingers), and fingertip workspace sampling.

Damped least squares for several fingertips of any hand: :mod:`bhgrasp.model.hand_ik`.

The closed form follows thesis 2.3.2 (spread angle from the target's bearing, then a planar two-link solution),
corrected: (2.6)-(2.7) use sin where cos belongs, l_2, l_3 instead of their squares and l_1 l_2 instead of
l_2 l_3, and ignore the knuckle offset and the CAD angle offsets.  Here the link vectors, offsets and axes are
read from the Pinocchio model, so the solution is exact for whatever URDF the hand was loaded from.
"""

from __future__ import annotations

import weakref
from dataclasses import dataclass
from typing import Any

import numpy as np
import pinocchio as pin

from bhgrasp._validation import as_generator, as_positive, as_vector, require_name
from bhgrasp.errors import InputError, ModelError, UnreachableError
from bhgrasp.model.hand import Hand

_LIMIT_SLACK = 1e-9  # [rad] joint-limit tolerance for solutions exactly on a limit


@dataclass(frozen=True)
class FingerIKResult:
    """Joint angles of one finger that put its fingertip on a target.

    Attributes:
        finger: Finger name.
        joints: The finger's joint names, base outward.
        angles: Their angles [rad], same order.
        indices: Their indices in the hand's ``q``.
        plane_residual: Distance [m] from the target to the finger's reachable plane (non-zero only for a finger
            without spread, such as Barrett F3, whose tip moves in a fixed plane).
    """

    finger: str
    joints: tuple[str, ...]
    angles: np.ndarray
    indices: np.ndarray
    plane_residual: float

    def apply(self, q: Any) -> np.ndarray:
        """A copy of the hand configuration ``q`` with this finger's joints set to :attr:`angles`."""
        q = np.array(q, dtype=float)
        q[self.indices] = self.angles
        return q


@dataclass(frozen=True)
class Workspace:
    """Sampled reachable fingertip positions of one finger (world frame) and their bounding box [m]."""

    finger: str
    points: np.ndarray
    lower: np.ndarray
    upper: np.ndarray


# ---------------------------------------------------------------------- closed form (Barrett-like fingers)
def finger_ik(
    hand: Hand, finger: str, position: Any, q0: Any = None, plane_tolerance: float | None = None
) -> FingerIKResult:
    """Closed-form IK of a Barrett-like finger: optional spread joint, then two parallel-axis joints.

    Args:
        hand: The hand (``BarrettHand()`` or any hand whose finger has that structure).
        finger: Finger name, e.g. ``"F1"``.
        position: Target fingertip position in the world frame [m], shape (3,).
        q0: Optional hand configuration; among several solutions the one closest to it is returned.
        plane_tolerance: For a finger without spread, raise if the target is farther than this [m] from the
            finger's plane (default: project onto the plane and report the distance as ``plane_residual``).

    Raises:
        UnreachableError: The target is out of reach or every solution violates a joint limit.
        ModelError: The finger is not a (spread +) planar two-joint chain.
    """
    require_name(finger, hand.fingers, "finger")
    target_world = as_vector(position, "position", 3)
    reference = hand.neutral() if q0 is None else as_vector(q0, "q0", hand.nq)
    chain = _finger_chain(hand, finger)
    target = hand.base_placement.actInv(target_world)  # base frame coordinates
    candidates, residual = chain.solve(target)
    if not candidates:
        raise UnreachableError(
            f"fingertip target {target_world.tolist()} m is out of reach of finger {finger!r}: {chain.why_not(target)}"
        )
    indices = hand.finger_indices(finger)
    best = min(candidates, key=lambda angles: float(np.sum((angles - reference[indices]) ** 2)))
    if plane_tolerance is not None and residual > as_positive(plane_tolerance, "plane_tolerance"):
        raise UnreachableError(
            f"target {target_world.tolist()} m lies {residual:.3g} m out of finger {finger!r}'s plane "
            f"(plane_tolerance {plane_tolerance} m)"
        )
    return FingerIKResult(finger, hand.finger_joints(finger), best, indices, float(residual))


_CHAINS: weakref.WeakKeyDictionary[Hand, dict[str, _FingerChain]] = weakref.WeakKeyDictionary()


def _finger_chain(hand: Hand, finger: str) -> _FingerChain:
    """The finger's geometry, read from the model once per hand (models are not modified after loading)."""
    chains = _CHAINS.setdefault(hand, {})
    if finger not in chains:
        chains[finger] = _FingerChain(hand, finger)
    return chains[finger]


class _FingerChain:
    """Geometry of a finger read off the model: [spread about a_s], proximal about a_p, distal parallel to it."""

    def __init__(self, hand: Hand, finger: str) -> None:
        model = hand.model
        joints = hand.finger_joints(finger)
        if len(joints) not in (2, 3):
            raise ModelError(f"finger {finger!r} has joints {joints}; closed-form IK needs [spread,] proximal, distal")
        ids = [model.getJointId(name) for name in joints]
        self.indices = hand.finger_indices(finger)
        self.lower = model.lowerPositionLimit[self.indices]
        self.upper = model.upperPositionLimit[self.indices]
        axes = [_joint_axis(model, j) for j in ids]
        tip_frame = model.frames[model.getFrameId(hand.fingertip_frames[finger])]
        if tip_frame.parentJoint != ids[-1]:
            raise ModelError(f"finger {finger!r}: the fingertip frame must hang from the last finger joint")
        proximal, distal = ids[-2], ids[-1]
        # Proximal joint frame P at zero angles, in the spread joint frame S (or the base, without spread).
        self.placement_p = model.jointPlacements[proximal]
        self.spread = None
        if len(ids) == 3:
            if model.parents[proximal] != ids[0]:
                raise ModelError(f"finger {finger!r}: the proximal joint must hang from the spread joint")
            if model.parents[ids[0]] != 0:
                raise ModelError(f"finger {finger!r}: the spread joint must hang from the hand base")
            self.spread = (model.jointPlacements[ids[0]], axes[0])
        elif model.parents[proximal] != 0:
            raise ModelError(f"finger {finger!r}: a two-joint finger must hang from the hand base")
        if model.parents[distal] != proximal:
            raise ModelError(f"finger {finger!r}: the distal joint must hang from the proximal joint")
        self.axis_p = axes[-2]
        distal_placement = model.jointPlacements[distal]
        axis_d = distal_placement.rotation @ axes[-1]
        if abs(abs(axis_d @ self.axis_p) - 1.0) > 1e-9:
            raise ModelError(f"finger {finger!r}: proximal and distal axes are not parallel")
        self.sign_d = float(np.sign(axis_d @ self.axis_p))
        tip = distal_placement.rotation @ tip_frame.placement.translation
        self.e1, self.e2 = _plane_basis(self.axis_p)
        self.link_d = self._in_plane(distal_placement.translation)  # proximal axis -> distal axis, 2-D
        self.link_t = self._in_plane(tip)  # distal axis -> fingertip at zero distal angle, 2-D
        self.height = float(self.axis_p @ (distal_placement.translation + tip))  # tip offset along the axis
        if self.spread is not None:
            axis_s = self.spread[1]
            axis_p_in_s = self.placement_p.rotation @ self.axis_p
            if abs(axis_p_in_s @ axis_s) > 1e-9:
                raise ModelError(f"finger {finger!r}: the spread axis must lie in the finger's plane")
            # Tip offset from the spread axis along the proximal axis (constant in every pose).
            self.spread_offset = float(axis_p_in_s @ self.placement_p.translation) + self.height

    def _in_plane(self, vector: np.ndarray) -> np.ndarray:
        return np.array([vector @ self.e1, vector @ self.e2])

    def reach(self) -> tuple[float, float]:
        """Smallest and largest distance from the proximal axis to the tip (ignoring joint limits) [m]."""
        a, b = np.linalg.norm(self.link_d), np.linalg.norm(self.link_t)
        return abs(a - b), a + b

    def solve(self, target: np.ndarray) -> tuple[list[np.ndarray], float]:
        """All in-limit joint solutions for a base-frame target, and the distance to the finger plane."""
        if self.spread is None:
            point_p = self.placement_p.actInv(target)
            residual = abs(float(self.axis_p @ point_p) - self.height)
            return [a for a in self._planar(point_p)], residual
        placement_s, axis_s = self.spread
        point_s = placement_s.actInv(target)
        solutions = []
        for spread in self._spread_angles(point_s, axis_s):
            point_p = self.placement_p.actInv(pin.exp3(-spread * axis_s) @ point_s)
            solutions += [np.concatenate(([spread], angles)) for angles in self._planar(point_p)]
        return solutions, 0.0

    def _spread_angles(self, point_s: np.ndarray, axis_s: np.ndarray) -> list[float]:
        # Rotating the spread by theta turns the proximal axis n into cos(theta) n + sin(theta) (a_s x n); the
        # target must then lie at `spread_offset` along it:  A cos(theta) + B sin(theta) = offset.
        normal = self.placement_p.rotation @ self.axis_p
        a, b = point_s @ normal, point_s @ np.cross(axis_s, normal)
        radius = np.hypot(a, b)
        if radius < abs(self.spread_offset) or radius == 0.0:
            return []
        phase, half_width = np.arctan2(b, a), np.arccos(np.clip(self.spread_offset / radius, -1.0, 1.0))
        return _in_limits([phase + half_width, phase - half_width], self.lower[0], self.upper[0])

    def _planar(self, point_p: np.ndarray) -> list[np.ndarray]:
        # Tip in the plane: rot(q2) (D + rot(s q3) T).  |D + rot(delta) T| = |p| fixes delta = s q3 + arg(T) -
        # arg(D) up to sign; then q2 is the angle from that vector to p.
        point = self._in_plane(point_p)
        length_d, length_t = np.linalg.norm(self.link_d), np.linalg.norm(self.link_t)
        cos_delta = (point @ point - length_d**2 - length_t**2) / (2.0 * length_d * length_t)
        if abs(cos_delta) > 1.0 + 1e-12:
            return []
        offset = np.arctan2(self.link_t[1], self.link_t[0]) - np.arctan2(self.link_d[1], self.link_d[0])
        solutions = []
        elbow_angle = float(np.arccos(np.clip(cos_delta, -1.0, 1.0)))
        for delta in (elbow_angle, -elbow_angle) if elbow_angle > 0.0 else (elbow_angle,):
            for q3 in _in_limits([self.sign_d * (delta - offset)], self.lower[-1], self.upper[-1]):
                elbow = self.link_d + _rotate(self.link_t, self.sign_d * q3)
                q2 = np.arctan2(point[1], point[0]) - np.arctan2(elbow[1], elbow[0])
                solutions += [np.array([q2_, q3]) for q2_ in _in_limits([q2], self.lower[-2], self.upper[-2])]
        return solutions

    def why_not(self, target: np.ndarray) -> str:
        near, far = self.reach()
        lower, upper = np.round(self.lower, 4).tolist(), np.round(self.upper, 4).tolist()
        return (
            f"no solution within the joint limits {lower}..{upper} rad "
            f"(the tip can be {near:.4f}..{far:.4f} m from the proximal axis)"
        )


def _joint_axis(model: pin.Model, joint_id: int) -> np.ndarray:
    joint = model.joints[joint_id]
    if joint.nv != 1 or joint.nq != 1:
        raise ModelError(f"joint {model.names[joint_id]!r} is not a 1-DOF revolute joint")
    data = model.createData()
    pin.computeJointJacobians(model, data, pin.neutral(model))
    column = pin.getJointJacobian(model, data, joint_id, pin.ReferenceFrame.LOCAL)[:, joint.idx_v]
    if np.linalg.norm(column[:3]) > 1e-12:
        raise ModelError(f"joint {model.names[joint_id]!r} is not revolute")
    return column[3:] / np.linalg.norm(column[3:])


def _plane_basis(axis: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    seed = np.eye(3)[int(np.argmin(np.abs(axis)))]
    e1 = seed - (seed @ axis) * axis
    e1 /= np.linalg.norm(e1)
    return e1, np.cross(axis, e1)


def _rotate(vector: np.ndarray, angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    return np.array([c * vector[0] - s * vector[1], s * vector[0] + c * vector[1]])


def _in_limits(angles: list[float], lower: float, upper: float) -> list[float]:
    """Each angle, shifted by a multiple of 2 pi into [lower, upper] if possible (snapped onto a limit within slack)."""
    found = []
    for angle in angles:
        for shift in (0.0, 2 * np.pi, -2 * np.pi):
            value = float(angle + shift)
            if lower - _LIMIT_SLACK <= value <= upper + _LIMIT_SLACK:
                found.append(min(max(value, lower), upper))
    return found


# ---------------------------------------------------------------------- damped least squares (any hand)


# ---------------------------------------------------------------------- workspace
def workspace(hand: Hand, finger: str, n: int, rng: np.random.Generator | int, q_rest: Any = None) -> Workspace:
    """Sample ``n`` fingertip positions of one finger over uniform joint angles within its limits (thesis (2.8)).

    The other joints stay at ``q_rest`` (default: neutral).  Returns the points and their bounding box.
    """
    require_name(finger, hand.fingers, "finger")
    if not isinstance(n, (int, np.integer)) or n < 1:
        raise InputError(f"`n` must be a positive integer, got {n!r}")
    generator = as_generator(rng)
    q = hand.neutral() if q_rest is None else as_vector(q_rest, "q_rest", hand.nq)
    indices = hand.finger_indices(finger)
    samples = generator.uniform(hand.lower[indices], hand.upper[indices], size=(int(n), len(indices)))
    tip = hand.fingers.index(finger)
    points = np.empty((int(n), 3))
    for k, angles in enumerate(samples):
        q[indices] = angles
        points[k] = hand.fingertip_positions(q)[tip]
    return Workspace(finger, points, points.min(axis=0), points.max(axis=0))
