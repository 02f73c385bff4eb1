"""What the grasp benchmark's loads need of the ratings at a trial's held grasp (bhgrasp.bench.need)."""

from __future__ import annotations

import numpy as np
import pytest

from bhgrasp.bench.need import protocol_loads, protocol_need, rating_limits
from bhgrasp.bench.protocol import FRICTION, HELD_AT, SHAKE_TIME, BenchObject, Trial
from bhgrasp.bench.trial import shake_force, simulate_trial
from bhgrasp.grasp.frames import contact_frames, grasp_map_from_frames, hand_jacobian
from bhgrasp.grasp.hold_torque import grasp_contacts, least_hold_torque
from bhgrasp.scenarios.estimation import state_at


@pytest.mark.parametrize("heading", [0.0, 0.3])
def test_the_loads_are_the_weight_and_the_shakes_pushes(heading: float) -> None:
    """The contacts carry the weight, then the weight and each push the shake applies (its own function), reversed."""
    mass, gravity = 0.5, np.array([0.0, 0.0, -9.81])
    loads = protocol_loads(mass, gravity, heading)
    np.testing.assert_array_equal(loads[0], [0.0, 0.0, mass * 9.81, 0.0, 0.0, 0.0])
    shake = shake_force(mass, 1, heading)
    for k in range(6):
        push = shake(HELD_AT + (k + 0.5) * SHAKE_TIME)[0]
        np.testing.assert_allclose(loads[1 + k, :3], -(push + mass * gravity), atol=1e-15)
    assert np.all(loads[:, 3:] == 0.0)  # about the centre of mass: no torque


@pytest.fixture(scope="module")
def held_box():
    """The development box held after the lift (the protocol up to the shake)."""
    trial = Trial(BenchObject.parse("box:0.06x0.05x0.05:0.3"), "power")
    trajectory, hand = simulate_trial(trial, duration=HELD_AT)
    return trial, trajectory, hand


def test_the_weight_needs_no_more_than_the_held_grasp_carries(held_box) -> None:
    """The simulated contact forces are Coulomb forces of the protocol's mu at the held sample's contact points, so
    they are among the LP's (circumscribed pyramids): the least fraction of the ratings that carries the weight is
    at most what the joints carry there (the hand at rest: tau = g(q) + J_h^T f, tests/test_hold_torque.py)."""
    trial, trajectory, hand = held_box
    k = len(trajectory.t) - 1
    state, body = state_at(trajectory, k), trajectory.object_names[0]
    assert np.abs(state.v[6:]).max() < 1e-2  # the fingers at rest on the held box
    points, normals, links = grasp_contacts(hand, state, body, contacts="point")
    grasp = grasp_map_from_frames(points, contact_frames(normals), state.object_poses[0].translation)
    jacobian = hand_jacobian(hand, state.q, points, links, normals)
    limits = rating_limits(hand)
    weight = protocol_loads(trial.item.mass, hand.gravity)[0]
    least = least_hold_torque(
        grasp, jacobian, weight, FRICTION, limits, hand.gravity_torques(state.q), cone="circumscribed"
    )
    rated = np.isfinite(limits)
    carried = np.max(np.abs(trajectory.tau[k][rated]) / limits[rated])
    assert 0.0 < least.fraction <= carried
    need, joint = protocol_need(trajectory, hand, k, trial.item.mass)
    assert least.fraction < need < 1.0 and joint.endswith(("proximal", "distal"))  # a push needs more
    # the ratings scale the fraction: half the ratings, twice the fraction
    half = least_hold_torque(
        grasp, jacobian, weight, FRICTION, limits / 2, hand.gravity_torques(state.q), cone="circumscribed"
    )
    assert half.fraction == pytest.approx(2 * least.fraction, rel=1e-6)


def test_nothing_held_needs_nothing(held_box) -> None:
    trial, trajectory, hand = held_box
    assert protocol_need(trajectory, hand, 0, trial.item.mass) == (None, "")  # the open hand above the box
