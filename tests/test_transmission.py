"""The hand's drive models against independent truths: power through the gears, reflected damping, the TorqueSwitch
rule at its threshold, and motor commands that do a joint law's work (tests the controller and the simulator share)."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

import bhgrasp as bh
from bhgrasp.barrett.transmission import (
    DISTAL_ALONE_RATIO,
    MAX_MOTOR_TORQUE,
    MOTOR_DAMPING,
    PROXIMAL_RATIO,
    SPREAD_RATIO,
    STALL_TIP_FORCE,
    TIP_LEVER,
    WORM_EFFICIENCY,
    BarrettTransmission,
    switch_modes,
)
from bhgrasp.controllers.motor_commands import MotorCommands
from bhgrasp.model.transmission import DirectDrive
from bhgrasp.sim.actuation import Actuation, BarrettActuation

MODES = [np.array(modes) for modes in itertools.product((0, 1, 2), repeat=3)]
PROXIMAL, DISTAL = (1, 4, 6), (2, 5, 7)  # joint indices of F1, F2, F3


def motor_speeds(drive: BarrettTransmission, modes: np.ndarray, w: np.ndarray) -> np.ndarray:
    """Motor shaft speeds [rad/s] for driven velocities w: each motor turns at its gear ratio times its coordinate."""
    ratios = [SPREAD_RATIO] + [DISTAL_ALONE_RATIO if mode == 1 else PROXIMAL_RATIO for mode in modes]
    return np.array(ratios) * w


@pytest.mark.parametrize("modes", MODES, ids=lambda m: "".join(map(str, m)))
def test_motor_power_reaches_the_joints_and_reflected_damping_is_b_r_squared(modes: np.ndarray) -> None:
    """tau . v = u . (eta motor speeds) for every allowed motion v = T w (the worms pass eta of the finger motors'
    power, the spread gears all of it); w^T T^T D T w = b_m |motor speeds|^2 weighted the same way."""
    hand = bh.BarrettHand()
    for efficiency in (1.0, WORM_EFFICIENCY, 0.3):
        drive = BarrettTransmission(hand, damping=0.0, efficiency=efficiency)
        rng = np.random.default_rng(int("".join(map(str, modes)), 3))
        transmission, gears = drive.matrix(modes), drive.gears(modes)
        passed = np.array([1.0, efficiency, efficiency, efficiency])  # share of each motor's power at the joints
        for u, w in zip(rng.normal(size=(5, 4)), rng.normal(size=(5, 4))):
            speeds = motor_speeds(drive, modes, w)
            assert (gears @ u) @ (transmission @ w) == pytest.approx(u @ (passed * speeds), rel=1e-13)
            v = transmission @ w
            expected = MOTOR_DAMPING * speeds @ (passed * speeds)
            assert v @ (drive.joint_damping(modes) * v) == pytest.approx(expected, rel=1e-13)
    for finger, mode in enumerate(modes):  # the kinematics of each mode
        proximal, distal = PROXIMAL[finger], DISTAL[finger]
        column = transmission[:, finger + 1]
        expected = {0: (1.0, 1.0 / 3.0), 1: (0.0, 1.0), 2: (1.0, 0.0)}[int(mode)]  # outer link at 1/3 when armed
        assert (column[proximal], column[distal]) == pytest.approx(expected, rel=1e-15)
    np.testing.assert_array_equal(transmission[:, 0], [1, 0, 0, 1, 0, 0, 0, 0])  # one spread motor, F1 and F2


def test_stall_torque_times_the_gear_ratio_is_the_joint_torque() -> None:
    """Ideal gears: the URDF's effort limits (the puck limit through 125:1); the worms pass eta."""
    ideal = BarrettTransmission(bh.BarrettHand(), efficiency=1.0)
    stall = np.full(4, MAX_MOTOR_TORQUE)
    tau = ideal.joint_torques(stall, [0, 1, 2])
    assert tau[0] == pytest.approx(SPREAD_RATIO * MAX_MOTOR_TORQUE)  # 0.373 N m, the URDF's spread effort limit
    assert tau[1] == tau[7 - 1] == pytest.approx(PROXIMAL_RATIO * MAX_MOTOR_TORQUE)  # 2.67 N m: F1, F3 proximal
    assert tau[5] == pytest.approx(DISTAL_ALONE_RATIO * MAX_MOTOR_TORQUE)  # F2 broken away: 2 N m distal
    np.testing.assert_allclose(tau[[0, 1, 5]], bh.BarrettHand().effort_limit[[0, 1, 5]], rtol=1e-3)
    worm = BarrettTransmission(bh.BarrettHand()).joint_torques(stall, [0, 1, 2])
    eta = WORM_EFFICIENCY
    np.testing.assert_allclose(worm, tau * [1, eta, eta, 1, eta, eta, eta, eta], rtol=1e-15)  # the spread: no worm
    # the calibration: a broken-away finger's stall is Barrett's 20 N at 5 cm on the fingertip (1 N m distal)
    assert worm[5] == pytest.approx(STALL_TIP_FORCE * TIP_LEVER) == pytest.approx(1.0)


def test_the_torque_switch_breaks_away_exactly_above_its_threshold_and_re_arms_at_the_stops() -> None:
    """The proximal load decides, whatever the link's speed (the switch reads no velocity)."""
    hand = bh.BarrettHand()
    drive = BarrettTransmission(hand, breakaway_torque=0.5)
    q = hand.configuration(**{f"F{f}_proximal": 1.0 for f in "123"}, **{f"F{f}_distal": 0.3 for f in "123"})
    u = np.array([0.0, 0.01, 0.01, 0.01])
    load = np.zeros(8)
    load[[1, 4, 6]] = (0.5, np.nextafter(0.5, 1.0), 0.7)  # F1 at the threshold, F2 just above it
    np.testing.assert_array_equal(drive.switch([0, 0, 0], q, u, load), [0, 1, 1])
    np.testing.assert_array_equal(drive.switch([0, 0, 0], q, -u, load), [0, 0, 0])  # opening
    at_tip_stop = q.copy()
    at_tip_stop[[2, 5]] = 0.0
    np.testing.assert_array_equal(drive.switch([1, 1, 1], at_tip_stop, -u, load), [2, 2, 1])
    np.testing.assert_array_equal(drive.switch([1, 1, 1], at_tip_stop, u, load), [1, 1, 1])
    at_stops = at_tip_stop.copy()
    at_stops[1] = 0.0
    np.testing.assert_array_equal(drive.switch([2, 2, 2], at_stops, -u, load), [0, 2, 2])
    np.testing.assert_array_equal(drive.switch([2, 2, 2], at_tip_stop, u, load), [0, 0, 0])  # closing


@pytest.mark.parametrize("modes", [None, np.array([0.0, 1.0, 2.0]), np.array([1.0, 1.0, 0.0])])
def test_motor_commands_do_the_joint_laws_work_in_the_states_torque_switch_mode(modes) -> None:
    """T^T B u = T^T (tau + D v) for the mode the state reports; under saturation u stays below the puck limit."""
    hand = bh.BarrettHand()
    actuation = BarrettActuation(hand, saturate=True, damping=0.01)
    rng = np.random.default_rng(2)
    tau, velocity = 0.1 * rng.normal(size=8), rng.normal(size=8)
    state = bh.State(0.0, hand.configuration(), velocity, actuation_modes=modes)
    u = MotorCommands(lambda t, s: tau, actuation.drive)(0.0, state)
    actuation.restore(modes, state.q)
    applied = actuation.joint_torques(u)  # the simulator's saturating actuation, in the same mode
    assert np.abs(u).max() < MAX_MOTOR_TORQUE  # the check below is about the gears, not the clipping
    wanted = tau + actuation.joint_damping() * velocity
    transmission = actuation.transmission()
    np.testing.assert_allclose(transmission.T @ applied, transmission.T @ wanted, rtol=1e-12, atol=1e-15)


def test_full_actuation_passes_torques_through_and_bad_drives_are_refused() -> None:
    hand = bh.BarrettHand()
    drive = DirectDrive(hand, damping=0.2)
    state = bh.State(0.0, hand.configuration(), np.ones(8))
    tau = np.arange(8.0)
    np.testing.assert_array_equal(MotorCommands(lambda t, s: tau, drive)(0.0, state), tau + 0.2)
    with pytest.raises(bh.InputError, match="`drive` must be a bhgrasp Transmission"):
        MotorCommands(lambda t, s: tau, BarrettActuation(hand))
    with pytest.raises(bh.InputError, match=r"TorqueSwitch modes must be 3 values in \(0, 1, 2\), got \[0.0, 3.0, 0"):
        switch_modes(np.array([0.0, 3.0, 0.0]))
    with pytest.raises(bh.InputError, match=r"got \[0.5, 0.0, 0.0\]"):
        BarrettTransmission(hand).matrix([0.5, 0.0, 0.0])
    with pytest.raises(bh.InputError, match="`damping` must be a number or 8 numbers, got 'x'"):
        DirectDrive(hand, damping="x")
    with pytest.raises(bh.InputError, match="`hand` must be a bhgrasp Hand"):
        DirectDrive("hand")

    class Direct(Actuation):
        def joint_torques(self, u):
            return u

    with pytest.raises(bh.InputError, match="`drive` must be a bhgrasp Transmission"):
        Direct(hand)  # a hand where its drive model belongs
