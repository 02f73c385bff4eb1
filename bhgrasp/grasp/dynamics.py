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

P and its rate P_dot come from :func:`~bhgrasp.grasp.kinematics.grasp_kinematics`, analytic (its module derives them).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import pinocchio as pin

from bhgrasp._validation import as_array, as_positive, as_vector
from bhgrasp.errors import InputError
from bhgrasp.grasp.kinematics import ObjectState, grasp_kinematics
from bhgrasp.model.hand import Hand


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


def grasp_dynamics(
    hand: Hand,
    q: Any,
    obj: ObjectState,
    points_body: Any,
    normals_body: Any,
    links: Any,
    gravity: Any = (0.0, 0.0, -9.81),
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
    """
    if not isinstance(obj, ObjectState):
        raise InputError(f"`obj` must be an ObjectState, got {type(obj).__name__}")
    as_positive(obj.mass, "obj.mass")
    gravity = as_vector(gravity, "gravity", 3)
    kinematics = grasp_kinematics(hand, q, obj, points_body, normals_body, links)
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
    return GraspDynamics(
        0.5 * (mass + mass.T),
        coriolis,
        gravity_o + p_map.T @ hand.gravity_torques(q),
        p_map,
        kinematics.grasp_map,
        kinematics.hand_jacobian,
        p_dot,
    )


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


__all__ = ["GraspDynamics", "grasp_dynamics", "grasp_mobility"]
