"""Object-space grasp control on the reduced hand-object model: computed torque (5.32), natural (5.37), stiffness.

All three command the object generalised force F = M~ a + C~ v + N~ + F_fb of the reduced dynamics (5.29) with
(thesis' e_o = X_o - X_do, here e = (x - x_d, log(R R_d^T)), e_dot = twist - desired twist, world):

- ``"ctc"`` (5.30)/(5.32): a = X_dd_d - K_v e_dot - K_p e, v = X_dot (actual), F_fb = 0; K_p, K_v are acceleration
  gains [1/s^2, 1/s] and the closed loop is e_dd + K_v e_dot + K_p e = 0 for an exact model.
- ``"natural"`` (5.37): a = X_dd_d, v = X_dot_d, F_fb = -K_v e_dot - K_p e (wrench gains).  The printed (5.37)
  adds a second C~ X_dot; that would compensate the velocity-product wrench twice, so it is left out here.
- ``"stiffness"`` (5.38): a = X_dd_d - lambda e_dot, v = X_dot_d - lambda e, F_fb = -K_v e_dot - K_p e (the
  Slotine-Li / passivity form; the printed (5.38) is garbled: its "X_dot_o + lambda e_dot" under M~ is read as the
  reference acceleration X_dd_d - lambda e_dot).

The model wrench is split exactly as (5.25) is built: the object part M_o a + C_o v + N_o + F_fb must come from
the contacts (G f = w, distributed by the friction-cone QP or the thesis' pseudo-inverse (5.31)), and the hand
part is the fingers' own inverse dynamics along the grasp, tau_h = M (P a + P_dot v) + C(q, q_dot) P v + g(q) with
P = J_h^+ G^T; tau = J_h^T f + tau_h, so that P^T tau = M~ a + C~ v + N~ + F_fb whenever f is in the range of J_h.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pinocchio as pin

from bhgrasp._validation import as_positive
from bhgrasp.controllers.base import gain_vector
from bhgrasp.controllers.grasp_options import DEFAULT_GRASP, GraspOptions
from bhgrasp.controllers.grasping import GraspContacts, ObjectGraspController
from bhgrasp.data import State
from bhgrasp.errors import InputError
from bhgrasp.grasp.kinematics import GraspKinematics, ObjectState, contact_kinematics, parent_joints
from bhgrasp.model.hand import Hand
from bhgrasp.model.objects import RigidObject
from bhgrasp.motion.trajectories import Reference

LAWS = ("ctc", "natural", "stiffness")


def pose_gains(value: Any, name: str, allow_zero: bool = False) -> np.ndarray:
    """Six object gains from a scalar, a (translation, rotation) pair or six values."""
    array = np.asarray(value, dtype=float)
    if array.shape == (2,):
        array = np.repeat(array, 3)
    return gain_vector(array if array.ndim else float(array), 6, name, allow_zero)


def object_model(obj: ObjectState, gravity: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """M_o (6, 6), C_o (6, 6) (omega x I omega form, M_o_dot - 2 C_o skew) and N_o (6,) of a rigid body at its COM."""
    inertia = obj.inertia_world
    mass = np.zeros((6, 6))
    mass[:3, :3] = obj.mass * np.eye(3)
    mass[3:, 3:] = inertia
    coriolis = np.zeros((6, 6))
    coriolis[3:, 3:] = pin.skew(obj.twist[3:]) @ inertia
    return mass, coriolis, np.concatenate((-obj.mass * gravity, np.zeros(3)))


def grasp_maps(hand: Hand, state: State, contacts: GraspContacts, obj: RigidObject):
    """The controller's model of the grasp now: the object's state and the grasp's maps P, P_dot, G, J_h of (5.25).

    The sensed contacts are taken as fixed on the object and on their links (P_dot analytic, see
    :mod:`bhgrasp.grasp.kinematics`; two kinematics passes).  The laws need only these maps: the fingers' share of
    M~, C~, N~ enters through :func:`hand_part`.
    """
    pose = state.object_poses[0]
    current = ObjectState(
        obj.mass, obj.inertia, pose.translation, pose.rotation, np.asarray(state.object_twists[0], dtype=float)
    )
    joints = parent_joints(hand, contacts.links)
    return current, contact_kinematics(hand, state.q, current, contacts.points, contacts.frames, joints)


def hand_part(hand: Hand, state: State, maps: GraspKinematics, acceleration, velocity) -> np.ndarray:
    """The fingers' inverse dynamics along the grasp: M (P a + P_dot v) + C(q, q_dot) P v + g(q) [N m]."""
    p_map, p_dot = maps.joint_map, maps.joint_map_rate
    return hand.slotine_li_torque(state.q, state.v, p_map @ velocity, p_map @ acceleration + p_dot @ velocity)


class ObjectSpaceController(ObjectGraspController):
    """Track an object pose with the reduced hand-object model: ``law`` = "ctc", "natural" or "stiffness".

    Logs, besides the base's: ``object_force`` (the object part of F), ``hand_torque`` (tau_h).
    """

    def __init__(
        self,
        nominal: Hand,
        nominal_object: RigidObject,
        law: str = "ctc",
        reference: Reference | None = None,
        kp: Any = None,
        kv: Any = None,
        lam: float = 10.0,
        options: GraspOptions = DEFAULT_GRASP,
    ) -> None:
        """Set up the law.

        Args:
            nominal: The controller's hand model.
            nominal_object: The controller's model of the object (mass, inertia about the COM; may be wrong).
            law: ``"ctc"`` (5.32), ``"natural"`` (5.37) or ``"stiffness"`` (5.38).
            reference: Object pose reference of size 6 (see :class:`ObjectGraspController`); ``None`` holds.
            kp, kv: Scalar, (translation, rotation) or six gains.  "ctc": acceleration gains [1/s^2], [1/s]
                (default 400, 40: critically damped at 20 rad/s).  "natural"/"stiffness": wrench gains [N/m, N m/rad],
                [N s/m, N m s/rad] (default (60, 0.05), (20, 0.002); the thesis' K_p = 60, K_v = 20 for translation).
            lam: lambda [1/s] of the stiffness law (the thesis' 0.01 barely differs from the natural law).
            options: The shared options, as in the base.
        """
        super().__init__(nominal, reference, options)
        if law not in LAWS:
            raise InputError(f"`law` must be one of {LAWS}, got {law!r}")
        if not isinstance(nominal_object, RigidObject):
            raise InputError(f"`nominal_object` must be a bhgrasp RigidObject (e.g. Box), got {nominal_object!r}")
        self.law = law
        self.nominal_object = nominal_object
        ctc = law == "ctc"
        self.kp = pose_gains((400.0 if ctc else (60.0, 0.05)) if kp is None else kp, "kp")
        self.kv = pose_gains((40.0 if ctc else (20.0, 0.002)) if kv is None else kv, "kv")
        self.lam = as_positive(lam, "lam")

    def grasp_torques(self, t: float, dt: float, state: State, contacts: GraspContacts) -> np.ndarray:
        """Tau = J_h^T f + tau_h for the law's (a, v, F_fb)."""
        hand = self.nominal
        current, maps = grasp_maps(hand, state, contacts, self.nominal_object)
        contacts.reference = current.com
        error, velocity_error, velocity, acceleration = self.errors(t, state)
        feedback = np.zeros(6)
        if self.law == "ctc":
            acceleration = acceleration - self.kv * velocity_error - self.kp * error
            velocity = current.twist
        else:
            feedback = -self.kv * velocity_error - self.kp * error
            if self.law == "stiffness":
                acceleration = acceleration - self.lam * velocity_error
                velocity = velocity - self.lam * error
        mass, coriolis, gravity = object_model(current, self.gravity)
        wrench = mass @ acceleration + coriolis @ velocity + gravity + feedback
        forces = self.distribute(contacts, wrench)
        tau_h = hand_part(hand, state, maps, acceleration, velocity)
        self.log["object_force"], self.log["hand_torque"] = wrench, tau_h
        forces = self.limit_squeeze(contacts, forces, lambda f: maps.hand_jacobian.T @ f.ravel() + tau_h)
        return maps.hand_jacobian.T @ forces.ravel() + tau_h


__all__ = ["LAWS", "ObjectSpaceController", "grasp_maps", "object_model", "pose_gains"]
