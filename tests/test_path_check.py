"""The path-level (second-order) check of an object motion: the fingers followed along the path with rolling contacts.

Against independent truths: its first step is the first-order joint motion P = J_h^+ G^T of the manipulable space, the
pads keep their gap to second order, and on the chapter-5 motion table it flags exactly the motions whose simulated runs
bring a link body onto the box (the 0.3 rad turns about x, where F3's distal link comes within 0.2 mm of the +y face
near 72 % of the path; the simulation's first such contact is at 78 %).
"""

from __future__ import annotations

import numpy as np
import pytest

import bhgrasp as bh
from bhgrasp.controllers.supervisor import MANIPULATE, PLAN_LENGTH, GraspSupervisor
from bhgrasp.grasp.manipulability import manipulable_space
from bhgrasp.grasp.path_check import path_contacts, sensed_path_contacts
from bhgrasp.grasp.sensing import ContactSensing
from bhgrasp.model.objects import Box
from bhgrasp.scenarios.box_grasp import OFF_STOP_SPACING, box_grasp
from bhgrasp.scenarios.grasp_controllers import grasp_controller
from bhgrasp.thesis.motions import ESTIMATE, GRASPS, MASS, MOTIONS


def planned_contacts(setup):
    """The IK contacts of a box grasp: each fingertip's nearest point of the box (as BoxGrasp.manipulable_space)."""
    hand, pose, half = setup.hand, setup.box.pose, 0.5 * np.asarray(setup.box.size)
    tips = hand.fingertip_positions(setup.q_contact)
    points = np.clip((tips - pose.translation) @ pose.rotation, -half, half) @ pose.rotation.T + pose.translation
    return points, [hand.fingertip_frames[f] for f in hand.fingers]


def sensed_start(spacing):
    """The scene and the state at which the supervisor plans the move (a simulation up to the move's start)."""
    setup = box_grasp(mass=MASS, finger_spacing=spacing)
    grasp = grasp_controller("smc-adaptive", setup.hand, Box(size=setup.box.size, mass=ESTIMATE))
    supervisor = GraspSupervisor(setup.hand, setup.q_contact, grasp, q_close=setup.q_close, fingers=setup.fingers)
    seen = []

    def law(t, state):
        tau = supervisor(t, state)
        if supervisor.phase == MANIPULATE and not seen:
            seen.append(state)  # the state _plan read
        return tau

    setup.simulator.run(law, 3.0, state=setup.state, progress=False, until=lambda state: bool(seen))
    return setup, seen[0]


@pytest.fixture(scope="module", params=list(GRASPS))
def started(request):
    return request.param, *sensed_start(GRASPS[request.param][1])


@pytest.mark.parametrize("steps", [10, 40])
def test_the_first_step_is_the_first_order_joint_motion(steps) -> None:
    setup = box_grasp(finger_spacing=OFF_STOP_SPACING)
    space = setup.manipulable_space()
    offset = space.nearest((0, 0, 0.01, 0.2, 0.1, 0), PLAN_LENGTH)
    points, links = planned_contacts(setup)
    box = setup.box
    path = path_contacts(setup.hand, setup.q_contact, points, links, box.geometry(), box.pose, offset, steps)
    np.testing.assert_allclose((path.q[1] - path.q[0]) * steps, space.joint_map @ offset, atol=1e-10)
    assert np.abs(path.gaps - path.gaps[0]).max() < 2e-6 * (40 / steps) ** 2  # the pads' gap holds to second order
    assert path.ok and path.drift.max() < 1e-4  # allowed to first order: little sliding to second


def test_no_motion_moves_nothing() -> None:
    setup = box_grasp()
    points, links = planned_contacts(setup)
    path = path_contacts(setup.hand, setup.q_contact, points, links, setup.box.geometry(), setup.box.pose, np.zeros(6))
    np.testing.assert_array_equal(path.q, np.tile(setup.q_contact, (len(path.q), 1)))
    assert path.ok and np.all(path.clearance == path.clearance[0])


def test_a_spread_on_its_stop_leaves_its_limit_on_a_turn_about_y() -> None:
    setup = box_grasp()  # the first-order check refuses it for the same reason
    points, links = planned_contacts(setup)
    offset = (0, 0, 0.01, 0, 0.15, 0)
    path = path_contacts(setup.hand, setup.q_contact, points, links, setup.box.geometry(), setup.box.pose, offset)
    with pytest.raises(bh.UnreachableError, match=r"joint F\d_spread leaves its limits at \d+ % of the path") as caught:
        path.check()
    assert caught.value.result is path


def test_the_motion_table_flags_the_turns_whose_link_bodies_meet_the_box(started) -> None:
    grasp, setup, state = started
    touching = [c for c in ContactSensing(setup.hand).fingers(state).values() if c.link is not None]
    space = manipulable_space(
        setup.hand,
        state.q,
        [c.point for c in touching],
        [c.normal for c in touching],
        [c.link for c in touching],
        state.object_poses[0].translation,
    )
    checked = []
    for motion, (_, offset) in MOTIONS.items():
        try:  # the first-order checks of run_grasp_demo
            setup.manipulable_space().check(offset)
            setup.check_clearance(offset)
        except bh.UnreachableError:
            continue
        planned = space.nearest(offset, PLAN_LENGTH)  # what the supervisor tracks (GraspSupervisor._plan)
        path = sensed_path_contacts(setup.hand, state, setup.box.geometry(), planned)
        checked.append(motion)
        if motion != "rx+0.3":
            assert path.ok, (grasp, motion, path)
            continue
        touch = path.touch
        assert (touch.geometry, touch.link, touch.face) == ("F3_distal_link_0", "F3_distal_link", "+y")
        assert 0.7 <= touch.fraction <= 0.8 and touch.spacing > 5e-3  # beside the pad, not at it
        k, column = int(np.searchsorted(path.fractions, touch.fraction)), path.geometries.index(touch.geometry)
        assert path.clearance[k, column] < path.tolerance <= path.clearance[k - 1, column]  # first within it
        assert path.clearance[-1, column] < 0.0  # and into the face at the end
        with pytest.raises(
            bh.UnreachableError, match=r"F3_distal_link_0 \(F3_distal_link\) comes within 0\.2 mm of the object's \+y"
        ):
            path.check()
    expected = {"on_stop": 5, "off_stop": 9}[grasp]  # the table's motions that run: 5 + 9 = 14
    assert len(checked) == expected and "rx+0.3" in checked


def test_contacts_must_lie_on_a_link_with_geometry() -> None:
    setup = box_grasp()
    points, _ = planned_contacts(setup)
    with pytest.raises(bh.InputError, match="link 'palm_nothing' is not a hand frame carrying collision geometry"):
        path_contacts(
            setup.hand, setup.q_contact, points, ["palm_nothing"] * 3, setup.box.geometry(), setup.box.pose, np.zeros(6)
        )
