"""Grasp synthesis (:mod:`bhgrasp.grasp.synthesis`): candidates that lift with their pads alone, and execute."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pinocchio as pin
import pytest

import bhgrasp as bh
from bhgrasp.controllers.adaptive_grasp import SMCAdaptiveGrasp
from bhgrasp.controllers.grasp_options import GraspOptions
from bhgrasp.controllers.supervisor import GraspSupervisor
from bhgrasp.grasp.manipulability import manipulable_space
from bhgrasp.grasp.metrics import slip_events
from bhgrasp.grasp.probes import HandClearance
from bhgrasp.grasp.synthesis import grasp_candidates, synthesize
from bhgrasp.model.objects import Box, Cylinder, Sphere
from bhgrasp.scenarios.box_grasp import CONTACT_HEIGHT, box_grasp
from bhgrasp.scenarios.demo_result import evaluate_demo
from bhgrasp.scenarios.object_grasp import object_grasp

CENTRE = pin.SE3(np.eye(3), np.array([0.0, 0.0, CONTACT_HEIGHT]))
LIFT = np.array([0.0, 0.0, 0.01, 0.0, 0.0, 0.0])


def test_candidates_keep_the_link_bodies_off_the_object_along_a_lift():
    hand, box = bh.BarrettHand(), Box(size=(0.06, 0.05, 0.05), mass=0.6, pose=CENTRE)
    candidates = grasp_candidates(hand, box, fingers=("F1", "F2", "F3"))
    shapes, shape = HandClearance(hand), box.geometry()
    assert candidates
    for c in candidates:
        space = manipulable_space(
            hand, c.q_contact, c.points, c.normals, [hand.fingertip_frames[f] for f in c.fingers], box.pose.translation
        )
        lifted = pin.SE3(box.pose.rotation, box.pose.translation + LIFT[:3])
        assert shapes.nearest_other(c.q_contact + space.joint_map @ LIFT, c.fingers, shape, lifted) >= 1.5e-3
        opened = np.flatnonzero(c.q_pregrasp != c.q_contact)  # the proximal joints alone
        assert [hand.joint_names[i] for i in opened] == ["F1_proximal", "F2_proximal", "F3_proximal"]


@pytest.mark.parametrize(
    "item",
    [Box(size=(0.06, 0.05, 0.05), mass=0.6, pose=CENTRE), Cylinder(radius=0.033, length=0.10, mass=0.35, pose=CENTRE)],
)
def test_synthesised_grasp_lifts_without_slip_or_turn(item):
    setup = object_grasp(item)
    grasp = SMCAdaptiveGrasp(
        setup.hand,
        replace(setup.item, density=None),
        options=GraspOptions(mu=0.6, squeeze=5.0),
        object_adaptation=(0.0, 0.0),
    )
    supervisor = GraspSupervisor(
        setup.hand, setup.candidate.q_contact, grasp, offset=LIFT, fingers=setup.candidate.fingers
    )
    traj = setup.simulator.run(supervisor, 3.0, state=setup.state, progress=False)
    result = evaluate_demo(
        traj, setup.hand, "smc-adaptive", item.mass, item.mass, supervisor, 0.0, setup.simulator.scene
    )
    assert result.true_position_error < 1e-4 and result.true_rotation_error < 1e-3  # [m], [rad]
    late = traj.t >= result.grasp_time + 0.02  # after the touch-down transient (the can's pads skid for ~7 ms)
    assert slip_events(setup.hand, traj, float(traj.t[late][0])) == 0


def test_the_box_synthesis_finds_the_thesis_pinch():
    """Independent truth: the thesis' hand-made grasp (box_grasp: F1, F2 on the -y face 50 mm apart, F3 opposite)."""
    hand, box = bh.BarrettHand(), Box(size=(0.06, 0.05, 0.05), mass=0.6, pose=CENTRE)
    best = synthesize(hand, box)
    thesis = box_grasp(mass=0.6)
    np.testing.assert_allclose(
        best.points,
        [[-0.025, -0.025, CONTACT_HEIGHT], [0.025, -0.025, CONTACT_HEIGHT], [0.0, 0.025, CONTACT_HEIGHT]],
        atol=1e-4,
    )
    np.testing.assert_allclose(best.q_contact, thesis.q_contact, atol=2e-3)
    assert best.quality.force_closure and best.holds_weight


def test_a_sphere_grasp_touches_the_sphere_with_its_pads_along_the_radii():
    hand, ball = bh.BarrettHand(), Sphere(radius=0.035, mass=0.2, pose=CENTRE)
    candidates = grasp_candidates(hand, ball)
    assert candidates and candidates[0].quality.force_closure
    for c in candidates[:5]:
        radial = c.points - CENTRE.translation
        np.testing.assert_allclose(np.linalg.norm(radial, axis=1), 0.035, atol=2e-5)  # on the surface
        np.testing.assert_allclose(c.normals, -radial / 0.035, atol=1e-3)  # into the ball, through its centre
        for finger, point, normal in zip(c.fingers, c.points, c.normals):  # the pad's centre 10 mm out
            pad = hand.frame_placement(c.q_contact, hand.fingertip_frames[finger]).translation
            np.testing.assert_allclose(pad, point - 0.010 * normal, atol=1e-5)


def test_a_fingertip_over_its_spread_axis_is_refused_and_no_grasp_is_named():
    """A 50 mm cube: its only reachable three-finger grasps put F1 and F2 over their knuckles (x = +-25 mm), where
    the spread joint cannot move the contact (the contact Jacobian loses a rank); with that rule off they appear."""
    hand, cube = bh.BarrettHand(), Box(size=(0.05, 0.05, 0.05), mass=0.3, pose=CENTRE)
    singular = grasp_candidates(hand, cube, fingers=("F1", "F2", "F3"), singularity_margin=0.0)
    assert singular
    for c in singular:
        np.testing.assert_allclose(np.abs(c.points[:2, 0]), 0.025, atol=1e-4)  # over the knuckles
        column = hand.point_jacobian(c.q_contact, hand.fingertip_frames["F1"], c.points[0])[:3, 0]
        assert np.linalg.norm(column) < 1e-4  # [m/rad] F1's spread barely moves its contact (margin: 2 mm/rad)
    with pytest.raises(bh.UnreachableError, match="no grasp of Box .* pads alone"):
        synthesize(hand, cube)


def test_the_demo_refuses_a_turn_that_brings_a_link_body_onto_the_box():
    """The supervisor's second-order check, wired in: F3's distal link nears the +y face in a 0.3 rad turn."""
    from bhgrasp.scenarios.grasp_demo import run_grasp_demo

    with pytest.raises(
        bh.UnreachableError, match=r"F3_distal_link_0 \(F3_distal_link\) comes within 0\.2 mm of the object's \+y face"
    ):
        run_grasp_demo(offset=(0.0, 0.0, 0.01, 0.3, 0.0, 0.0))


def test_slip_is_counted_from_the_sample_after_the_grasp_controller_took_over():
    """A sample's contacts come from the step the previous input drove: the demo counts slip from the sample after
    the grasp controller took over.  The Allegro's pads skid while they close (the approach): counted from any such
    sample k, that sample's skids are left out and every later one counted.  (The can's grasp, which skidded in its
    switching sample, skids no more since a can stands on its pedestal without being thrown off.)"""
    from bhgrasp.grasp.metrics import slip_events_after
    from bhgrasp.scenarios.grasp_demo import run_grasp_demo

    result = run_grasp_demo(hand="allegro", mass=0.6, estimate=0.3, duration=0.6)
    traj, hand = result.trajectory, result.scene.hand
    switch = int(np.searchsorted(traj.t, result.grasp_time))
    assert traj.log["phase"][switch] == 1.0 and traj.log["phase"][switch - 1] == 0.0  # the switching sample
    per_sample = np.array([slip_events(hand, traj, t) for t in traj.t[: switch + 2]])
    skids = -np.diff(per_sample)  # skids in each sample
    k = int(np.argmax(skids > 0))
    assert skids[k] > 0 and k < switch  # a pad skids during the approach
    assert slip_events_after(hand, traj, k) == per_sample[k] - skids[k] < per_sample[k]  # sample k's left out
    assert result.slip_events == slip_events_after(hand, traj, switch) == 0
