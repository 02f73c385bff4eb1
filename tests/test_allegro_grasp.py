"""Issue 8, generic hands: the 16-DOF Allegro hand of example-robot-data runs the same grasp pipeline on a box."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import bhgrasp as bh
from bhgrasp.controllers.adaptive_grasp import SMCAdaptiveGrasp
from bhgrasp.controllers.supervisor import GraspSupervisor
from bhgrasp.grasp.metrics import finger_normal_forces
from bhgrasp.model.objects import Box
from bhgrasp.scenarios.allegro_grasp import FINGERTIPS, GRASPING, allegro_box_grasp
from bhgrasp.scenarios.grasp_demo import OFFSET, run_grasp_demo
from bhgrasp.sim.start_check import pair_distances

GRAVITY = np.array([0.0, 0.0, -9.81])


@pytest.fixture(scope="module")
def demo():
    return run_grasp_demo(hand="allegro", mass=0.6, estimate=0.3, duration=2.2)


def test_contact_configuration_touches_the_box_with_three_fingertips_only():
    """At q_contact coal finds the three fingertip spheres on the box (independent of the IK) and every other link
    clear of it; the approach's target presses the spheres into the box."""
    setup = allegro_box_grasp()
    scene = setup.simulator.scene
    distances = {}
    for q_hand in (setup.q_contact, setup.q_close):
        q, _ = scene.initial_state(q_hand)
        pairs = [p for p in scene.pairs if p.body_b == scene.object_names[0] and p.joint_a != 0]
        distances[id(q_hand)] = dict(zip((p.body_a for p in pairs), pair_distances(scene, q, [p.index for p in pairs])))
    at_contact, closed = distances[id(setup.q_contact)], distances[id(setup.q_close)]
    tips = {FINGERTIPS[f] for f in GRASPING}
    for tip in tips:
        assert abs(at_contact[tip]) < 1e-6  # [m]
        assert closed[tip] < -5e-3  # pushed 8 mm into the box (coal reports the penetration depth)
    assert min(d for link, d in at_contact.items() if link not in tips) > 1.5e-3  # the synthesis' clearance
    assert np.all(setup.q_contact[setup.hand.finger_indices("ring")] == 0.0)
    assert setup.hand.within_limits(setup.q_start) and setup.hand.within_limits(setup.q_close)


def test_allegro_grasps_lifts_and_turns_the_box_and_learns_its_mass(demo):
    """The same SMC-adaptive law, QP and supervisor as the Barrett demo; checked on the simulator's own record."""
    traj, hand = demo.trajectory, demo.scene.hand
    assert hand.nv == 16 and 0.1 < demo.grasp_time < 0.5
    first = int(np.argmax(traj.log["phase"] >= 1))
    moved = traj.object_position[-1, 0] - traj.object_position[first, 0]
    np.testing.assert_allclose(moved, OFFSET[:3], atol=2e-4)  # [m] lifted 10 mm
    start, end = (pin.Quaternion(*np.roll(traj.object_quaternion[k, 0], 1)) for k in (first, -1))
    turned = pin.log3(end.toRotationMatrix() @ start.toRotationMatrix().T)
    np.testing.assert_allclose(turned, OFFSET[3:], atol=2e-3)  # [rad] turned 0.1 rad about x
    assert demo.mass_estimate == pytest.approx(0.6, rel=0.02)
    assert demo.slip_events == 0 and demo.force_error < 0.05
    forces = finger_normal_forces(hand, traj)
    assert np.all(forces[:, hand.fingers.index("ring")] == 0.0)  # the idle finger never touches
    assert np.all(forces[-1, [hand.fingers.index(f) for f in GRASPING]] > 1.0)  # [N]


def test_allegro_contacts_carry_the_box_weight_at_rest(demo):
    """Newton on the box at the end (at rest): the hand's contact forces sum to -m g (pedestal left behind)."""
    traj = demo.trajectory
    contacts = traj.contacts_at(len(traj) - 1)
    on_hand = [link in FINGERTIPS.values() for link, _ in contacts["bodies"]]
    assert all(on_hand) and len(on_hand) >= 3
    np.testing.assert_allclose(contacts["force"].sum(axis=0), -0.6 * GRAVITY, atol=0.01)  # [N]


def test_supervisor_rejects_unknown_grasping_fingers():
    setup = allegro_box_grasp()
    grasp = SMCAdaptiveGrasp(setup.hand, Box(size=setup.box.size, mass=0.2))
    with pytest.raises(bh.InputError, match="pinky"):
        GraspSupervisor(setup.hand, setup.q_contact, grasp, fingers=["pinky"])
    with pytest.raises(bh.InputError, match="q_close"):
        GraspSupervisor(setup.hand, setup.q_contact, grasp, q_close=np.zeros(8))
    with pytest.raises(bh.InputError, match="hand"):
        run_grasp_demo(hand="shadow")
