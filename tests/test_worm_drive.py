"""The BH8-280's self-locking worm drives against independent truths: Pinocchio's gravity torques and mass matrix,
the unlock threshold eta r u = load, and a stall on a fixed block whose contact torque is eta r u (issue 16)."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import bhgrasp as bh
from bhgrasp.barrett.transmission import PROXIMAL_RATIO, WORM_EFFICIENCY
from bhgrasp.grasp.sensing import ContactSensing
from bhgrasp.model.objects import Box
from bhgrasp.model.spring_mounted import SpringMounted
from bhgrasp.sim import Simulator
from bhgrasp.sim.actuation import BarrettActuation
from bhgrasp.sim.scene import Scene

PROXIMAL, DISTAL = 1, 2  # F1's joints
COLUMN = np.array([1.0, 1.0 / 3.0])  # F1's motor coordinate w moves (proximal, distal) by (1, 1/3) w when armed


@pytest.fixture(scope="module")
def hand() -> bh.Hand:
    return bh.BarrettHand()  # palm up: gravity pulls the raised fingers open


def raised(hand: bh.Hand) -> np.ndarray:
    return hand.configuration(**{f"F{f}_proximal": 0.8 for f in "123"}, **{f"F{f}_distal": 0.8 / 3 for f in "123"})


def load(hand: bh.Hand, q: np.ndarray) -> float:
    """Torque along F1's motor coordinate that holds it against gravity [N m] (Pinocchio, a second method)."""
    return float(COLUMN @ hand.gravity_torques(q)[[PROXIMAL, DISTAL]])


def run(hand: bh.Hand, u_f1: float, steps: int, self_locking: bool = True):
    simulator = Simulator(Scene(hand), dt=1e-3, actuation=BarrettActuation(hand, self_locking=self_locking))
    state = simulator.initial_state(raised(hand))
    states = [state]
    for _ in range(steps):
        state, _ = simulator.step(state, [0.0, u_f1, 0.0, 0.0])
        states.append(state)
    return simulator, states


def test_an_idle_finger_is_held_by_its_worm_and_the_drive_carries_its_weight(hand) -> None:
    simulator, states = run(hand, 0.0, 500)
    fingers = [1, 2, 4, 5, 6, 7]  # (the spread's drive is not a worm: it is not held, and rests at 1e-24 rad)
    held = np.array([s.q[fingers] for s in states])
    np.testing.assert_array_equal(held, np.broadcast_to(held[0], held.shape))  # not one bit moves, from the start
    assert (states[-1].actuation_modes[3:] == 1).all()
    _, info = simulator.step(states[-1], np.zeros(4))
    q = states[-1].q
    held = COLUMN @ info.drive_torques[[PROXIMAL, DISTAL]]
    assert held == pytest.approx(load(hand, q), rel=1e-9)  # the worm carries the finger's weight
    free_simulator, free = run(hand, 0.0, 500, self_locking=False)  # the same finger back-drives its gears ...
    damping = free_simulator.actuation.joint_damping()[[PROXIMAL, DISTAL]]
    terminal = -load(hand, free[-1].q) / (COLUMN @ (damping * COLUMN))  # ... against the motor's reflected damping
    assert free[-1].v[PROXIMAL] == pytest.approx(terminal, rel=0.02)


def test_a_locked_drive_turns_only_when_the_motor_gives_more_than_the_load(hand) -> None:
    threshold = load(hand, raised(hand)) / (WORM_EFFICIENCY * PROXIMAL_RATIO)  # motor torque that balances gravity
    for scale, moves in ((0.98, False), (1.02, True)):
        _, states = run(hand, 0.0, 5)  # locked first
        simulator = Simulator(Scene(hand), dt=1e-3, actuation=BarrettActuation(hand))
        state = states[-1]
        for _ in range(200):
            state, _ = simulator.step(state, [0.0, scale * threshold, 0.0, 0.0])
        if moves:
            assert state.q[PROXIMAL] > states[-1].q[PROXIMAL] + 1e-5, scale
        else:
            assert state.q[PROXIMAL] == states[-1].q[PROXIMAL], scale  # not one bit
    state = states[-1]
    for _ in range(200):  # a small opening torque: the load helps the motor, the finger opens
        state, _ = simulator.step(state, [0.0, -0.05 * threshold, 0.0, 0.0])
    assert state.q[PROXIMAL] < states[-1].q[PROXIMAL] - 1e-5


def test_a_free_finger_accelerates_with_the_worms_efficiency(hand) -> None:
    """From rest, one implicit step of the four motor coordinates w (v = T w, T from the ratios):
    (T^T M T + dt T^T D T) w+ = dt T^T (tau - g), tau = eta r u on F1's proximal joint (Pinocchio's M and g).
    F2's and F3's motors are idle: their worms hold them, so T has the spread's and F1's columns only."""
    u = 0.03
    transmission = np.zeros((8, 2))
    transmission[[0, 3], 0] = 1.0  # one spread motor
    transmission[[PROXIMAL, DISTAL], 1] = COLUMN
    for efficiency in (1.0, 0.35):
        actuation = BarrettActuation(hand, efficiency=efficiency)
        simulator = Simulator(Scene(hand), dt=1e-3, actuation=actuation)
        state, _ = simulator.step(simulator.initial_state(raised(hand)), [0.0, u, 0.0, 0.0])
        q = raised(hand)
        mass = pin.crba(hand.model, hand.data, q)
        mass = np.triu(mass) + np.triu(mass, 1).T
        damping = np.diag(actuation.joint_damping())
        tau = np.zeros(8)
        tau[PROXIMAL] = efficiency * PROXIMAL_RATIO * u
        reduced = transmission.T @ (mass + 1e-3 * damping) @ transmission
        w = np.linalg.solve(reduced, 1e-3 * transmission.T @ (tau - hand.gravity_torques(q)))
        np.testing.assert_allclose(state.v, transmission @ w, rtol=1e-9, atol=1e-15)


def test_a_stalled_finger_presses_with_eta_r_u_and_keeps_its_grip_when_the_motor_idles(hand) -> None:
    """F1 closes on a fixed block: at stall the contact torque along w is eta r u minus the weight's; the idle worm
    keeps it (a back-drivable drive lets go)."""
    ahead = raised(hand)
    ahead[[PROXIMAL, DISTAL]] += (0.15, 0.05)
    tip = hand.frame_placement(ahead, "F1_tip").translation  # where the tip will be after turning w by 0.15 rad
    body = Box(
        size=(0.04, 0.04, 0.04), mass=0.1, pose=pin.SE3(np.eye(3), tip + np.array([0.0, 0.02, 0.0])), friction=0.5
    )
    block = SpringMounted(body, [0.0, 1.0, 0.0], stiffness=1e5, damping=100.0)  # stiff, in the tip's way
    u = 0.02
    results = {}
    sensing = ContactSensing(hand)
    for self_locking in (True, False):  # (a high breakaway torque keeps the TorqueSwitch armed: w is F1's column)
        actuation = BarrettActuation(hand, breakaway_torque=100.0, self_locking=self_locking)
        simulator = Simulator(Scene(hand, [block]), dt=1e-3, actuation=actuation)
        state = simulator.initial_state(raised(hand))
        contact = []
        for k in range(1500):
            motor = u if k < 1000 else 0.0  # idle after 1 s
            state, _ = simulator.step(state, [0.0, motor, 0.0, 0.0])
            contact.append(-COLUMN @ sensing.reaction_torques(state)[[PROXIMAL, DISTAL]])
        results[self_locking] = (np.array(contact), state)
    pressing, _ = results[True]
    stall = WORM_EFFICIENCY * PROXIMAL_RATIO * u - load(hand, raised(hand))
    assert np.mean(pressing[800:1000]) == pytest.approx(stall, rel=0.05)
    # idle: the worm holds the finger where it stalled; the grip does not change
    assert np.abs(pressing[1000:] - pressing[999]).max() < 1e-9
    released, _ = results[False]
    assert released[-1] < 0.2 * stall
