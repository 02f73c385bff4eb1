"""The least joint torque with which a grasp can exert a wrench: can the hand's actuators hold the object at all?

Contact forces f (contact frames (t1, t2, n), forces on the object, :mod:`~bhgrasp.grasp.frames`) exert ``G f`` on the
object and load the joints with ``J_h^T f`` (thesis (5.20): at rest the hand's joints carry ``tau = tau_0 + J_h^T f``,
``tau_0`` what they carry anyway, the fingers' own weight).  With a torque limit L_j > 0 on each joint, the linear
program

    min_{f, s}  s   s.t.   G f = w,   f_i in a friction pyramid of mu,   f_n,i >= f_min,
                           -s L_j <= tau_0,j + (J_h^T f)_j <= s L_j   for every limited joint j

gives s*, the smallest fraction of its limits that every joint can stay within while these contacts exert w.  With
every limit 1 N m, s* is the least peak joint torque [N m].  Two pyramids (``cone``):

- ``"inscribed"`` (the force QP's, :mod:`~bhgrasp.grasp.forces`): inside the cone, the forces a controller assuming
  ``mu`` may command.  s* > 1: none of those holds w within the limits, whatever the controller distributes.
- ``"circumscribed"``: the pyramid whose faces touch the cone (slope mu / cos(pi / facets) on its edges), which holds
  every force of the cone.  Then s* is a lower bound: forces a Coulomb contact of ``mu`` can take, at these contacts,
  need at least s* of the limits to hold w at rest.

Solved with HiGHS (``scipy.optimize.linprog``, imported when called): one LP of 3n + 1 variables, bounded cost.
:func:`least_hold_torque` takes the maps; :func:`static_hold_torque` reads them off a state's contacts with one
object, as a controller senses them (one per finger) or point by point (every contact point on its own link, the
palm's too).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from bhgrasp._validation import as_array, as_real, as_vector
from bhgrasp.data import State
from bhgrasp.errors import InputError, SolverFailed
from bhgrasp.grasp.cones import friction_pyramid
from bhgrasp.grasp.frames import contact_frames, grasp_map_from_frames, hand_jacobian
from bhgrasp.grasp.sensing import ContactSensing
from bhgrasp.model.hand import Hand
from bhgrasp.model.hand_joints import finger_indices

CONES = ("inscribed", "circumscribed")
CONTACTS = ("finger", "point")


@dataclass(frozen=True)
class HoldTorque:
    """The least-torque way of exerting a wrench (:func:`least_hold_torque`).

    Attributes:
        fraction: s*, the least max_j |tau_j| / L_j over the pyramids' forces that exert the wrench; ``inf`` when no
            such forces exert it at any torque (``forces`` and ``torques`` are then ``None``).
        forces: (n, 3) contact-frame forces [N] that reach it (one of them, when several do).
        torques: (nv,) joint torques tau_0 + J_h^T f [N m] of those forces.
        joint: Index of the limited joint at the largest fraction of its limit (the first of equals; -1 when
            infeasible).
    """

    fraction: float
    forces: np.ndarray | None
    torques: np.ndarray | None
    joint: int

    @property
    def within(self) -> bool:
        """Whether some of the pyramids' forces exert the wrench with every joint within its limit (s* <= 1)."""
        return self.fraction <= 1.0


def least_hold_torque(
    grasp_map: Any,
    hand_jacobian: Any,
    wrench: Any,
    mu: float,
    limits: Any = 1.0,
    offset: Any = None,
    min_normal_force: float = 0.0,
    facets: int = 8,
    cone: str = "inscribed",
) -> HoldTorque:
    """s* of the module's linear program, and the forces and joint torques that reach it.

    Args:
        grasp_map: G (6, 3n) about the object's reference point.
        hand_jacobian: J_h (3n, nv) in the same contact coordinates (:func:`~bhgrasp.grasp.frames.hand_jacobian`).
        wrench: w (6,) [N, N m] the contacts must exert on the object, about the same point.
        mu: Friction coefficient (>= 0).
        limits: L (nv,) or one value [N m] > 0 per joint; ``inf`` leaves a joint unlimited.
        offset: tau_0 (nv,) [N m] the joints carry besides the contacts (default 0).
        min_normal_force: f_min [N] >= 0.
        facets: Sides of each pyramid (>= 3).
        cone: ``"inscribed"`` or ``"circumscribed"`` pyramids (module docstring).

    Raises:
        InputError: Bad shapes, non-finite values, a limit <= 0, no limited joint, or an unknown ``cone``.
        SolverFailed: HiGHS stopped without an answer (an iteration limit or numerical trouble).
    """
    grasp = as_array(grasp_map, "grasp_map", (6, None))
    if grasp.shape[1] == 0 or grasp.shape[1] % 3:
        raise InputError(f"`grasp_map` must have shape (6, 3n), got shape {grasp.shape}")
    n = grasp.shape[1] // 3
    jacobian = as_array(hand_jacobian, "hand_jacobian", (3 * n, None))
    nv = jacobian.shape[1]
    w = as_vector(wrench, "wrench", 6)
    try:
        limit = np.array(np.broadcast_to(np.asarray(limits, dtype=float), (nv,)))
    except (TypeError, ValueError) as error:
        raise InputError(f"`limits` must be one number or {nv} numbers > 0 [N m], got {limits!r}") from error
    if np.any(np.isnan(limit)) or np.any(limit <= 0.0):
        raise InputError(f"`limits` must be > 0 [N m] (inf: unlimited), got {limit}")
    tau_0 = np.zeros(nv) if offset is None else as_vector(offset, "offset", nv)
    f_min = as_real(min_normal_force, "min_normal_force")
    if cone not in CONES:
        raise InputError(f"`cone` must be one of {CONES}, got {cone!r}")
    from scipy.optimize import linprog  # here: importing bhgrasp.grasp does not import scipy

    limited = np.flatnonzero(np.isfinite(limit))
    if not len(limited):
        raise InputError("`limits` must limit at least one joint (all are inf)")
    mu = as_real(mu, "mu")
    pyramid, _ = friction_pyramid(mu, facets)
    if cone == "circumscribed":  # faces moved out to touch the cone: slope mu / cos(pi / facets) on the edges
        pyramid, _ = friction_pyramid(mu / math.cos(math.pi / len(pyramid)), len(pyramid))

    size = 3 * n + 1  # x = (f, s)
    cones = np.zeros((n * len(pyramid), size))
    for i in range(n):
        cones[i * len(pyramid) : (i + 1) * len(pyramid), 3 * i : 3 * i + 3] = pyramid
    torque = jacobian.T[limited] / limit[limited, None]  # (J_h^T f)_j / L_j
    upper = np.hstack((torque, -np.ones((len(limited), 1))))  # tau_j / L_j - s <= -tau_0,j / L_j
    lower = np.hstack((-torque, -np.ones((len(limited), 1))))  # -tau_j / L_j - s <= tau_0,j / L_j
    scaled_offset = tau_0[limited] / limit[limited]
    result = linprog(
        np.eye(size)[-1],
        A_ub=np.vstack((cones, upper, lower)),
        b_ub=np.concatenate((np.zeros(len(cones)), -scaled_offset, scaled_offset)),
        A_eq=np.hstack((grasp, np.zeros((6, 1)))),
        b_eq=w,
        bounds=[(None, None), (None, None), (f_min, None)] * n + [(0.0, None)],
        method="highs",
    )
    if result.status == 2:  # infeasible: no forces of the pyramids exert w
        return HoldTorque(math.inf, None, None, -1)
    if result.status != 0:  # s >= 0 bounds it below: not unbounded
        raise SolverFailed(
            f"the hold-torque LP stopped without an answer (HiGHS status {result.status}): {result.message}"
        )
    forces = result.x[:-1].reshape(n, 3)
    torques = tau_0 + jacobian.T @ result.x[:-1]
    ratios = np.abs(torques[limited]) / limit[limited]
    return HoldTorque(float(result.x[-1]), forces, torques, int(limited[np.argmax(ratios)]))


def grasp_contacts(
    hand: Hand, state: State, body: str, contacts: str = "finger"
) -> tuple[np.ndarray, np.ndarray, list[str]] | None:
    """The hand's contacts with ``body`` in ``state``: (points (n, 3), normals (n, 3), link names), or ``None``.

    ``contacts``: ``"finger"``, one per finger pressing ``body``, as a grasp controller senses them
    (:class:`~bhgrasp.grasp.sensing.ContactSensing`: the force-weighted point and normal, on the link that presses
    hardest); ``"point"``, every contact point between a frame of the hand (the palm's too) and ``body``.
    """
    if contacts not in CONTACTS:
        raise InputError(f"`contacts` must be one of {CONTACTS}, got {contacts!r}")
    if contacts == "finger":
        touching = [c for c in ContactSensing(hand).fingers(state, body).values() if c.link is not None]
        rows = [(c.point, c.normal, c.link) for c in touching]
    else:
        model = hand.model
        rows = [
            (point, normal, link)
            for point, normal, (link, other) in zip(state.contact_points, state.contact_normals, state.contact_bodies)
            if other == body and model.existFrame(link)
        ]
    if not rows:
        return None
    return np.array([r[0] for r in rows]), np.array([r[1] for r in rows]), [r[2] for r in rows]


def contact_maps(hand: Hand, state: State, body: str, contacts: str = "finger") -> tuple[np.ndarray, np.ndarray] | None:
    """G (6, 3n) about object 0's position and J_h (3n, nv) of :func:`grasp_contacts`, or ``None`` (no contact)."""
    found = grasp_contacts(hand, state, body, contacts)
    if found is None:
        return None
    points, normals, links = found
    grasp = grasp_map_from_frames(points, contact_frames(normals), state.object_poses[0].translation)
    return grasp, hand_jacobian(hand, state.q, points, links, normals)


def static_hold_torque(
    hand: Hand,
    state: State,
    body: str,
    mass: float,
    mu: float,
    limits: Any = None,
    contacts: str = "finger",
    **kw: Any,
) -> HoldTorque:
    """:func:`least_hold_torque` of the grasp of ``body`` (object 0 of ``state``, ``mass`` [kg]) holding it at rest.

    The contacts with ``body`` (:func:`grasp_contacts`); w the object's weight (the hand's gravity) reversed, about
    its position (its centre of mass); tau_0 the hand's gravity torques.  ``limits``: as :func:`least_hold_torque`'s;
    default 1 N m on every finger joint and none on the joints that move the whole hand (a wrist mount's), so that
    ``fraction`` is the least peak finger joint torque [N m].  ``kw``: ``min_normal_force``, ``facets``, ``cone``.
    Nothing touching the object: ``fraction`` ``inf``.

    Raises:
        InputError: No object in the state, or a bad argument.
    """
    if not state.object_poses:
        raise InputError("static_hold_torque needs the object's pose in the state (a scene with an object)")
    maps = contact_maps(hand, state, body, contacts)
    if maps is None:
        return HoldTorque(math.inf, None, None, -1)
    grasp, jacobian = maps
    if limits is None:
        limits = np.full(hand.nv, math.inf)
        limits[np.concatenate([finger_indices(hand, finger) for finger in hand.fingers])] = 1.0
    wrench = np.concatenate((-as_real(mass, "mass") * hand.gravity, np.zeros(3)))
    return least_hold_torque(grasp, jacobian, wrench, mu, limits, hand.gravity_torques(state.q), **kw)


__all__ = [
    "CONES",
    "CONTACTS",
    "HoldTorque",
    "contact_maps",
    "grasp_contacts",
    "least_hold_torque",
    "static_hold_torque",
]
