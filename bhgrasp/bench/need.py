"""What the protocol's loads need of the hand at a trial's grasp: the least fraction of the finger joints' ratings.

At the held sample (lifted, before the shake) the fingers' contacts on the object (one per finger, as a grasp
controller senses them) carry its weight, and through the shake its weight and each push in turn (10 m newtons along
+-x, +-y, +-z, turned with the hand's heading: :func:`~bhgrasp.bench.trial.shake_force`).  For each of these seven
loads, :func:`~bhgrasp.grasp.hold_torque.least_hold_torque` gives the least fraction of the ratings (the hand's
effort limits) of the joints the envelope checks, the fingers' inner and outer joints
(:func:`~bhgrasp.bench.metrics.joint_load`), with which any contact forces inside the true friction's cones
(:data:`~bhgrasp.bench.protocol.FRICTION`) carry it at rest, on top of the fingers' own weight; the spreads and the
wrist are left free, as the envelope leaves them.  The need is the largest of the seven.

It is a lower bound of the envelope's ``torque_to_rating`` at that grasp under the quasi-static loads: above 1, no
force distribution carries the protocol within the ratings there, whatever the drive does; below it, one does, and a
trial outside the envelope pressed harder than its grasp needed.
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin

import bhgrasp as bh
from bhgrasp.bench.protocol import FRICTION
from bhgrasp.grasp.frames import contact_frames, grasp_map_from_frames, hand_jacobian
from bhgrasp.grasp.hold_torque import least_hold_torque
from bhgrasp.grasp.sensing import ContactSensing
from bhgrasp.model.hand import STANDARD_GRAVITY
from bhgrasp.scenarios.estimation import state_at

PUSH = 10.0  # [N per kg of the object] the shake's push (bench.trial.shake_force)
GRAVITY = -STANDARD_GRAVITY[2]  # [m/s^2] the simulated hand's (bhgrasp.model.hand)


def protocol_loads(mass: float, heading: float = 0.0) -> np.ndarray:
    """(7, 6) wrenches [N, N m] the contacts must exert on the object: its weight, then with each push in turn."""
    axes = np.eye(3)[[0, 0, 1, 1, 2, 2]] * np.array([1.0, -1.0, 1.0, -1.0, 1.0, -1.0])[:, None]
    axes = axes @ pin.rpy.rpyToMatrix(0.0, 0.0, heading).T
    forces = np.vstack((np.zeros(3), PUSH * mass * axes)) + np.array([0.0, 0.0, -mass * GRAVITY])  # on the object
    return np.hstack((-forces, np.zeros((7, 3))))


def protocol_need(trajectory, hand: bh.Hand, k: int, mass: float, heading: float = 0.0) -> tuple[float | None, str]:
    """The need (the module's) at sample ``k`` and the joint that sets it; ``(None, "")`` when nothing holds the object.

    ``None`` also when no forces inside the cones carry some load at all (the grasp cannot hold it by friction).
    """
    state = state_at(trajectory, k)
    touching = [c for c in ContactSensing(hand).fingers(state, trajectory.object_names[0]).values() if c.link]
    if not touching:
        return None, ""
    points, normals = np.array([c.point for c in touching]), np.array([c.normal for c in touching])
    grasp = grasp_map_from_frames(points, contact_frames(normals), state.object_poses[0].translation)
    jacobian = hand_jacobian(hand, state.q, points, [c.link for c in touching], normals)
    joints = [hand.joint_index(f"{f}_{j}") for f in hand.fingers for j in ("proximal", "distal")]
    limits = np.full(hand.nv, math.inf)
    limits[joints] = hand.effort_limit[joints]
    offset = hand.gravity_torques(state.q)
    holds = [least_hold_torque(grasp, jacobian, w, FRICTION, limits, offset) for w in protocol_loads(mass, heading)]
    worst = max(holds, key=lambda hold: hold.fraction)
    if not math.isfinite(worst.fraction):
        return None, ""
    return worst.fraction, hand.joint_names[worst.joint]


__all__ = ["PUSH", "protocol_loads", "protocol_need"]
