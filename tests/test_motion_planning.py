"""Planning object motions inside a grasp (issue 17, items 2-3): the supervisor's plan, the support's clearance, and
the motions the chapter-5 grasps make, against independent truths (weighted least squares, plane geometry).
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import bhgrasp as bh
from bhgrasp.grasp.clearance import check_clearance, path_clearance
from bhgrasp.scenarios.box_grasp import BOX_SIZE, KNUCKLE_SPACING, OFF_STOP_SPACING, PEDESTAL, box_grasp
from bhgrasp.scenarios.demo_result import SUCCESS
from bhgrasp.scenarios.grasp_demo import run_grasp_demo
from bhgrasp.thesis.motions import run_motion, short_reason


@pytest.fixture(scope="module")
def off_stop():
    return box_grasp(mass=0.6, finger_spacing=OFF_STOP_SPACING)


def test_the_nearest_offset_is_the_weighted_least_squares_one(off_stop) -> None:
    space = off_stop.manipulable_space()
    allowed = space.basis / np.r_[1.0, 1.0, 1.0, [space.length] * 3][:, None]  # allowed twists, unscaled
    request = np.array([0.001, -0.002, 0.01, 0.05, 0.15, 0.2])
    for length in (None, 0.1, 0.01):
        weight = np.r_[1.0, 1.0, 1.0, [space.length if length is None else length] * 3]
        # second method: min_a || W (request - A a) || by lstsq
        a = np.linalg.lstsq(weight[:, None] * allowed, weight * request, rcond=None)[0]
        np.testing.assert_allclose(space.nearest(request, length), allowed @ a, atol=1e-12)
        nearest = space.nearest(request, length)
        assert np.max(space.sliding(nearest)) < 1e-12  # inside the space: no contact slides
        np.testing.assert_allclose(space.nearest(nearest, length), nearest, atol=1e-14)  # a projection


def test_a_turn_over_the_pedestal_penetrates_as_plane_geometry_says() -> None:
    setup = box_grasp()
    shape, start, fixed = setup.box.geometry(), setup.box.pose, setup.simulator.scene.environment
    for angle in (0.05, 0.15, 0.3):
        depth, fraction, name = path_clearance(shape, start, (0, 0, 0, 0, angle, 0), fixed)
        # the bottom face after the turn is the plane n . p = h (p from the box centre, n = R (0, 0, -1) outward): a
        # top edge of the pedestal, p = (+-PEDESTAL/2, y, -h), lies n . p - h from it (negative: inside the box)
        normal = pin.exp3(np.array([0.0, angle, 0.0])) @ np.array([0.0, 0.0, -1.0])
        half = 0.5 * BOX_SIZE[2]
        expected = min(normal[0] * x - normal[2] * half - half for x in (-0.5 * PEDESTAL, 0.5 * PEDESTAL))
        assert depth == pytest.approx(expected, abs=1e-7) and fraction == 1.0 and name == "environment0"


def test_a_turn_on_the_support_is_refused_with_the_lift_that_clears_it() -> None:
    setup = box_grasp()
    shape, start, fixed = setup.box.geometry(), setup.box.pose, setup.simulator.scene.environment
    with pytest.raises(bh.UnreachableError, match=r"1\.78 mm into environment0 at 100 % of its path") as caught:
        check_clearance(shape, start, (0, 0, 0, 0, 0.15, 0), fixed)
    lifted = caught.value.result
    check_clearance(shape, start, lifted, fixed)  # the lift it names clears the path
    short = lifted - [0, 0, 2e-4, 0, 0, 0]  # and 0.2 mm less does not (0.1 mm resolution)
    with pytest.raises(bh.UnreachableError):
        check_clearance(shape, start, short, fixed)
    check_clearance(shape, start, (0, 0, 0.01, 0, 0.3, 0), fixed)  # lifted first: clear
    check_clearance(shape, start, (0, 0, 0, 0, 0, 0.3), fixed)  # a turn about z keeps the bottom face on its top


def test_the_supervisor_plans_a_turn_about_y_the_fingers_make() -> None:
    offset = (0, 0, 0.01, 0, 0.15, 0)
    result = run_grasp_demo(0.6, 0.3, offset=offset, finger_spacing=OFF_STOP_SPACING)
    planned = result.planned_offset
    assert not np.allclose(planned, offset, 0, 1e-6)  # the sensed contacts leave F3 1.6 mm below the centre
    assert np.max(np.abs(planned - offset)) < 1e-3  # a small change
    assert result.slip_events == 0
    assert result.true_position_error < SUCCESS[0] and result.true_rotation_error < SUCCESS[1]  # to the request


def test_a_motion_the_fingers_make_as_asked_is_tracked_unchanged() -> None:
    result = run_grasp_demo(0.6, 0.3)  # the thesis' lift and turn about x
    np.testing.assert_array_equal(result.planned_offset, result.requested_offset)


@pytest.mark.parametrize(
    ("spacing", "offset", "reason"),
    [
        (0.05, (0, 0, 0.01, 0, 0.15, 0), "joint F2_spread at its limit"),
        (OFF_STOP_SPACING, (0, 0, 0.01, 0, 0, 0.15), "F3 would slide 3.75 mm"),
        (OFF_STOP_SPACING, (0.005, 0, 0.01, 0, 0, 0), "F3 would slide 5.00 mm"),
        (OFF_STOP_SPACING, (0, 0, 0, 0, 0.15, 0), "1.78 mm into environment0: lift 1.8 mm first"),
    ],
)
def test_motions_outside_the_grasp_are_refused_with_their_reason(spacing, offset, reason) -> None:
    row = run_motion(spacing, offset)
    assert row == {"refused": True, "reason": reason}


def test_short_reasons_keep_unknown_messages() -> None:
    assert short_reason("something else; more") == "something else"


def test_finger_spacing_is_checked() -> None:
    with pytest.raises(bh.InputError, match=r"`finger_spacing` must be within \[0.05, 0.06\] m"):
        box_grasp(finger_spacing=0.07)
    with pytest.raises(bh.InputError, match="apply to the Barrett scene"):
        run_grasp_demo(hand="allegro", finger_spacing=0.055)


CAN_TURN = (0.0, 0.0, 0.01, 0.0, 0.0, 0.05)  # [m, rad]: a lift and a turn about z


def _can_turn(plan_tolerance):
    """The synthesised can grasp told to turn 0.05 rad about z after a lift: at the contacts it senses it makes only
    part of that (the rest would slide a pad), as the supervisor finds when the move starts.

    (It used to be a turn of 0.1 rad about y, which the sensed contacts made only in part while the can, thrown off
    its pedestal by a wrong contact depth, had settled off its planned contacts; standing still now, the can's pads
    make that turn to within 0.13 mm.)"""
    from dataclasses import replace

    from bhgrasp.controllers.adaptive_grasp import SMCAdaptiveGrasp
    from bhgrasp.controllers.grasp_options import GraspOptions
    from bhgrasp.controllers.supervisor import GraspSupervisor
    from bhgrasp.controllers.supervisor_options import Planning
    from bhgrasp.scenarios.demo_result import evaluate_demo
    from bhgrasp.scenarios.object_grasp import OBJECTS, object_grasp

    setup = object_grasp(OBJECTS["can"][1])
    grasp = SMCAdaptiveGrasp(
        setup.hand,
        replace(setup.item, density=None),
        options=GraspOptions(mu=0.6, squeeze=5.0),
        object_adaptation=(0.0, 0.0),
    )
    offset = np.array(CAN_TURN)
    planning = Planning(tolerance=plan_tolerance)
    supervisor = GraspSupervisor(
        setup.hand, setup.candidate.q_contact, grasp, offset=offset, fingers=setup.candidate.fingers, planning=planning
    )
    traj = setup.simulator.run(supervisor, 3.0, state=setup.state, progress=False)
    return offset, evaluate_demo(
        traj, setup.hand, "smc-adaptive", setup.item.mass, setup.item.mass, supervisor, 0.0, setup.simulator.scene
    )


def test_a_request_the_sensed_contacts_make_only_in_part_is_refused_and_run_anyway_misses_by_that_part() -> None:
    with pytest.raises(bh.UnreachableError, match=r"only to within \d\.\d\d mm and \d\.\d\d mrad") as caught:
        _can_turn((5e-4, 5e-3))  # the default, issue 17's final-pose tolerance
    offset, planned = np.array(CAN_TURN), caught.value.result
    shortfall = np.linalg.norm((offset - planned)[:3])
    assert f"only to within {1e3 * shortfall:.2f} mm" in str(caught.value) and shortfall > 5e-4
    assert short_reason(str(caught.value)).startswith("the sensed contacts miss it by 1.")
    _, result = _can_turn((2e-3, 2e-2))  # looser: it runs, tracks the plan, and ends off the request by the part
    np.testing.assert_allclose(result.planned_offset, planned, atol=1e-12)
    assert result.true_position_error == pytest.approx(shortfall, rel=0.15)
    with pytest.raises(bh.InputError, match="Planning.tolerance"):
        _can_turn((0.0, 5e-3))


def test_a_motion_run_too_short_to_reach_its_motion_says_so() -> None:
    """Chapter 5 at a small --scale: a run that ends before the motion starts names both times (it raised a
    TypeError on the missing plan before)."""
    with pytest.raises(bh.InputError, match=r"a 0.9 s run ends before the motion starts at 0\.93 s: nothing"):
        run_motion(KNUCKLE_SPACING, (0.0, 0.0, 0.01, 0.0, 0.0, 0.0), 0.9)
