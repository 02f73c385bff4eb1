"""Object-space grasp laws (5.32), (5.37), (5.38), the SMC-adaptive grasp (5.46)-(5.60) and the grasp supervisor."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import bhgrasp as bh
from bhgrasp.controllers.adaptive_grasp import SMCAdaptiveGrasp, object_parameters, object_regressor
from bhgrasp.controllers.grasp_options import GraspOptions
from bhgrasp.controllers.motor_commands import MotorCommands
from bhgrasp.controllers.object_space import ObjectSpaceController
from bhgrasp.controllers.supervisor import GraspSupervisor
from bhgrasp.grasp.metrics import finger_normal_forces, slip_events
from bhgrasp.model.objects import Box
from bhgrasp.scenarios.box_grasp import box_grasp
from bhgrasp.scenarios.grasp_controllers import grasp_controller
from bhgrasp.scenarios.grasp_demo import run_grasp_demo
from bhgrasp.scenarios.hold import reference_hold

GRAVITY = np.array([0.0, 0.0, -9.81])


def test_object_regressor_is_newton_euler_and_its_coriolis_form_is_passive():
    rng = np.random.default_rng(4)
    rotation = pin.exp3(rng.normal(size=3))
    twist, acceleration = rng.normal(size=6), rng.normal(size=6)
    root = rng.normal(size=(3, 3))
    inertia = root @ root.T + 0.1 * np.eye(3)
    sigma = object_parameters(0.7, inertia)
    inertia_w = rotation @ inertia @ rotation.T
    omega = twist[3:]
    wrench = object_regressor(rotation, twist, twist, acceleration, GRAVITY) @ sigma
    np.testing.assert_allclose(wrench[:3], 0.7 * (acceleration[:3] - GRAVITY), atol=1e-12)
    np.testing.assert_allclose(
        wrench[3:], inertia_w @ acceleration[3:] + np.cross(omega, inertia_w @ omega), atol=1e-12
    )

    # C(omega) as a matrix in omega_r: M_dot - 2 C skew-symmetric, M_dot = d/dt (R I R^T) by central differences.
    coriolis = np.column_stack(
        [object_regressor(rotation, twist, np.r_[0, 0, 0, e], np.zeros(6), np.zeros(3))[3:] @ sigma for e in np.eye(3)]
    )
    h = 1e-6
    ahead, behind = pin.exp3(h * omega) @ rotation, pin.exp3(-h * omega) @ rotation
    inertia_dot = (ahead @ inertia @ ahead.T - behind @ inertia @ behind.T) / (2 * h)
    residual = inertia_dot - 2.0 * coriolis
    np.testing.assert_allclose(residual, -residual.T, atol=1e-7)


@pytest.fixture(scope="module")
def lifts():
    """Each object-space law lifts the 0.3 kg box 5 mm (controller told the true mass), via the supervisor."""
    runs = {}
    for law in ("ctc", "natural", "stiffness"):
        setup = box_grasp(mass=0.3)
        controller = grasp_controller(law, setup.hand, Box(size=setup.box.size, mass=0.3))
        supervisor = GraspSupervisor(setup.hand, setup.q_contact, controller, offset=(0, 0, 0.005, 0, 0, 0))
        runs[law] = (setup, setup.simulator.run(supervisor, 2.6, state=setup.state))
    return runs


@pytest.mark.parametrize("law", ["ctc", "natural", "stiffness"])
def test_object_space_laws_lift_the_box_without_slip(lifts, law):
    setup, traj = lifts[law]
    phase = traj.log["phase"]
    grasped = traj.t[np.argmax(phase >= 1)]
    assert 0.5 < grasped < 1.2  # [s] all three fingers touched during the approach
    start = traj.object_position[np.argmax(phase >= 1), 0, 2]
    assert traj.object_position[-1, 0, 2] - start == pytest.approx(0.005, abs=5e-4)  # lifted 5 mm, < 0.5 mm error
    assert np.linalg.norm(traj.log["object_error"][-1, 3:]) < 5e-3  # [rad]
    assert slip_events(setup.hand, traj, grasped) == 0
    assert np.nanmin(traj.log["cone_margin"]) > -1e-6  # the QP kept every commanded force in the assumed cone


@pytest.mark.parametrize("mass", [0.2, 1.0])
def test_smc_adaptive_learns_an_unknown_mass_and_tracks_the_contact_forces(mass):
    """Acceptance: unknown mass 0.2-1.0 kg (told 0.5 kg): force error <= 5 % after settling, no slip."""
    result = run_grasp_demo(mass=mass, estimate=0.5, duration=3.0)
    assert result.slip_events == 0
    assert result.force_error < 0.05
    assert result.mass_estimate == pytest.approx(mass, rel=0.02)
    assert result.position_error < 1e-4 and result.rotation_error < 1e-3  # [m], [rad]
    traj = result.trajectory
    settled = traj.t >= result.settle_time
    # the logged force error is the measured one: desired minus the simulator's contact forces (to 0.2 mN: the
    # controller sums a finger's touching contact points, the trajectory every point of the finger's links)
    measured = finger_normal_forces(bh.BarrettHand(), traj)[settled]
    np.testing.assert_allclose(
        traj.log["desired_force"][settled][..., 2] - measured, traj.log["force_error"][settled][..., 2], atol=2e-4
    )


def test_pseudo_inverse_baseline_leaves_the_cone_where_the_qp_does_not():
    """Thesis (5.53) with G^+ on a 1 kg box: its commanded forces leave the assumed cone; the QP's never do."""
    baseline = run_grasp_demo(mass=1.0, estimate=0.5, duration=2.4, distribution="pinv")
    qp = run_grasp_demo(mass=1.0, estimate=0.5, duration=2.4)
    assert baseline.cone_margin < -0.05 and qp.cone_margin > -1e-6


def test_slip_events_follow_coulomb_capacity():
    """The reference hold squeezes with 8 N in total: mu sum f_n = 6.4 N holds 0.2 kg but not 1 kg (9.81 N)."""
    counts = {}
    for mass in (0.2, 1.0):
        hold = reference_hold(box_mass=mass)
        traj = hold.simulator.run(hold.controller, 0.3, state=hold.state, progress=False)
        counts[mass] = slip_events(hold.hand, traj)
    assert counts[0.2] == 0 and counts[1.0] > 0


def test_supervisor_approach_under_barrett_motors_reaches_every_contact():
    setup = box_grasp(mass=0.3, actuation="barrett")
    grasp = SMCAdaptiveGrasp(setup.hand, Box(size=setup.box.size, mass=0.3))
    supervisor = GraspSupervisor(setup.hand, setup.q_contact, grasp)
    traj = setup.simulator.run(MotorCommands(supervisor, setup.simulator.actuation.drive), 0.6, state=setup.state)
    assert np.all(traj.log["arrived"][-1] == 1.0) and traj.log["phase"][-1] >= 1
    assert np.all(np.isnan(traj.log["object_error"][0]))  # the grasp controller's keys start once it runs
    assert traj.u.shape[1] == 4


def test_grasp_controllers_reject_bad_arguments():
    hand = bh.BarrettHand()
    box = Box(size=(0.06, 0.05, 0.05), mass=0.5)
    with pytest.raises(bh.InputError, match="law"):
        ObjectSpaceController(hand, box, law="magic")
    with pytest.raises(bh.InputError, match="nominal_object"):
        SMCAdaptiveGrasp(hand, 0.5)
    with pytest.raises(bh.InputError, match="distribution"):
        SMCAdaptiveGrasp(hand, box, options=GraspOptions(distribution="lsq"))
    with pytest.raises(bh.InputError, match="q_contact"):
        GraspSupervisor(hand, np.full(8, 5.0), SMCAdaptiveGrasp(hand, box))
    with pytest.raises(bh.InputError, match="controller"):
        grasp_controller("pid", hand, box)


def test_hand_adaptation_path_matches_the_fixed_model_at_vanishing_rate():
    """(5.58) through the regressor Y_f sigma_f (hand adaptation on, rate -> 0) equals the fixed nominal model."""
    runs = []
    for rate in (None, 1e-12):
        setup = box_grasp(mass=0.3)
        grasp = SMCAdaptiveGrasp(setup.hand, Box(size=setup.box.size, mass=0.3), hand_adaptation=rate)
        supervisor = GraspSupervisor(setup.hand, setup.q_contact, grasp, offset=(0, 0, 0.005, 0, 0, 0))
        runs.append(setup.simulator.run(supervisor, 1.2, state=setup.state))
    assert np.any(runs[0].log["phase"] >= 1)
    np.testing.assert_allclose(runs[1].u, runs[0].u, atol=1e-9)
    np.testing.assert_allclose(runs[1].q, runs[0].q, atol=1e-10)


def test_finger_normal_forces_are_each_fingers_sum_of_f_dot_n_over_its_object_contacts():
    """The vectorised sum against its definition, sample by sample, to the bit (the demo: pads, links, pedestal).

    f . n written out, as the function computes it (a BLAS dot rounds by the machine's kernel).
    """
    traj = run_grasp_demo(duration=1.0).trajectory
    hand = box_grasp(mass=0.6).hand
    expected = np.zeros((len(traj), len(hand.fingers)))
    for k in range(len(traj)):
        contacts = traj.contacts_at(k)
        for (link, other), force, normal in zip(contacts["bodies"], contacts["force"], contacts["normal"]):
            finger = next((f for f in hand.fingers if str(link).startswith(f + "_")), None)
            if finger is not None and other in traj.object_names:
                pressed = force[0] * normal[0] + force[1] * normal[1] + force[2] * normal[2]
                expected[k, hand.fingers.index(finger)] += pressed
    measured = finger_normal_forces(hand, traj)
    np.testing.assert_array_equal(measured, expected)
    assert (measured > 1.0).all(axis=1).sum() > 300  # three fingers pressing for a third of the second
    on_pedestal = [str(a) == "environment0" for a, _ in traj.pair_bodies[traj.contact_pair]]
    assert any(on_pedestal)  # the box on its pedestal: an environment contact, not counted
