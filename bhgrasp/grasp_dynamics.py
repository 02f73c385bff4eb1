"""Coupled hand-object dynamics of a grasp (thesis (5.20)-(5.25)) and the object motions a grasp allows.

With contacts that neither slide nor roll, the grasp constraint (5.19) J_h q_dot = G^T x_dot_o ties the hand's joint
velocities to the object twist x_dot_o = (v, omega) at its centre of mass (world-aligned).  The thesis assumes
J_h square and invertible and writes q_dot = J_h^-1 G^T x_dot_o (5.23).  The Barrett hand with three fingertip
contacts has J_h of size 9 x 8, so here P = J_h^+ G^T (least squares, = J_h^-1 G^T when J_h is invertible) maps
object twists to joint velocities and the reduced dynamics are

    M~ = M_o + P^T M P,   C~ x_dot = C_o x_dot + P^T (M P_dot + C P) x_dot,   N~ = N_o + P^T g(q),   F = P^T tau,

which are (5.25) for invertible J_h.  Definition 5.1 holds for any P: M~ is symmetric positive definite and
M~_dot - 2 C~ is skew-symmetric (P^T (M_dot - 2 C) P plus P_dot^T M P - P^T M P_dot).  The reduction is exact only
for object twists the grasp allows (G^T x_dot in the range of J_h): :func:`grasp_mobility` gives that subspace;
for three point contacts on the BH8-280 it has 5 dimensions, not 6, so one object motion needs rolling or sliding.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import pinocchio as pin

from bhgrasp._validation import as_array, as_positive, as_vector
from bhgrasp.errors import InputError
from bhgrasp.grasp import _frames, _grasp_map, contact_frames
from bhgrasp.hand import Hand


@dataclass(frozen=True)
class GraspDynamics:
    """Reduced hand-object dynamics at one instant (object coordinates: COM velocity and angular velocity, world).

    Attributes:
        mass: M~ (6, 6).
        coriolis: C~ (6, 6), with C~ x_dot the velocity-product wrench.
        gravity: N~ (6,) [N, N m].
        joint_map: P = J_h^+ G^T (nv, 6): joint velocities of an object twist; ``P.T @ tau`` is F of (5.25).
        grasp_map: G (6, 3n) at the centre of mass.
        hand_jacobian: J_h (3n, nv).
        joint_map_rate: P_dot (nv, 6) along the current motion [1/s].
    """

    mass: np.ndarray
    coriolis: np.ndarray
    gravity: np.ndarray
    joint_map: np.ndarray
    grasp_map: np.ndarray
    hand_jacobian: np.ndarray
    joint_map_rate: np.ndarray


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
        return ObjectState(self.mass, self.inertia_body, self.com + dt * v, pin.exp3(dt * omega) @ self.rotation,
                           self.twist)  # fmt: skip


def grasp_kinematics(
    hand: Hand, q: Any, obj: ObjectState, points_body: Any, normals_body: Any, links: Any, step: float = 1e-6
) -> GraspKinematics:
    """P = J_h^+ G^T, its rate P_dot, G and J_h for contacts fixed on the object (body frame) and on hand links.

    Arguments as :func:`grasp_dynamics`.  P_dot is the central difference of P along the motion: the object
    advanced and retreated by ``step`` [s] at its twist, the joints by P x_dot (no numerical derivative of the
    kinematics themselves: each P is exact).
    """
    q = as_vector(q, "q", hand.nq)
    points_body = as_array(points_body, "points_body", (None, 3))
    normals_body = as_array(normals_body, "normals_body", (points_body.shape[0], 3))
    count = points_body.shape[0]
    if isinstance(links, str) or len(links) != count or not all(isinstance(link, str) for link in links):
        raise InputError(f"`links` must be {count} frame name(s), one per contact, got {links!r}")
    if not isinstance(obj, ObjectState):
        raise InputError(f"`obj` must be an ObjectState, got {type(obj).__name__}")
    twist = as_vector(obj.twist, "obj.twist", 6)
    step = as_positive(step, "step")
    unit_body = contact_frames(normals_body)[:, :, 2]  # validated, normalised
    world_aligned = np.broadcast_to(np.eye(3), (count, 3, 3))

    def joint_map(configuration: np.ndarray, state: ObjectState) -> tuple[np.ndarray, ...]:
        # P = J_h^+ G^T does not depend on the contact frames (R^T cancels), so P is built world-aligned
        points = state.com + points_body @ state.rotation.T
        jacobian = hand.point_jacobians(configuration, links, points)  # (n, 3, nv) world
        pinv = np.linalg.pinv(jacobian.reshape(3 * count, hand.nv))
        grasp = _grasp_map(points, world_aligned, state.com)
        return pinv @ grasp.T, jacobian, pinv, points

    p_map, jacobian_world, pinv_world, points = joint_map(q, obj)
    q_dot = p_map @ twist
    ahead = joint_map(pin.integrate(hand.model, q, step * q_dot), obj.advanced(step))[0]
    behind = joint_map(pin.integrate(hand.model, q, -step * q_dot), obj.advanced(-step))[0]
    frames = _frames(unit_body @ obj.rotation.T)  # contact coordinates: J_h = R^T J, J_h^+ = J^+ R, G = G_w R
    jacobian = np.einsum("nji,njk->nik", frames, jacobian_world).reshape(3 * count, hand.nv)
    pinv = np.einsum("vni,nij->vnj", pinv_world.reshape(hand.nv, count, 3), frames).reshape(hand.nv, 3 * count)
    grasp = _grasp_map(points, frames, obj.com)
    return GraspKinematics(p_map, (ahead - behind) / (2.0 * step), grasp, jacobian, pinv)


def grasp_dynamics(
    hand: Hand,
    q: Any,
    obj: ObjectState,
    points_body: Any,
    normals_body: Any,
    links: Any,
    gravity: Any = (0.0, 0.0, -9.81),
    step: float = 1e-6,
) -> GraspDynamics:
    """M~, C~, N~ and P of (5.25) for contacts fixed on the object (body frame) and on hand links.

    Args:
        hand: The hand (any :class:`Hand`).
        q: Joint positions [rad]; the joint velocities are those the object twist implies, q_dot = P x_dot.
        obj: The object's inertia and motion.
        points_body, normals_body: (n, 3) contact points [m] and inward normals in the object's body frame (about
            its COM): contacts move with the object.
        links: n link frame names of the hand that carry the contacts.
        gravity: World gravity [m/s^2].
        step: Time step [s] of the central difference that gives P_dot along the motion.
    """
    if not isinstance(obj, ObjectState):
        raise InputError(f"`obj` must be an ObjectState, got {type(obj).__name__}")
    as_positive(obj.mass, "obj.mass")
    gravity = as_vector(gravity, "gravity", 3)
    kinematics = grasp_kinematics(hand, q, obj, points_body, normals_body, links, step)
    q = np.asarray(q, dtype=float)
    p_map, p_dot = kinematics.joint_map, kinematics.joint_map_rate
    twist = np.asarray(obj.twist, dtype=float)
    q_dot = p_map @ twist

    inertia = obj.inertia_world
    omega = twist[3:]
    mass_o = np.zeros((6, 6))
    mass_o[:3, :3] = obj.mass * np.eye(3)
    mass_o[3:, 3:] = inertia
    coriolis_o = np.zeros((6, 6))
    coriolis_o[3:, 3:] = pin.skew(omega) @ inertia  # omega x (I omega): with M_o_dot - 2 C_o skew-symmetric
    mass_h = hand.mass_matrix(q)
    coriolis_h = hand.coriolis_matrix(q, q_dot)
    gravity_o = np.concatenate((-obj.mass * gravity, np.zeros(3)))
    mass = mass_o + p_map.T @ mass_h @ p_map
    coriolis = coriolis_o + p_map.T @ (mass_h @ p_dot + coriolis_h @ p_map)
    return GraspDynamics(0.5 * (mass + mass.T), coriolis, gravity_o + p_map.T @ hand.gravity_torques(q), p_map,
                         kinematics.grasp_map, kinematics.hand_jacobian, p_dot)  # fmt: skip


def grasp_mobility(grasp: Any, jacobian: Any, tolerance: float = 1e-9) -> np.ndarray:
    """Orthonormal basis (6, k) of the object twists the grasp allows: G^T x_dot in the range of J_h.

    These are the object motions the fingers can produce while every contact neither slides nor rolls; k < 6
    means some object motion is impossible for this grasp.
    """
    grasp = as_array(grasp, "grasp", (6, None))
    jacobian = as_array(jacobian, "jacobian", (grasp.shape[1], None))
    constraint = np.hstack((grasp.T, -jacobian))
    _, singular, vt = np.linalg.svd(constraint)
    rank = int(np.sum(singular > tolerance * max(1.0, singular[0])))
    null = vt[rank:].T  # (6 + nv, dim): joint and object velocities that keep the contacts
    if null.shape[1] == 0:
        return np.zeros((6, 0))
    u, s, _ = np.linalg.svd(null[:6], full_matrices=False)
    return u[:, s > tolerance]


__all__ = ["GraspDynamics", "GraspKinematics", "ObjectState", "grasp_dynamics", "grasp_kinematics", "grasp_mobility"]
