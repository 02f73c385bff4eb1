"""Actuation models: Barrett couplings and TorqueSwitch breakaway (thesis 2.4.7), full actuation, saturation."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import bhgrasp as bh
from bhgrasp.barrett.transmission import MAX_MOTOR_TORQUE, PROXIMAL_RATIO
from bhgrasp.model.objects import Box
from bhgrasp.model.spring_mounted import SpringMounted
from bhgrasp.sim import Simulator
from bhgrasp.sim.actuation import BarrettActuation, FullyActuated
from bhgrasp.sim.contact_law import SpringDamper
from bhgrasp.sim.scene import Scene

PAIRS = ((1, 2), (4, 5), (6, 7))  # (proximal, distal) indices of F1, F2, F3


def test_free_closing_keeps_distal_at_a_third_of_proximal() -> None:
    hand = bh.BarrettHand()
    q0 = hand.configuration(F1_spread=0.3, F2_spread=0.3, F1_distal=0.1, F2_distal=0.05, F3_distal=0.2)
    sim = Simulator(Scene(hand), dt=1e-3, actuation=BarrettActuation(hand))
    trajectory = sim.run(
        lambda t, s: np.array([0.02, 0.03, 0.03, 0.03]), 0.5, state=sim.initial_state(q0), progress=False
    )
    q = trajectory.q
    for proximal, distal in PAIRS:
        offset = q0[distal] - q0[proximal] / 3  # distal = proximal / 3 + its offset, 125:375 gears
        np.testing.assert_allclose(q[:, distal] - q[:, proximal] / 3, offset, atol=1e-12)
        assert q[-1, proximal] > 0.2  # it really closed
    np.testing.assert_array_equal(q[:, 0], q[:, 3])  # F1 and F2 spread turn together
    assert not trajectory.modes.any()  # a free finger never breaks away
    # The motor's torque-speed line caps the speed (no saturation here): 0.03 N m is 141 % of the 0.0213 N m stall
    # torque, so the proximal joints settle near 1.41 x the 2.45 rad/s no-load speed (gravity and the distal load
    # shave a little off).
    speed = trajectory.v[-1, 1]
    assert speed == pytest.approx(0.03 / MAX_MOTOR_TORQUE * 2.4544, rel=0.05)


def _blocked_f3(duration: float, motor: callable) -> tuple:
    hand = bh.BarrettHand()
    obstacle = SpringMounted(
        Box(size=(0.04, 0.02, 0.02), mass=0.5, pose=pin.SE3(np.eye(3), np.array([0.0, 0.095, 0.115]))),
        direction=(0, 0, 1),
        stiffness=1e5,
        damping=50.0,
    )
    actuation = BarrettActuation(hand)
    sim = Simulator(Scene(hand, [obstacle]), dt=1e-3, actuation=actuation, contact=SpringDamper(5e4, 50.0))
    return sim.run(motor, duration, progress=False), actuation


def test_blocked_proximal_link_breaks_away_and_the_tip_curls() -> None:
    """Like GraspIt!'s breakaway DOF: the proximal link stops on the obstacle, the distal joint keeps closing."""
    trajectory, _ = _blocked_f3(2.0, lambda t, s: np.array([0.0, 0.0, 0.0, 0.01]))
    broken = trajectory.modes[:, 2] == 1
    assert broken.any() and not trajectory.modes[:, :2].any()
    k = int(np.argmax(broken))
    touching = trajectory.contact_count() > 0
    assert touching[:k].any()  # it broke away only after touching
    before, after = trajectory.q[:k], trajectory.q[k:]
    np.testing.assert_allclose(before[:, 7] - before[:, 6] / 3, 0.0, atol=1e-12)  # coupled until then
    assert np.ptp(after[:, 6]) < np.radians(0.5)  # the proximal joint holds
    assert after[-1, 7] - after[0, 7] > np.radians(10)  # the fingertip curls on
    assert trajectory.tau[k, 6] > 0.5  # the breaking step's clutch torque exceeded the threshold [N m] ...
    assert trajectory.v[k, 6] > 0.1  # ... while the link still moved [rad/s]: the switch reads no speed


def test_switch_rearms_when_the_finger_is_opened_to_its_stop() -> None:
    """Opening a broken finger: the tip returns to its stop, then the proximal link to its own; then it re-arms."""
    close_then_open = lambda t, s: np.array([0.0, 0.0, 0.0, 0.01 if t < 1.6 else -0.03])  # noqa: E731
    trajectory, actuation = _blocked_f3(3.0, close_then_open)
    assert trajectory.between(1.4, 1.6).modes[:, 2].all()  # broken while closing against the obstacle
    opened = trajectory.between(1.6, 3.0)
    phases = opened.modes[:, 2]
    assert {1.0, 2.0} <= set(phases.tolist()) and phases[-1] == 0.0  # broken -> re-opening -> armed
    tip_home = int(np.argmax(phases == 2.0))
    assert opened.q[tip_home, 7] <= 1e-3  # the fingertip reached its stop first
    assert opened.q[-1, 6] <= 1e-3  # the proximal link is back at its open stop
    assert not actuation.broken[2]


def test_fully_actuated_saturation() -> None:
    hand = bh.BarrettHand()
    saturated, free = FullyActuated(hand, saturate=True), FullyActuated(hand)
    u = np.full(8, 100.0)
    np.testing.assert_array_equal(saturated.joint_torques(u), hand.effort_limit)
    np.testing.assert_array_equal(free.joint_torques(u), u)


def test_barrett_motor_torques_through_the_gears() -> None:
    hand = bh.BarrettHand()
    actuation = BarrettActuation(hand, saturate=True, efficiency=0.4)
    tau = actuation.joint_torques(np.array([0.0, 1.0, 0.01, 0.0]))
    assert tau[1] == pytest.approx(0.4 * PROXIMAL_RATIO * MAX_MOTOR_TORQUE)  # 1 N m clipped to the 0.0213 N m limit
    assert tau[4] == pytest.approx(0.4 * PROXIMAL_RATIO * 0.01)  # through the worm's forward efficiency
    transmission = actuation.transmission()
    np.testing.assert_array_equal(transmission[:, 0], [1, 0, 0, 1, 0, 0, 0, 0])
    np.testing.assert_allclose(transmission[[1, 2], 1], [1.0, 1.0 / 3.0])


def test_barrett_actuation_needs_a_barrett_hand() -> None:
    finger = bh.thesis_two_link_finger()
    with pytest.raises(bh.InputError, match="the BH8-280 transmission needs a Barrett hand; `hand` lacks joints"):
        BarrettActuation(finger)
    with pytest.raises(bh.InputError, match="`breakaway_torque` must be a positive finite number"):
        BarrettActuation(bh.BarrettHand(), breakaway_torque=-1.0)
    with pytest.raises(bh.InputError, match=r"`efficiency` must be in \(0, 1\], got 1.5"):
        BarrettActuation(bh.BarrettHand(), efficiency=1.5)
    with pytest.raises(bh.InputError, match="`efficiency` must be a positive finite number"):
        BarrettActuation(bh.BarrettHand(), efficiency=0.0)
    with pytest.raises(bh.InputError, match="`damping` must be finite and >= 0"):
        FullyActuated(bh.BarrettHand(), damping=-0.1)
