"""The BH8-280's drive inside Barrett's published envelope: a stalled finger presses about 20 N at its tip, the
TorqueSwitch breaks away on the torque its clutch passes whatever the link's speed, a free finger never breaks away.

Independent truths: Barrett's figures (the fingertip torque sensor's +/- 1 N m "is about 20 N @ 5 cm", the stalled
fingertip force plotted up to about 25 N, "2 kg per finger"; urdf/README.md), Newton at rest (the contact's moment
about the distal axis against the motor's torque through the worm and Pinocchio's gravity torque), and the switch's
threshold against the contact's moment about the proximal axis.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import bhgrasp as bh
from bhgrasp.barrett.commands import BarrettDriver
from bhgrasp.barrett.transmission import (
    BREAKAWAY_TORQUE,
    DISTAL_ALONE_RATIO,
    MAX_MOTOR_TORQUE,
    WORM_EFFICIENCY,
)
from bhgrasp.bench.protocol import DT
from bhgrasp.bench.trial import contact_law
from bhgrasp.model.objects import Box, FixedBox
from bhgrasp.model.spring_mounted import SpringMounted
from bhgrasp.sim import Simulator
from bhgrasp.sim.actuation import BarrettActuation
from bhgrasp.sim.contact_law import SpringDamper
from bhgrasp.sim.scene import Scene

F3_PROXIMAL, F3_DISTAL = 6, 7
BAND = (15.0, 25.0)  # [N] Barrett's stalled fingertip force (urdf/README.md)
LAW = contact_law()  # the grasp benchmark's: stiff, so the stall is not lost in centimetres of penetration


def contact_force(trajectory: bh.Trajectory, k: int) -> float:
    """Total contact force magnitude at sample ``k`` [N]."""
    return float(np.linalg.norm(trajectory.contacts_at(k)["force"], axis=1).sum())


def moment_about(hand: bh.Hand, q: np.ndarray, joint: str, contacts: dict) -> float:
    """The moment of the contacts' forces (each on the pair's second body) about ``joint``'s axis [N m], positive
    in the joint's closing sense."""
    data = hand.model.createData()
    pin.forwardKinematics(hand.model, data, q)
    placement = data.oMi[hand.model.getJointId(joint)]
    axis = placement.rotation[:, 2]
    return float(
        sum(np.cross(p - placement.translation, f) @ axis for p, f in zip(contacts["point"], contacts["force"]))
    )


@pytest.fixture(scope="module", params=["python", "compiled"])
def stall(request) -> tuple[bh.Hand, bh.Trajectory]:
    """F3 closed by libbarrett's close() onto a fixed block in front of its fingertip."""
    hand = bh.BarrettHand()
    block = FixedBox(size=(0.06, 0.03, 0.02), pose=pin.SE3(np.eye(3), np.array([0.0, 0.035, 0.185])), name="block")
    simulator = Simulator(
        Scene(hand, [], environment=[block]),
        dt=DT,
        contact=LAW,
        actuation=BarrettActuation(hand, saturate=True),
        engine=request.param,
    )
    driver = BarrettDriver(hand)
    driver.script([(0.0, "close", "F3")])
    return hand, simulator.run(driver, 0.8, progress=False)


def test_a_stalled_finger_presses_barretts_fingertip_force(stall) -> None:
    hand, trajectory = stall
    touching = trajectory.contact_count() > 0
    first = int(np.argmax(touching))
    assert touching[first:].all() and trajectory.modes[-1, 2] == 1  # on the block, broken away, ...
    assert trajectory.modes[-1, 5] == 1  # ... and held by its worm once the puck idled
    bodies = {tuple(b) for k in range(first, len(trajectory)) for b in trajectory.contacts_at(k)["bodies"]}
    assert bodies == {("block", "F3_distal_link")}  # the fingertip alone touches it
    pushing = (trajectory.u[:, 3] == MAX_MOTOR_TORQUE) & (trajectory.modes[:, 2] == 1) & (trajectory.modes[:, 5] == 0)
    k = int(np.flatnonzero(pushing)[-1])  # the last sample with the motor at MT on the tip, before the puck idles
    assert (
        trajectory.t[k] - trajectory.t[first] > 0.05 and np.abs(trajectory.v[k, [F3_PROXIMAL, F3_DISTAL]]).max() < 1e-3
    )
    # Newton at rest about the distal axis: the motor's torque through the worm holds the contact and the tip's weight
    q = trajectory.q[k]
    gravity = hand.gravity_torques(q)[F3_DISTAL]
    drive = WORM_EFFICIENCY * DISTAL_ALONE_RATIO * MAX_MOTOR_TORQUE  # 1 N m
    assert drive + moment_about(hand, q, "F3_distal", trajectory.contacts_at(k)) == pytest.approx(gravity, abs=1e-3)
    # the force itself: in Barrett's band, and held there by the worm when the puck idles
    assert BAND[0] < contact_force(trajectory, k) < BAND[1]
    assert contact_force(trajectory, len(trajectory) - 1) == pytest.approx(contact_force(trajectory, k), rel=1e-3)
    peak = max(contact_force(trajectory, i) for i in range(first, len(trajectory)))
    assert peak < 2 * BAND[1]  # the impact of a finger closing at full speed included


def _inner_link_push(engine: str) -> tuple[bh.Hand, bh.Trajectory]:
    """F3 closes at full torque onto a light box on a soft spring at its inner link: the link keeps moving while
    the spring's force grows (a soft contact law, so that the touch is no impact)."""
    hand = bh.BarrettHand()
    box = SpringMounted(
        Box(size=(0.04, 0.02, 0.02), mass=0.02, pose=pin.SE3(np.eye(3), np.array([0.0, 0.095, 0.115]))),
        direction=(0, 0, 1),
        stiffness=2000.0,
        damping=5.0,
    )
    simulator = Simulator(
        Scene(hand, [box]),
        dt=DT,
        contact=SpringDamper(5e4, 50.0),
        actuation=BarrettActuation(hand, saturate=True),
        engine=engine,
    )
    return hand, simulator.run(lambda t, s: np.array([0.0, 0.0, 0.0, MAX_MOTOR_TORQUE]), 0.6, progress=False)


@pytest.mark.parametrize("engine", ["python", "compiled"])
def test_the_switch_breaks_away_on_its_clutch_torque_while_the_link_still_moves(engine) -> None:
    hand, trajectory = _inner_link_push(engine)
    k = int(np.argmax(trajectory.modes[:, 2] == 1))  # the sample that ends the breaking step
    assert k > 0 and trajectory.modes[k:, 2].all()
    assert trajectory.v[k - 1, F3_PROXIMAL] > 0.5  # [rad/s] still closing: a rule waiting for a stopped link would wait

    def load(i: int) -> float:  # the clutch's load: the finger's push on the box about the proximal axis, and gravity
        q = trajectory.q[i]
        return moment_about(hand, q, "F3_proximal", trajectory.contacts_at(i)) + hand.gravity_torques(q)[F3_PROXIMAL]

    assert load(k - 1) <= BREAKAWAY_TORQUE < load(k) < BREAKAWAY_TORQUE + 0.01
    # then the inner link holds with what the clutch passed, while the fingertip curls on to the box
    tip = [i for i in range(k, len(trajectory)) if "F3_distal_link" in trajectory.contacts_at(i)["bodies"]]
    assert tip and trajectory.q[tip[0], F3_DISTAL] - trajectory.q[k, F3_DISTAL] > 0.3
    assert max(load(i) for i in range(k, tip[0])) < BREAKAWAY_TORQUE + 0.01  # the motor's full 1.33 N m would press on
    assert np.ptp(trajectory.q[k:, F3_PROXIMAL]) == 0.0


@pytest.mark.parametrize("dt", [2.5e-4, 1e-3])
def test_a_free_finger_under_a_full_torque_step_never_breaks_away(dt) -> None:
    """The massless motor's start-up transient is the links' own acceleration, not a load: no breakaway in free air
    (the drive's torque reaches 0.98 N m, twice the threshold, on the first step at 0.25 ms)."""
    hand = bh.BarrettHand()
    simulator = Simulator(Scene(hand), dt=dt, actuation=BarrettActuation(hand, saturate=True))
    closing = np.array([0.0, 1.0, 1.0, 1.0]) * MAX_MOTOR_TORQUE
    trajectory = simulator.run(lambda t, s: closing, 0.6, progress=False)
    assert trajectory.tau[1:, [1, 4, 6]].max() > BREAKAWAY_TORQUE  # the drive's start-up torque exceeds it ...
    assert not trajectory.modes[:, :3].any()  # ... and no switch breaks
    assert trajectory.q[-1, 6] > 1.0  # the fingers closed
