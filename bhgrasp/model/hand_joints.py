"""A hand's joint space: which coordinate is which joint and finger, the limits, configurations, the joint table.

Free functions over a :class:`~bhgrasp.model.hand.Hand`, which offers each as a method or property of the same name
(``hand.configuration(F1_proximal=0.8)`` is ``configuration(hand, F1_proximal=0.8)``).  :class:`JointLayout` is
built once per hand from its model (:mod:`~bhgrasp.model.hand_description`).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pinocchio as pin

from bhgrasp._validation import as_generator, as_vector, require_name
from bhgrasp.errors import InputError
from bhgrasp.model.hand_description import HandDescription as Hand


def joint_index(hand: Hand, joint: str) -> int:
    """Index of a 1-DOF joint in ``q``/``v`` (a mimic joint has none: InputError naming the joint it follows)."""
    index = hand.layout.indices.get(joint) if isinstance(joint, str) else None
    if index is None:
        for coupling in hand.couplings:
            if coupling.joint == joint:
                source, multiplier, offset = coupling.mimics, coupling.multiplier, coupling.offset
                raise InputError(
                    f"joint {joint!r} mimics {source!r} (q = {multiplier:g} q[{source!r}] + {offset:g}) and has no "
                    f"coordinate of its own: use {source!r}"
                )
        require_name(joint, hand.joint_names, "joint")  # raises: an unknown name
    return index


def finger_joints(hand: Hand, finger: str) -> tuple[str, ...]:
    """Names of the joints whose coordinates move a finger's tip, from the base outward (not ``base_joints``).

    A mimic joint counts as the joint it mimics (listed once, where first met).
    """
    joints = hand.layout.finger_joints.get(finger) if isinstance(finger, str) else None
    if joints is None:
        require_name(finger, hand.fingers, "finger")  # raises: an unknown finger
    return joints


def finger_indices(hand: Hand, finger: str) -> np.ndarray:
    """Velocity indices of a finger's joints (columns of its Jacobian that can be non-zero)."""
    return np.array([joint_index(hand, joint) for joint in finger_joints(hand, finger)], dtype=int)


def lower(hand: Hand) -> np.ndarray:
    """Lower joint position limits [rad], shape (nq,)."""
    return hand.model.lowerPositionLimit.copy()


def upper(hand: Hand) -> np.ndarray:
    """Upper joint position limits [rad], shape (nq,)."""
    return hand.model.upperPositionLimit.copy()


def velocity_limit(hand: Hand) -> np.ndarray:
    """Joint speed limits [rad/s], shape (nv,)."""
    return hand.model.velocityLimit.copy()


def effort_limit(hand: Hand) -> np.ndarray:
    """Joint torque limits [N m], shape (nv,)."""
    return hand.model.effortLimit.copy()


def neutral(hand: Hand) -> np.ndarray:
    """Pinocchio's neutral configuration (all zeros for revolute joints: Barrett fingers open and flat)."""
    return pin.neutral(hand.model)


def random_configuration(hand: Hand, rng: np.random.Generator | int) -> np.ndarray:
    """Configuration drawn uniformly inside the joint limits.

    Args:
        rng: A NumPy generator or an integer seed (there is no unseeded default).
    """
    generator = as_generator(rng)
    return generator.uniform(hand.model.lowerPositionLimit, hand.model.upperPositionLimit)


def configuration(hand: Hand, **joint_values: float) -> np.ndarray:
    """Neutral configuration with the named joints set, e.g. ``hand.configuration(F3_proximal=0.8)`` [rad].

    Raises:
        InputError: Unknown joint name (the message lists the valid ones), non-finite value, or a value
            outside the joint's limits.
    """
    q = neutral(hand)
    for joint, value in joint_values.items():
        i = joint_index(hand, joint)
        angle = float(as_vector([value], joint, 1)[0])
        low, high = hand.model.lowerPositionLimit[i], hand.model.upperPositionLimit[i]
        if not low <= angle <= high:
            raise InputError(f"joint {joint!r} = {angle!r} rad is outside its limits [{low:.6g}, {high:.6g}]")
        q[i] = angle
    return q


def within_limits(hand: Hand, q: Any, tolerance: float = 0.0) -> bool:
    """Whether every joint of ``q`` lies inside its limits (widened by ``tolerance`` [rad])."""
    q = hand.check_q(q)
    return bool(
        np.all(q >= hand.model.lowerPositionLimit - tolerance)
        and np.all(q <= hand.model.upperPositionLimit + tolerance)
    )


def summary(hand: Hand) -> str:
    """A human-readable table of joints, limits, fingers and mass."""
    model = hand.model
    lines = [f"{hand.name}: {hand.nv} joints, {len(hand.fingers)} fingers, {hand.total_mass:.4f} kg"]
    lines.append(
        f"  {'joint':<16}{'lower':>9}{'upper':>9}  [deg]{'vel':>8} [rad/s]{'effort':>8} [N m]{'link mass':>11} [kg]"
    )
    low, high, speed, effort = lower(hand), upper(hand), velocity_limit(hand), effort_limit(hand)
    for i, joint in enumerate(hand.joint_names):
        joint_id = model.getJointId(joint)
        mass = model.inertias[joint_id].mass
        prismatic = model.joints[joint_id].shortname().startswith("JointModelP")
        limits = (
            f"{low[i]:9.3f}{high[i]:9.3f}"
            if prismatic  # a sliding joint: [m], [m/s], [N]
            else f"{np.degrees(low[i]):9.1f}{np.degrees(high[i]):9.1f}"
        )
        lines.append(f"  {joint:<16}{limits}{speed[i]:13.3f}{effort[i]:15.3f}{mass:14.4f}" + "  [m, N]" * prismatic)
    for coupling in hand.couplings:
        lines.append(f"  mimic {coupling.joint}: {coupling.multiplier:g} x {coupling.mimics} + {coupling.offset:g}")
    tips = hand.fingertip_frames
    for finger in hand.fingers:
        lines.append(f"  finger {finger}: tip {tips[finger]!r}, joints {', '.join(finger_joints(hand, finger))}")
    return "\n".join(lines)
