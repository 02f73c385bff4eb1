"""Grasp kinematics: P = J_h^+ G^T, the joint velocities of an object twist, and its rate P_dot, both analytic.

With contacts that neither slide nor roll, the grasp constraint (5.19) J_h q_dot = G^T x_dot_o ties the hand's joint
velocities to the object twist x_dot_o = (v, omega) at its centre of mass (world-aligned).  The thesis assumes
J_h square and invertible and writes q_dot = J_h^-1 G^T x_dot_o (5.23).  The Barrett hand with three fingertip
contacts has J_h of size 9 x 8, so here P = J_h^+ G^T (least squares, = J_h^-1 G^T when J_h is invertible) maps
object twists to joint velocities (:mod:`~bhgrasp.grasp.dynamics` reduces the hand-object dynamics with it).

P and its rate along the motion are analytic, from two Pinocchio passes (:func:`grasp_kinematics`).  Contact i is
the point p_i = c + R b_i fixed on the object (COM c, body point b_i) and, at this instant, on the link of joint
j(i).  With Pinocchio's world-frame joint Jacobian J^W_j (6, nv; ``data.J`` of ``computeJointJacobians``: the rows
are the velocity [m/s] of the body point at the world origin and the angular velocity [rad/s], world) and its time
derivative J^W_dot_j along q_dot (``data.dJ`` of ``computeJointJacobiansTimeVariation``; columns outside joint j's
support zeroed):

    J_i     = J^W_lin,j - skew(p_i) J^W_ang,j                                    (3, nv) world [m/rad]
    J_dot_i = J^W_dot_lin,j - skew(p_i) J^W_dot_ang,j - skew(p_dot_i) J^W_ang,j,  p_dot_i = v + omega x (p_i - c)
    G_w^T rows of contact i = [I, -skew(p_i - c)],  their rate [0, -skew(omega x (p_i - c))]
    d(J^+)  = -J^+ J_dot J^+ + J^+ J^+T J_dot^T (I - J J^+) + (I - J^+ J) J_dot^T J^+T J^+
    P       = J^+ G_w^T,   P_dot = d(J^+) G_w^T + J^+ G_w_dot^T,

along q_dot = P x_dot (the joint motion the reduction assumes) and the object twist x_dot.  The pseudo-inverse's
derivative is Golub and Pereyra's (SIAM J. Numer. Anal. 10(2), 1973, (4.12)), exact while the rank of J is
constant (J (9, 8) has full column rank for the Barrett hand's three fingertip contacts; with two contacts J (6, nv)
has full row rank and the third term carries the null-space motion).  P is the same in contact and world
coordinates (J_h = R^T J and G = G_w R with R = blockdiag(R_i) orthogonal, so J_h^+ G^T = J^+ G_w^T).

:func:`contact_kinematics` runs these formulas compiled (``src/grasp.cpp``); :func:`contact_kinematics_python` is
their readable twin.
"""

from __future__ import annotations

import weakref
from dataclasses import dataclass
from typing import Any

import numpy as np
import pinocchio as pin

from bhgrasp._native import kernel
from bhgrasp._validation import as_array, as_vector, require_name
from bhgrasp.errors import InputError
from bhgrasp.grasp.frames import contact_frames, unit_normal_frames
from bhgrasp.model.couplings import refuse_couplings
from bhgrasp.model.hand import Hand


@dataclass(frozen=True)
class GraspKinematics:
    """The maps of a grasp at one instant, without the inertia (what the object-space control laws need).

    Attributes:
        joint_map: P = J_h^+ G^T (nv, 6).
        joint_map_rate: P_dot (nv, 6) along the current motion [1/s].
        grasp_map: G (6, 3n) at the centre of mass.
        hand_jacobian: J_h (3n, nv).
        hand_jacobian_pinv: J_h^+ (nv, 3n).
    """

    joint_map: np.ndarray
    joint_map_rate: np.ndarray
    grasp_map: np.ndarray
    hand_jacobian: np.ndarray
    hand_jacobian_pinv: np.ndarray


@dataclass(frozen=True)
class ObjectState:
    """A grasped object's inertia and motion.

    Attributes: mass [kg]; inertia_body about the COM in the body frame [kg m^2]; com [m] (world); rotation
    (world <- body); twist (v [m/s] of the COM, omega [rad/s]), world-aligned.
    """

    mass: float
    inertia_body: np.ndarray
    com: np.ndarray
    rotation: np.ndarray
    twist: np.ndarray

    @property
    def inertia_world(self) -> np.ndarray:
        """R I_body R^T."""
        return self.rotation @ self.inertia_body @ self.rotation.T

    def advanced(self, dt: float) -> ObjectState:
        """The state after moving for ``dt`` [s] at constant twist (for finite differences along the motion)."""
        v, omega = self.twist[:3], self.twist[3:]
        return ObjectState(
            self.mass, self.inertia_body, self.com + dt * v, pin.exp3(dt * omega) @ self.rotation, self.twist
        )


def grasp_kinematics(
    hand: Hand, q: Any, obj: ObjectState, points_body: Any, normals_body: Any, links: Any
) -> GraspKinematics:
    """P = J_h^+ G^T, its rate P_dot, G and J_h for contacts fixed on the object (body frame) and on hand links.

    Arguments as :func:`~bhgrasp.grasp.dynamics.grasp_dynamics`.  P_dot is analytic (module docstring): its rate
    along the object's twist and the joint velocities q_dot = P x_dot; two kinematics passes
    (``computeJointJacobians`` and ``computeJointJacobiansTimeVariation``), no finite difference.
    """
    q = as_vector(q, "q", hand.nq)
    points_body = as_array(points_body, "points_body", (None, 3))
    normals_body = as_array(normals_body, "normals_body", (points_body.shape[0], 3))
    count = points_body.shape[0]
    if isinstance(links, str) or len(links) != count or not all(isinstance(link, str) for link in links):
        raise InputError(f"`links` must be {count} frame name(s), one per contact, got {links!r}")
    if not isinstance(obj, ObjectState):
        raise InputError(f"`obj` must be an ObjectState, got {type(obj).__name__}")
    as_vector(obj.twist, "obj.twist", 6)
    unit_body = contact_frames(normals_body)[:, :, 2]  # validated, normalised
    rotation = np.asarray(obj.rotation, dtype=float)
    points = obj.com + points_body @ rotation.T
    return contact_kinematics(
        hand, q, obj, points, unit_normal_frames(unit_body @ rotation.T), parent_joints(hand, links)
    )


def contact_kinematics(
    hand: Hand, q: np.ndarray, obj: ObjectState, points: np.ndarray, frames: np.ndarray, joints: Any
) -> GraspKinematics:
    """:func:`grasp_kinematics` from validated world data (the control laws' hot path: nothing is checked).

    Runs the compiled kernel (``src/grasp.cpp``, one per hand, its own Pinocchio data) when ``bhgrasp._core``
    loads; without it, its Python twin :func:`contact_kinematics_python` (same maths, same results to round-off:
    ``tests/test_grasp_kernels.py``), silently.  The hand's current :attr:`~bhgrasp.model.hand.Hand.base_placement` is
    read on every call; its model must not change after the first.

    Args:
        hand: The hand.
        q: Joint positions (nq,) [rad].
        obj: The object (its ``com`` [m] and ``twist`` (v [m/s], omega [rad/s]) are read, world).
        points: (n, 3) contact points [m], world, fixed on the object and on the links.
        frames: (n, 3, 3) contact frames [t1, t2, n] (columns, world), as :func:`~bhgrasp.grasp.frames.contact_frames`.
        joints: n Pinocchio joint ids, the joint whose body carries each contact (:func:`parent_joints`).
    """
    kernel = grasp_kinematics_kernel(hand)
    if kernel is None:
        return contact_kinematics_python(hand, q, obj, points, frames, joints)
    placement = hand.base_placement
    com, twist = np.asarray(obj.com, dtype=float), np.asarray(obj.twist, dtype=float)
    return GraspKinematics(
        *kernel.compute(placement.rotation, placement.translation, q, com, twist, points, frames.reshape(-1, 3), joints)
    )


def contact_kinematics_python(
    hand: Hand, q: np.ndarray, obj: ObjectState, points: np.ndarray, frames: np.ndarray, joints: Any
) -> GraspKinematics:
    """:func:`contact_kinematics` in NumPy and Pinocchio's Python API: the readable twin of the compiled kernel."""
    model, data = hand.model, hand.data
    count, nv = points.shape[0], model.nv
    com, twist = np.asarray(obj.com, dtype=float), np.asarray(obj.twist, dtype=float)
    masks = hand_index(hand).masks[joints][:, None, :]  # (n, 1, nv): the columns that move each contact's body
    placement = hand.base_placement
    moved = not placement.isIdentity(0.0)  # world = placement * (the model's frame)
    offsets = points - com  # r_i = p_i - c [m]
    levers = _skews(offsets)  # skew(r_i), (n, 3, 3)
    omega_skew = pin.skew(twist[3:])
    swept = offsets @ omega_skew.T  # omega x r_i [m/s]
    sweeps = _skews(swept)  # skew(omega x r_i)

    # J_i = J^W_lin - skew(c) J^W_ang - skew(r_i) J^W_ang (the world Jacobian moved to the COM, then to p_i)
    pin.computeJointJacobians(model, data, q)
    spatial = placement.action @ data.J if moved else data.J.copy()  # J^W (6, nv), world
    angular = spatial[3:]
    at_com = spatial[:3] - pin.skew(com) @ angular
    jacobian_world = ((at_com - levers @ angular) * masks).reshape(3 * count, nv)  # J (3n, nv)
    pinv_world = _pinv(jacobian_world)  # J^+ (nv, 3n)
    grasp_t = np.concatenate((np.broadcast_to(np.eye(3), (count, 3, 3)), -levers), axis=2).reshape(3 * count, 6)
    p_map = pinv_world @ grasp_t  # P = J^+ G_w^T (nv, 6)

    # J_dot_i = J^W_dot_lin - skew(c) J^W_dot_ang - skew(v) J^W_ang - skew(r_i) J^W_dot_ang - skew(omega x r_i) J^W_ang
    pin.computeJointJacobiansTimeVariation(model, data, q, p_map @ twist)
    rate = placement.action @ data.dJ if moved else data.dJ  # J^W_dot (6, nv) [1/s]
    rate_at_com = rate[:3] - pin.skew(com) @ rate[3:] - pin.skew(twist[:3]) @ angular
    jacobian_rate = ((rate_at_com - levers @ rate[3:] - sweeps @ angular) * masks).reshape(3 * count, nv)
    grasp_t_rate = np.concatenate((np.zeros((count, 3, 3)), -sweeps), axis=2).reshape(3 * count, 6)
    # P_dot = d(J^+) G_w^T + J^+ G_w_dot^T, d(J^+) by Golub-Pereyra, multiplied out right to left
    rate_t = jacobian_rate.T
    p_dot = (
        pinv_world @ (grasp_t_rate - jacobian_rate @ p_map)
        + (pinv_world @ pinv_world.T) @ (rate_t @ (grasp_t - jacobian_world @ p_map))
        + (rate_t - pinv_world @ (jacobian_world @ rate_t)) @ (pinv_world.T @ p_map)
    )

    # contact coordinates: J_h = R^T J, J_h^+ = J^+ R, G = G_w R (blockwise)
    frames_t = frames.transpose(0, 2, 1)
    jacobian = (frames_t @ jacobian_world.reshape(count, 3, nv)).reshape(3 * count, nv)
    pinv = (pinv_world.reshape(nv, count, 3).transpose(1, 0, 2) @ frames).transpose(1, 0, 2).reshape(nv, 3 * count)
    grasp = (grasp_t.reshape(count, 3, 6).transpose(0, 2, 1) @ frames).transpose(1, 0, 2).reshape(6, 3 * count)
    return GraspKinematics(p_map, p_dot, grasp, jacobian, pinv)


def parent_joints(hand: Hand, links: Any) -> list[int]:
    """The Pinocchio joint ids of the bodies that carry the frames ``links`` (unknown names are rejected)."""
    index = hand_index(hand)
    try:
        return [index.joints[link] for link in links]
    except KeyError:
        for link in links:
            require_name(link, hand.frame_names(), "frame")
        raise


@dataclass(frozen=True)
class HandIndex:
    """What the kinematics read from a hand's model once: support masks (njoints, nv) and frame -> joint id."""

    masks: np.ndarray
    joints: dict[str, int]


_INDEX: weakref.WeakKeyDictionary[Hand, HandIndex] = weakref.WeakKeyDictionary()


def hand_index(hand: Hand) -> HandIndex:
    """The hand's :class:`HandIndex`, built on first use (models are not modified after loading)."""
    index = _INDEX.get(hand)
    if index is None:
        refuse_couplings(hand.couplings, "the grasp kinematics (grasp map, P = J_h^+ G^T and its rate)")
        model = hand.model
        masks = np.zeros((model.njoints, model.nv))
        for joint in range(1, model.njoints):
            for ancestor in list(model.supports[joint])[1:]:  # [0] is the universe
                start = model.joints[ancestor].idx_v
                masks[joint, start : start + model.joints[ancestor].nv] = 1.0
        index = _INDEX[hand] = HandIndex(masks, {frame.name: frame.parentJoint for frame in model.frames})
    return index


def grasp_kinematics_kernel(hand: Hand) -> Any:
    """The hand's compiled ``_core.GraspKinematics``, built on first use; ``None`` when the default engine is Python."""
    refuse_couplings(hand.couplings, "the grasp kinematics (grasp map, P = J_h^+ G^T and its rate)")
    return kernel(hand, "GraspKinematics", lambda core: core.GraspKinematics(hand.model.saveToString()))


# skew(x) = x @ _LEVI_CIVITA reshaped (3, 3): skew(x)[i, j] = -eps_ijk x_k
_LEVI_CIVITA = np.array([pin.skew(axis).ravel() for axis in np.eye(3)])  # (3, 9)


def _skews(vectors: np.ndarray) -> np.ndarray:
    """skew(x_i) for the rows of ``vectors`` (n, 3): (n, 3, 3), in one product."""
    return (vectors @ _LEVI_CIVITA).reshape(-1, 3, 3)


def _pinv(matrix: np.ndarray) -> np.ndarray:
    """The pseudo-inverse as ``np.linalg.pinv`` (singular values below 1e-15 of the largest dropped), less overhead."""
    u, singular, vt = np.linalg.svd(matrix, full_matrices=False)
    inverse = np.divide(1.0, singular, out=np.zeros_like(singular), where=singular > 1e-15 * singular[0])
    return (vt.T * inverse) @ u.T


__all__ = [
    "GraspKinematics",
    "HandIndex",
    "ObjectState",
    "contact_kinematics",
    "contact_kinematics_python",
    "grasp_kinematics",
    "grasp_kinematics_kernel",
    "hand_index",
    "parent_joints",
]
