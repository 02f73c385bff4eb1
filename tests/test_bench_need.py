"""What the grasp benchmark's loads need of the ratings at a trial's held grasp (bhgrasp.bench.need)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bhgrasp.bench.need import GRAVITY, PUSH, protocol_loads, protocol_need
from bhgrasp.bench.protocol import FRICTION, HELD_AT, BenchObject, Trial
from bhgrasp.bench.trial import simulate_trial
from bhgrasp.grasp.frames import contact_frames, grasp_map_from_frames, hand_jacobian
from bhgrasp.grasp.hold_torque import least_hold_torque
from bhgrasp.grasp.sensing import ContactSensing
from bhgrasp.scenarios.estimation import state_at


def test_the_loads_are_the_weight_and_each_push_turned_with_the_hand() -> None:
    mass, heading = 0.5, 0.3
    loads = protocol_loads(mass, heading)
    np.testing.assert_allclose(loads[0], [0, 0, mass * GRAVITY, 0, 0, 0])  # the contacts carry the weight
    pushes = -(loads[1:, :3] - loads[0, :3])  # what each push adds, on the object
    np.testing.assert_allclose(np.linalg.norm(pushes, axis=1), PUSH * mass)
    turned = np.array([math.cos(heading), math.sin(heading), 0.0])
    np.testing.assert_allclose(pushes[0] / (PUSH * mass), turned, atol=1e-15)  # +x turned about z
    np.testing.assert_allclose(pushes[4] / (PUSH * mass), [0, 0, 1], atol=1e-15)  # +z stays
    assert np.all(loads[:, 3:] == 0.0)  # about the centre of mass: no torque


@pytest.fixture(scope="module")
def held_box():
    """The development box held after the lift (the protocol up to the shake)."""
    trial = Trial(BenchObject.parse("box:0.06x0.05x0.05:0.3"), "power")
    trajectory, hand = simulate_trial(trial, duration=HELD_AT)
    return trial, trajectory, hand


def test_the_need_is_the_largest_loads_least_torque_on_the_inner_and_outer_joints(held_box) -> None:
    trial, trajectory, hand = held_box
    k = len(trajectory.t) - 1
    need, joint = protocol_need(trajectory, hand, k, trial.item.mass)
    assert 0.0 < need < 1.0 and joint.endswith(("proximal", "distal"))
    # the same LP by hand: the spreads and the wrist free, the inner and outer joints at their ratings
    state = state_at(trajectory, k)
    touching = [c for c in ContactSensing(hand).fingers(state, trajectory.object_names[0]).values() if c.link]
    assert len(touching) == 3
    points, normals = np.array([c.point for c in touching]), np.array([c.normal for c in touching])
    grasp = grasp_map_from_frames(points, contact_frames(normals), state.object_poses[0].translation)
    jacobian = hand_jacobian(hand, state.q, points, [c.link for c in touching], normals)
    limits = np.full(hand.nv, math.inf)
    for finger in hand.fingers:
        for part in ("proximal", "distal"):
            index = hand.joint_index(f"{finger}_{part}")
            limits[index] = hand.effort_limit[index]
    fractions = [
        least_hold_torque(grasp, jacobian, w, FRICTION, limits, hand.gravity_torques(state.q)).fraction
        for w in protocol_loads(trial.item.mass)
    ]
    assert need == max(fractions) and fractions[0] < need  # a push needs more than the weight alone
    # the ratings scale the fraction: half the ratings, twice the fraction of each load
    half = [
        least_hold_torque(grasp, jacobian, w, FRICTION, limits / 2, hand.gravity_torques(state.q)).fraction
        for w in protocol_loads(trial.item.mass)
    ]
    np.testing.assert_allclose(half, 2 * np.array(fractions), rtol=1e-6)


def test_nothing_held_needs_nothing(held_box) -> None:
    trial, trajectory, hand = held_box
    assert protocol_need(trajectory, hand, 0, trial.item.mass) == (None, "")  # the open hand above the box
