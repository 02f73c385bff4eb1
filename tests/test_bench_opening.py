"""How far the grasp benchmark opens the hand (bhgrasp.bench.opening): the pre-shape wherever the height rule finds a
height there; wider only where the open hand meets the object on its way down, to the first opening that clears it.
Checked against coal's distances at the grasp heights, the first touches at other openings and every object set."""

from __future__ import annotations

import numpy as np
import pytest

from bhgrasp.bench.height import STAND_MARGIN, SWEEP, first_touches, grasp_clearance, grasp_ready
from bhgrasp.bench.objects import SETS, BenchObject
from bhgrasp.bench.opening import top_down, way_in_gap, widened
from bhgrasp.bench.placement import grasp_centre
from bhgrasp.bench.protocol import PRESHAPE, THREE_FINGER_SPREAD, Trial, spread_of
from bhgrasp.bench.reach import reach_of
from bhgrasp.bench.side import approach_of, top_grasp, trial_opening

BALL = BenchObject.parse("sphere:0.07:0.123")  # held-out-3's mini soccer ball


def test_the_open_hand_reaches_into_the_large_ball_at_every_height_of_the_rule() -> None:
    """At the pre-shape F3's open fingertip is 3.5-7.7 mm inside the ball with the knuckles 0-40 mm over its top (and
    F1, F2 30-39 mm off it): no height qualifies there, for the height rule refuses a finger that touches the object
    before it closes."""
    reach = reach_of(BALL, THREE_FINGER_SPREAD, PRESHAPE)
    for clearance in np.arange(0.0, 0.04 + 1e-9, 0.002):
        centre = grasp_centre(BALL, THREE_FINGER_SPREAD, float(clearance), PRESHAPE)
        gaps = {finger: reach.distance(finger, PRESHAPE, centre) for finger in reach.hand.fingers}
        assert -7.75e-3 <= gaps["F3"] <= -3.5e-3, (clearance, gaps)
        assert gaps["F1"] > 0.03 and gaps["F2"] > 0.03
    for grasp in ("power", "precision"):
        assert grasp_clearance(BALL, THREE_FINGER_SPREAD, grasp, PRESHAPE) is None


def test_the_hand_opens_to_the_first_opening_that_clears_the_ball() -> None:
    assert way_in_gap(BALL, THREE_FINGER_SPREAD, 0.0, PRESHAPE) < 0.0
    opening = widened(BALL, THREE_FINGER_SPREAD)
    assert opening == pytest.approx(0.69)
    assert way_in_gap(BALL, THREE_FINGER_SPREAD, 0.0, opening) >= STAND_MARGIN
    assert way_in_gap(BALL, THREE_FINGER_SPREAD, 0.0, round(opening + SWEEP, 9)) < STAND_MARGIN  # the first
    for grasp in ("power", "precision"):
        assert top_down(BALL, THREE_FINGER_SPREAD, grasp) == (opening, 0.0)
        # there every finger first touches the ball below its equator, with its fingertip
        assert grasp_ready(BALL, THREE_FINGER_SPREAD, 0.0, opening, grasp)
        # and a trial comes down so, alone on its stand or on a table among neighbours (no side pinch)
        for table in (False, True):
            trial = Trial(BALL, grasp, table=table)
            assert approach_of(trial) == "top" and trial_opening(trial) == opening and top_grasp(trial)[1] == 0.0


def test_opening_further_changes_no_first_touch() -> None:
    """Why the search stops where the open fingers clear the object: from a wider opening a closing finger passes the
    same angles (the ball's first touches, links and points, from 0.69 and from 0.4 rad)."""
    found = first_touches(BALL, THREE_FINGER_SPREAD, 0.0, 0.69)
    wider = first_touches(BALL, THREE_FINGER_SPREAD, 0.0, 0.4)
    for finger, (link, point) in found.items():
        assert wider[finger][0] == link
        np.testing.assert_allclose(wider[finger][1], point, atol=1e-9)


@pytest.mark.parametrize("name", ["development", "held-out", "held-out-2", "held-out-3", "held-out-4"])
def test_an_object_with_a_height_at_the_preshape_keeps_it(name: str) -> None:
    """The pre-shape and the height rule's height wherever it finds one there, alone on a stand and, for the sets run
    among neighbours, on a table."""
    for item in SETS[name]:
        spread = spread_of(item)
        for grasp in ("power", "precision"):
            for table in (False, True) if name in ("development", "held-out") else (False,):
                height = grasp_clearance(item, spread, grasp, PRESHAPE, table=table)
                found = top_down(item, spread, grasp, table)
                if height is not None:
                    assert found == (PRESHAPE, height), (item.name, grasp, table)
                elif found is not None:  # widened: the open fingers met the object at the pre-shape
                    assert found[0] < PRESHAPE and way_in_gap(item, spread, 0.0, PRESHAPE) < STAND_MARGIN
                    assert way_in_gap(item, spread, found[1], found[0]) >= STAND_MARGIN
