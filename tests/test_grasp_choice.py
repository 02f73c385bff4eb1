"""The grasp chosen for the motion asked (bhgrasp.scenarios.grasp_choice): the first pinch that makes it, else each
pinch's reason; checked against each pinch's own check and by running the chosen grasp."""

from __future__ import annotations

import numpy as np
import pytest

from bhgrasp.errors import UnreachableError
from bhgrasp.scenarios.box_grasp import KNUCKLE_SPACING, OFF_STOP_SPACING, box_grasp
from bhgrasp.scenarios.grasp_choice import PINCHES, GraspChoice, checked_pinch, choose_pinch
from bhgrasp.scenarios.grasp_demo import OFFSET, run_grasp_demo

TURN_Y = (0.0, 0.0, 0.01, 0.0, 0.3, 0.0)  # lift 10 mm and turn 0.3 rad about y: the thesis pinch's spread is stuck


def own_reason(spacing: float, offset) -> str | None:
    """What the pinch's own checks say of ``offset`` (None: it makes it)."""
    try:
        checked_pinch(box_grasp(mass=0.6, finger_spacing=spacing), offset)
    except UnreachableError as error:
        return str(error)
    return None


def test_the_demo_motion_goes_to_the_thesis_pinch_with_nothing_refused() -> None:
    _, choice = choose_pinch(0.6, OFFSET, 1e4)
    assert choice == GraspChoice(PINCHES[0][0], KNUCKLE_SPACING, ())


def test_a_turn_about_y_goes_to_the_pinch_off_its_stop_with_the_thesis_pinch_reason_kept() -> None:
    setup, choice = choose_pinch(0.6, TURN_Y, 1e4)
    assert choice.label == PINCHES[1][0] and choice.finger_spacing == OFF_STOP_SPACING
    np.testing.assert_array_equal(setup.q_contact, box_grasp(mass=0.6, finger_spacing=OFF_STOP_SPACING).q_contact)
    reason = own_reason(KNUCKLE_SPACING, TURN_Y)
    assert reason is not None and "F2_spread reaches its limit" in reason
    assert choice.refused == ((PINCHES[0][0], reason),)
    assert own_reason(OFF_STOP_SPACING, TURN_Y) is None
    assert "refused pinch, spread on its stop" in choice.summary() and "55.0 mm" in choice.summary()


def test_a_motion_no_pinch_makes_is_refused_with_every_reason() -> None:
    shift_x = (0.005, 0.0, 0.0, 0.0, 0.0, 0.0)  # F3 has no spread: its contact would slide
    with pytest.raises(UnreachableError) as refused:
        choose_pinch(0.6, shift_x, 1e4)
    message = str(refused.value)
    for label, spacing in PINCHES:
        assert f"{label}: {own_reason(spacing, shift_x)}" in message
    assert refused.value.result is not None  # the thesis pinch's nearest offset without sliding


def test_the_demo_makes_the_turn_about_y_with_the_pinch_it_chose() -> None:
    """By default the demo gives the turn to the pinch off its stop and makes it (no slip, within 0.5 mm / 5 mrad);
    told the thesis pinch, it refuses before simulating."""
    result = run_grasp_demo(offset=TURN_Y)
    assert result.grasp_choice.finger_spacing == OFF_STOP_SPACING
    assert result.slip_events == 0 and result.true_position_error < 5e-4 and result.true_rotation_error < 5e-3
    with pytest.raises(UnreachableError, match="F2_spread reaches its limit"):
        run_grasp_demo(offset=TURN_Y, finger_spacing=KNUCKLE_SPACING)


def test_the_default_choice_runs_the_same_bits_as_the_thesis_pinch_given() -> None:
    chosen = run_grasp_demo(duration=0.8)
    given = run_grasp_demo(duration=0.8, finger_spacing=KNUCKLE_SPACING)
    assert chosen.grasp_choice.label == PINCHES[0][0] and given.grasp_choice.label == "the given pinch"
    np.testing.assert_array_equal(chosen.trajectory.q, given.trajectory.q)
    np.testing.assert_array_equal(chosen.trajectory.object_position, given.trajectory.object_position)
