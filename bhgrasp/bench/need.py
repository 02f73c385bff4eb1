"""What the protocol's loads need of the hand at a trial's grasp: the least fraction of the finger joints' ratings.

At the held sample (lifted, before the shake) every contact point between the hand (fingers and palm) and the object
carries its weight, and through the shake its weight and each push in turn (:data:`~bhgrasp.bench.protocol.PUSH`
newtons per kilogram along +-x, +-y, +-z, turned with the hand's heading: :func:`~bhgrasp.bench.protocol.push_axes`).
For each of these seven loads, :func:`~bhgrasp.grasp.hold_torque.least_hold_torque` gives the least fraction of the
ratings (the hand's effort limits) of the joints the envelope checks, the fingers' inner and outer joints
(:func:`~bhgrasp.bench.metrics.joint_load`), with which forces at those contact points, inside pyramids that hold the
true friction's cones (:data:`~bhgrasp.bench.protocol.FRICTION`, ``cone="circumscribed"``), carry it at rest, on top of
the fingers' own weight; the spreads and the wrist are left free, as the envelope leaves them.  The need is the
largest of the seven.

The simulated hand-object forces lie in these pyramids (a pair's mu is at most FRICTION), so where the held sample is
static, the object touches only the hand and no finger joint rests on a stop, the weight's need is at most what the
joints carry there (``tests/test_bench_need.py`` checks those conditions and the bound on a held box).  The need is a
lower bound: the pyramids hold the cones with up to 1 / cos(pi / 8) - 1 = 8 % more friction at their edges.  For the
pushes it is the held grasp's: a push deforms the grasp by the millimetres it moves the object.  A trial outside the
envelope whose need is well below 1 pressed harder than its grasp needed; a need above 1 says its grasp cannot carry
the protocol's loads within the ratings.
"""

from __future__ import annotations

import math

import numpy as np

import bhgrasp as bh
from bhgrasp.bench.protocol import FRICTION, PUSH, push_axes
from bhgrasp.data import Trajectory
from bhgrasp.errors import SolverFailed
from bhgrasp.grasp.hold_torque import contact_maps, least_hold_torque
from bhgrasp.scenarios.estimation import state_at

NO_CONTACT = ""  # need_joint where the hand does not touch the object at the held sample
INFEASIBLE = "infeasible"  # need_joint where no forces in the cones carry some load (friction cannot hold it)
SOLVER_FAILED = "solver failed"  # need_joint where HiGHS stopped without an answer


def protocol_loads(mass: float, gravity: np.ndarray, heading: float = 0.0) -> np.ndarray:
    """(7, 6) wrenches [N, N m] the contacts must exert on the object: its weight, then with each push in turn.

    ``gravity`` (3,) [m/s^2] world; about the object's centre of mass (no torque).
    """
    on_object = np.vstack((np.zeros(3), PUSH * mass * push_axes(heading))) + mass * np.asarray(gravity, dtype=float)
    return np.hstack((-on_object, np.zeros((7, 3))))


def rated_joints(hand: bh.Hand) -> list[int]:
    """Velocity indices of the joints the envelope rates: each finger's inner then outer joint, finger by finger."""
    return [hand.joint_index(f"{f}_{j}") for f in hand.fingers for j in ("proximal", "distal")]


def rating_limits(hand: bh.Hand) -> np.ndarray:
    """(nv,) [N m]: the inner and outer finger joints' ratings (effort limits); inf on every other joint."""
    joints = rated_joints(hand)
    limits = np.full(hand.nv, math.inf)
    limits[joints] = hand.effort_limit[joints]
    return limits


def protocol_need(
    trajectory: Trajectory, hand: bh.Hand, k: int, mass: float, heading: float = 0.0
) -> tuple[float | None, str]:
    """The need (the module's) at sample ``k`` and the joint that sets it.

    ``(None, NO_CONTACT)`` when nothing of the hand touches the object; ``(None, INFEASIBLE)`` when no forces in the
    cones carry some load at all; ``(None, SOLVER_FAILED)`` if HiGHS stops without an answer.
    """
    state = state_at(trajectory, k)
    maps = contact_maps(hand, state, trajectory.object_names[0], contacts="point")
    if maps is None:
        return None, NO_CONTACT
    grasp, jacobian = maps
    limits, offset = rating_limits(hand), hand.gravity_torques(state.q)
    try:
        holds = [
            least_hold_torque(grasp, jacobian, w, FRICTION, limits, offset, cone="circumscribed")
            for w in protocol_loads(mass, hand.gravity, heading)
        ]
    except SolverFailed:
        return None, SOLVER_FAILED
    worst = max(holds, key=lambda hold: hold.fraction)  # the first of equals
    if not math.isfinite(worst.fraction):
        return None, INFEASIBLE
    return worst.fraction, hand.joint_names[worst.joint]


__all__ = [
    "INFEASIBLE",
    "NO_CONTACT",
    "SOLVER_FAILED",
    "protocol_loads",
    "protocol_need",
    "rated_joints",
    "rating_limits",
]
