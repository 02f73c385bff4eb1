"""The grasp chosen for the motion asked, for any object (bhgrasp.scenarios.object_choice): checked against each
candidate's own checks, the supervisor's refusal when the move starts, and by running the chosen grasp."""

from __future__ import annotations

import time

import pytest

from bhgrasp.errors import InputError, UnreachableError
from bhgrasp.scenarios.object_choice import checked_candidate, describe, grasp_for_motion
from bhgrasp.scenarios.object_grasp import OBJECTS, object_grasp, run_object_grasp

CAN = OBJECTS["can"][1]
TURN_X = (0.0, 0.0, 0.01, -0.15, 0.0, 0.0)  # lift 10 mm, turn -0.15 rad about x
TURN_Z = (0.0, 0.0, 0.01, 0.0, 0.0, 0.15)  # F3 has no spread: its contact would slide in every grasp


@pytest.fixture(scope="module")
def candidates():
    from dataclasses import replace

    from bhgrasp.grasp.synthesis import grasp_candidates
    from bhgrasp.model.barrett_hand import BarrettHand
    from bhgrasp.scenarios.box_grasp import FRICTION

    return grasp_candidates(BarrettHand(), replace(CAN, friction=FRICTION, density=None), 0.6)


def test_a_grasp_the_supervisor_refuses_at_the_move_passes_the_motion_to_the_next(candidates) -> None:
    """The can's best grasp passes every check before simulating, but at the contacts the fingers sense F1's distal
    link body would meet the can: that run is refused when the move starts, and the second grasp makes the turn."""
    best = object_grasp(CAN, candidate=candidates[0])
    checked_candidate(best, TURN_X)  # passes before simulating
    with pytest.raises(UnreachableError, match="F1_distal_link"):
        run_object_grasp(best, offset=TURN_X)  # refused by the supervisor when the move starts
    result = grasp_for_motion(CAN, TURN_X, candidates=candidates)
    choice = result.grasp_choice
    assert choice.label == f"candidate 2 of {len(candidates)} ({describe(candidates[1])})"
    assert len(choice.refused) == 1 and choice.refused[0][1].startswith("refused when the move started:")
    assert result.slip_events == 0 and result.slide == 0.0
    assert result.true_position_error < 5e-4 and result.true_rotation_error < 5e-3
    with pytest.raises(UnreachableError, match="refused the motion .* in all 1 runs allowed") as refused:
        grasp_for_motion(CAN, TURN_X, candidates=candidates, tries=1)
    assert refused.value.result[0][0].startswith("candidate 1 of")


def test_a_motion_no_grasp_makes_is_refused_before_any_run_with_the_best_grasps_reason(candidates) -> None:
    start = time.perf_counter()
    with pytest.raises(UnreachableError, match=r"none of the 15 .* \(0 refused when the move started\)") as refused:
        grasp_for_motion(CAN, TURN_Z, candidates=candidates)
    assert time.perf_counter() - start < 30.0  # checks only (~0.1 s here), no 3 s simulation per grasp
    reasons = refused.value.result
    assert len(reasons) == len(candidates) == 15 and "F3 would slide" in reasons[0][1]
    with pytest.raises(UnreachableError, match="F3 would slide"):
        checked_candidate(object_grasp(CAN, candidate=candidates[0]), TURN_Z)


@pytest.mark.parametrize(
    ("arguments", "message"),
    [
        ({"tries": 0}, "`tries` must be an integer >= 1, got 0"),
        ({"tries": 1.5}, "`tries` must be an integer >= 1, got 1.5"),
        ({"offset": (0.0, 0.01)}, r"`offset` must have shape \(6,\)"),
        ({"item": "can"}, "`item` must be a bhgrasp rigid object"),
    ],
)
def test_bad_arguments_are_named(arguments: dict, message: str) -> None:
    call = {"item": CAN, "offset": TURN_X, **arguments}
    with pytest.raises(InputError, match=message):
        grasp_for_motion(call.pop("item"), call.pop("offset"), **call)


def test_grasps_without_force_closure_are_never_run() -> None:
    """A 5 mm shift of the box along x: no three-finger grasp makes it (F3 would slide), and the two-finger pinches
    that would (no force closure: the box turned 0.56 rad about their axis when one was run) are refused unrun."""
    box = OBJECTS["box"][1]
    with pytest.raises(UnreachableError, match=r"\(0 refused when the move started\)") as refused:
        grasp_for_motion(box, (0.005, 0.0, 0.01, 0.0, 0.0, 0.0))
    reasons = dict(refused.value.result)
    open_grasps = [label for label in reasons if "epsilon 0.000" in label]
    assert open_grasps and all(reasons[label].startswith("not a force-closure grasp") for label in open_grasps)
    assert "F3 would slide" in next(iter(reasons.values()))
