"""Object-space grasp control through the friction-cone QP, on the simulator's contacts (the reference hold)."""

from __future__ import annotations

import numpy as np
import pytest

import bhgrasp as bh
from bhgrasp.controllers.grasp_force import GraspForceController
from bhgrasp.controllers.grasp_options import GraspOptions
from bhgrasp.controllers.grasping import GraspContacts
from bhgrasp.motion.trajectories import Quintic
from bhgrasp.scenarios.hold import BOX_MASS, reference_hold

OPTIONS = GraspOptions(mu=0.6, squeeze=3.0)  # the controllers' shared options here
CLOSING_HARDER = GraspOptions(mu=0.6, squeeze=3.0, approach_torque=0.1)


def measured_cone_margins(traj, mu):
    """mu f_n - |f_t| of every recorded contact force (force on the box along and across the contact normal)."""
    normal = np.einsum("ij,ij->i", traj.contact_force, traj.contact_normal)
    tangential = np.linalg.norm(traj.contact_force - normal[:, None] * traj.contact_normal, axis=1)
    return mu * normal - tangential


@pytest.fixture(scope="module")
def lifted():
    hold = reference_hold()
    pose = hold.state.object_poses[0]
    start = np.concatenate((pose.translation, np.zeros(3)))
    reference = Quintic(start, start + np.array([0.0, 0.0, 0.005, 0.0, 0.0, 0.0]), 1.0)
    controller = GraspForceController(hold.hand, BOX_MASS, reference=reference, options=OPTIONS)
    traj = hold.simulator.run(controller, 2.0, state=hold.state, progress=False)
    return hold, traj


def test_hold_keeps_the_box_still_with_forces_inside_the_cones():
    hold = reference_hold()
    controller = GraspForceController(hold.hand, BOX_MASS, options=OPTIONS)
    traj = hold.simulator.run(controller, 1.0, state=hold.state, progress=False)
    drift = np.linalg.norm(traj.object_position[-1, 0] - traj.object_position[0, 0])
    assert drift < 2e-5  # [m]
    # sample 0 is the initial state, before any contact is sensed: the QP's log starts at sample 1
    assert np.all(np.isnan(traj.log["feasible"][0])) and np.all(traj.log["feasible"][1:] == 1.0)
    assert traj.log["infeasible_cycles"][-1] == 0.0 and np.max(traj.log["qp_iterations"][1:]) <= 30
    assert np.max(traj.log["wrench_residual"][1:]) < 1e-6
    assert np.all(traj.contact_sticking)
    assert np.min(measured_cone_margins(traj, 0.8)) > 0.0  # no measured force leaves the true cone (mu 0.8)
    weight = -np.sum(traj.contacts_at(len(traj) - 1)["force"], axis=0)  # forces on the box balance its weight
    assert weight[2] == pytest.approx(-BOX_MASS * 9.81, rel=0.01)


def test_lift_tracks_the_object_reference_without_slip(lifted):
    hold, traj = lifted
    target = hold.state.object_poses[0].translation[2] + 0.005
    assert abs(traj.object_position[-1, 0, 2] - target) < 5e-4  # [m], PD steady state
    assert np.all(traj.contact_sticking)  # slip events = 0
    assert np.min(traj.log["cone_margin"][1:]) > 0.0 and np.min(measured_cone_margins(traj, 0.8)) > 0.0


def test_fingers_close_onto_the_box_and_grasp_it():
    """From 0.03 rad open, the approach torque closes the fingers; the grasp holds once they touch."""
    hold = reference_hold()
    q = hold.state.q.copy()
    for finger in hold.hand.fingers:
        q[hold.hand.joint_index(f"{finger}_proximal")] -= 0.03
    controller = GraspForceController(hold.hand, BOX_MASS, options=CLOSING_HARDER)
    traj = hold.simulator.run(controller, 1.0, state=hold.simulator.initial_state(q), progress=False)
    grasped = np.argmax(traj.log["contacts"] >= 2)
    assert 0 < traj.t[grasped] < 0.1 and traj.log["contacts"][-1] == 3
    late = traj.object_position[traj.t > 0.5, 0, 2]
    assert np.max(np.abs(late - traj.object_position[grasped, 0, 2])) < 1e-4  # held where it was caught [m]
    assert np.all(traj.contact_sticking[traj.contact_offsets[grasped + 50] :])  # no slip once grasped


def test_grasp_controller_validates_its_inputs():
    hand = bh.BarrettHand()
    with pytest.raises(bh.InputError, match="object_mass"):
        GraspForceController(hand, -1.0)
    with pytest.raises(bh.InputError, match="kp"):
        GraspForceController(hand, 0.2, kp=(0.0, 1.0))
    with pytest.raises(bh.InputError, match="reference"):
        GraspForceController(hand, 0.2, reference=Quintic(np.zeros(3), np.ones(3), 1.0))
    controller = GraspForceController(hand, 0.2)
    with pytest.raises(bh.InputError, match="object"):
        controller(0.0, bh.State(0.0, hand.neutral(), np.zeros(8)))


def finger_normal_forces(hand, traj, k):
    """Measured normal force of each finger on the box at sample k [N] (sum over its contacts)."""
    contacts = traj.contacts_at(k)
    forces = np.zeros(len(hand.fingers))
    for (link, _), force, normal in zip(contacts["bodies"], contacts["force"], contacts["normal"]):
        finger = next(f for f in hand.fingers if link.startswith(f))
        forces[hand.fingers.index(finger)] += force @ normal
    return forces


@pytest.mark.parametrize(("mass", "first_slip_free"), [(0.5, 0.0), (1.0, 1.0)])
def test_unknown_object_mass_is_learnt_and_contact_forces_follow_the_qp(mass, first_slip_free):
    """Nominal 0.2 kg, true 0.5 or 1.0 kg: the mass estimate converges, the box stays, forces match the QP's."""
    hold = reference_hold(box_mass=mass)
    controller = GraspForceController(hold.hand, BOX_MASS, options=OPTIONS, mass_adaptation=5.0)
    traj = hold.simulator.run(controller, 3.0, state=hold.state, progress=False)
    assert traj.log["mass_estimate"][-1] == pytest.approx(mass, rel=0.02)
    assert abs(traj.object_position[-1, 0, 2] - traj.object_position[0, 0, 2]) < 1e-4
    after = traj.contact_offsets[np.searchsorted(traj.t, first_slip_free)]
    assert np.all(traj.contact_sticking[after:])  # a 1 kg box slips only until the estimate catches up
    measured = finger_normal_forces(hold.hand, traj, len(traj) - 1)
    commanded = traj.log["commanded_normal"][-1]
    np.testing.assert_allclose(measured, commanded, rtol=0.05)  # contact force error within 5 % after settling


def test_an_infeasible_wrench_gets_the_nearest_admissible_forces_and_is_logged():
    """Two contacts on one line exert no torque about it: the controller still gets forces, inside the cones, that
    meet the rest of the wrench, says so in its log, and counts the infeasible cycles."""
    hand = bh.BarrettHand()
    controller = GraspForceController(hand, BOX_MASS, options=GraspOptions(mu=0.5, squeeze=3.0))
    contacts = GraspContacts(
        points=np.array([[0.03, 0.0, 0.0], [-0.03, 0.0, 0.0]]),
        normals=np.array([[-1.0, 0.0, 0.0], [1.0, 0.0, 0.0]]),
        links=["F1_distal_link", "F3_distal_link"],
        fingers=["F1", "F3"],
        forces=np.zeros((2, 3)),
        reference=np.zeros(3),
    )
    wrench = np.array([0.0, 0.0, BOX_MASS * 9.81, 0.05, 0.0, 0.0])  # 0.05 N m about x, the contacts' line
    for cycle in range(1, 4):
        forces = controller.distribute(contacts, wrench)
        assert controller.log["feasible"] == 0.0 and controller.log["infeasible_cycles"] == cycle
        assert controller.log["qp_iterations"] <= (40 if cycle == 1 else 5)  # then one warm nearest solve
        assert controller.log["cone_margin"] >= -1e-9 and np.all(forces[:, 2] >= controller.min_normal_force - 1e-9)
        error = contacts.grasp_map @ forces.ravel() - wrench
        assert abs(error[3] + 0.05) < 1e-9 and np.linalg.norm(np.delete(error, 3)) < 1e-3  # only the torque missed
        assert controller.log["wrench_residual"] == pytest.approx(np.linalg.norm(error))


class TwoFingerGrasp(GraspForceController):
    """Uses F1 and F3 only (F2 keeps touching, with gravity compensation alone): no admissible forces of the two
    hold the box's pose."""

    def touching(self, state):
        return {finger: c for finger, c in super().touching(state).items() if finger != "F2"}


def test_controller_keeps_running_through_infeasible_cycles():
    """Every grasp cycle is infeasible; each QP call ends within a few iterations (the pre-fix solver took up to
    12 551 per cycle, 26 s for this run) and the nearest admissible forces still hold the box within a centimetre."""
    hold = reference_hold()
    controller = TwoFingerGrasp(hold.hand, BOX_MASS, options=OPTIONS)
    traj = hold.simulator.run(controller, 0.5, state=hold.state, progress=False)
    grasping = traj.log["contacts"][1:] >= 2
    assert np.all(traj.log["feasible"][1:][grasping] == 0.0)
    assert traj.log["infeasible_cycles"][-1] >= 490  # of 500 control cycles (1 ms), the first before contact
    assert np.nanmax(traj.log["qp_iterations"]) <= 100 and np.nanmin(traj.log["cone_margin"]) >= -1e-9
    assert np.linalg.norm(traj.object_position[-1, 0] - traj.object_position[0, 0]) < 0.01  # [m]


def test_a_friction_margin_raises_the_grip_with_the_measured_load():
    """Two opposed contacts, no wrench: the QP returns its desired forces.  Without a margin the normals are the
    squeeze; with margin m each contact's normal is raised to |f_t| / ((1 - m) mu) of its measured tangential force
    (closed form), and the squeeze is kept where the measured load needs less; the QP's cones are (1 - m) mu's."""
    hand = bh.BarrettHand()
    load = np.array([[0.0, 0.0, 2.0], [0.0, 0.0, 0.3]])  # measured on the box, world: 2 N and 0.3 N upwards
    contacts = GraspContacts(
        points=np.array([[0.03, 0.0, 0.0], [-0.03, 0.0, 0.0]]),
        normals=np.array([[-1.0, 0.0, 0.0], [1.0, 0.0, 0.0]]),
        links=["F1_distal_link", "F3_distal_link"],
        fingers=["F1", "F3"],
        forces=load + np.array([[-4.0, 0.0, 0.0], [4.0, 0.0, 0.0]]),  # and 4 N of squeeze
        reference=np.zeros(3),
    )
    plain = GraspForceController(hand, BOX_MASS, options=GraspOptions(mu=0.6, squeeze=3.0))
    np.testing.assert_allclose(plain.distribute(contacts, np.zeros(6))[:, 2], [3.0, 3.0], atol=1e-9)
    margin = GraspForceController(hand, BOX_MASS, options=GraspOptions(mu=0.6, squeeze=3.0, friction_margin=0.3))
    assert margin.design_mu == pytest.approx(0.42) and margin.options.design_mu == margin.design_mu
    forces = margin.distribute(contacts, np.zeros(6))
    # 2 N needs 2 / 0.42 = 4.76 N; 0.3 N needs 0.71 N < the squeeze.  Two opposed contacts balance only equal
    # normals: the QP's nearest balanced forces split the difference (the closed-form projection on f_n1 = f_n3).
    needed = max(3.0, 2.0 / 0.42), max(3.0, 0.3 / 0.42)
    np.testing.assert_allclose(forces[:, 2], np.mean(needed), atol=1e-6)
    assert margin._qps[2].mu == pytest.approx(0.42)


def test_friction_margin_is_checked():
    for bad in (-0.1, 1.0, 1.5, float("nan"), float("inf"), True, False):
        with pytest.raises(bh.InputError, match="friction_margin"):
            GraspOptions(friction_margin=bad)
    assert GraspOptions().design_mu == GraspOptions().mu and GraspOptions(friction_margin=0.0).design_mu == 0.5
