"""Which way the hand faces among neighbours (bhgrasp.bench.heading): the turn, the clearance, the choice."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pinocchio as pin
import pytest

from bhgrasp.bench.heading import CLEAR, HEADING_STEP, clearest_heading, hand_base, heading_clearance, headings
from bhgrasp.bench.neighbours import neighbour_displacements, peak_force_on, raised
from bhgrasp.bench.objects import BenchObject
from bhgrasp.bench.protocol import APPROACH, CLOSE_AT, DISTURBED, FRICTION, Trial
from bhgrasp.bench.table import Clutter, floor_below, table_around
from bhgrasp.bench.trial import setup, simulate_trial
from bhgrasp.errors import InputError
from bhgrasp.model.objects import Box, Cylinder

CAN = Trial(BenchObject.parse("cylinder:0.033x0.1:0.35"), "power", table=True)


def turned(pose: pin.SE3, angle: float) -> pin.SE3:
    """``pose`` turned by ``angle`` [rad] about the world z axis (the object's)."""
    return pin.SE3(pin.rpy.rpyToMatrix(0.0, 0.0, angle), np.zeros(3)) * pose


def test_the_hand_turns_about_the_objects_axis():
    """Every heading puts the object's axis at the same place in the hand frame; the simulated hand starts there."""
    axis = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 0.1]])  # two points of the can's axis (world)
    straight = hand_base(CAN, APPROACH)
    for heading in (0.3, -1.2, math.pi):
        base = hand_base(CAN, APPROACH, heading)
        assert np.allclose(base.homogeneous, turned(straight, heading).homogeneous, atol=1e-15)
        for point in axis:
            assert np.allclose(base.actInv(point), straight.actInv(point), atol=1e-15)
        clutter = Clutter((CAN.item.body(FRICTION),), (*table_around(CAN.item), floor_below()), heading=heading)
        hand = setup(CAN, clutter=clutter)[2]
        assert np.array_equal(hand.base_placement.homogeneous, base.homogeneous)
    assert np.array_equal(setup(CAN)[2].base_placement.homogeneous, straight.homogeneous)  # alone: heading 0


def test_the_headings_keep_the_grasp():
    """A round object: every 15 deg, nearest first; a box: a half turn; a household mesh: none."""
    round_turns = headings(CAN)
    assert round_turns[0] == 0.0 and len(round_turns) == len(set(round_turns)) == round(2 * math.pi / HEADING_STEP)
    assert np.all(np.diff(np.abs(round_turns)) >= 0.0)
    steps = np.array(round_turns) / HEADING_STEP
    assert np.allclose(steps, np.round(steps), atol=1e-12)
    assert headings(Trial(BenchObject.parse("box:0.06x0.05x0.05:0.3"), "power")) == [0.0, math.pi]
    assert headings(Trial(BenchObject.parse("box:0.06x0.05x0.05:0.3:mesh"), "power")) == [0.0, math.pi]
    assert headings(Trial(BenchObject.parse("cylinder:0.033x0.1:0.35:mesh"), "power")) == [0.0]  # 64 facets
    assert headings(Trial(BenchObject.parse("household:bottle:0.25"), "power")) == [0.0]


NEIGHBOURS = (
    Box(size=(0.04, 0.05, 0.08), mass=0.2, pose=pin.SE3(np.eye(3), np.array([0.09, 0.03, 0.04])), friction=FRICTION),
    Cylinder(radius=0.025, length=0.1, mass=0.2, pose=pin.SE3(np.eye(3), np.array([-0.06, 0.08, 0.05]))),
)


def test_the_clearance_turns_with_the_neighbours():
    """The whole scene turned about the object's axis: the clearance at heading h + a is the one at h (symmetry)."""
    angle = 2 * HEADING_STEP
    moved = [dataclasses.replace(item, pose=turned(item.pose, angle)) for item in NEIGHBOURS]
    clearances = []
    for heading in (0.0, HEADING_STEP, -3 * HEADING_STEP):
        clearance = heading_clearance(CAN, NEIGHBOURS, heading)
        assert heading_clearance(CAN, moved, heading + angle) == pytest.approx(clearance, abs=1e-9)
        clearances.append(clearance)
    assert np.ptp(clearances) > 0.01  # the headings differ: the symmetry is not that of a constant


def post_under(trial: Trial, finger: str, name: str = "post", angle: float = 0.0, height: float | None = None) -> Box:
    """A 2 cm post 2 cm under ``finger``'s open fingertip (or ``height`` [m] tall), turned ``angle`` [rad] about the
    object's axis."""
    _, state, hand, _ = setup(trial)
    x, y, z = hand.fingertip_positions(state.q)[hand.fingers.index(finger)]
    height = z - 0.02 if height is None else height
    pose = turned(pin.SE3(np.eye(3), np.array([x, y, height / 2])), angle)
    return Box(size=(0.02, 0.02, height), mass=0.2, pose=pose, name=name)


def test_the_hand_turns_away_from_a_post_in_a_fingers_path():
    """A post 2 cm under F3's open fingertip: heading 0 would meet it (tests/test_bench_neighbours.py); the chosen
    heading clears it by CLEAR, and the simulated descent and close leave it where it stood."""
    post = post_under(CAN, "F3")
    assert heading_clearance(CAN, [post], 0.0) < 0.0
    heading, clearance = clearest_heading(CAN, [post])
    assert heading != 0.0 and clearance >= CLEAR
    assert clearance == heading_clearance(CAN, [post], heading)
    clutter = Clutter((CAN.item.body(FRICTION), post), (*table_around(CAN.item), floor_below()), heading=heading)
    trajectory, hand = simulate_trial(CAN, duration=CLOSE_AT + 0.5, clutter=clutter)
    assert neighbour_displacements(trajectory)[0] < 0.1 * DISTURBED
    assert peak_force_on(trajectory, hand, ["post"]) == 0.0


def test_a_box_turns_half_way_and_a_blocked_hand_takes_the_clearest_heading():
    box = Trial(BenchObject.parse("box:0.06x0.05x0.05:0.3"), "power", table=True)
    heading, _ = clearest_heading(box, [post_under(box, "F3", height=0.1)])  # a tall post where F3 comes down
    assert heading == math.pi
    ring = [post_under(CAN, "F3", f"post {k}", k * math.pi / 4) for k in range(8)]  # one every 45 deg
    heading, clearance = clearest_heading(CAN, ring)
    every = {turn: heading_clearance(CAN, ring, turn) for turn in headings(CAN)}
    assert max(every.values()) < CLEAR  # none clear: the clearest, the first of equals
    assert clearance == every[heading] == max(every.values())
    assert heading == next(turn for turn, c in every.items() if c == clearance)


def test_bad_headings_and_starts_are_named():
    table = (*table_around(CAN.item), floor_below())
    for bad in (math.nan, math.inf):
        with pytest.raises(InputError, match="`heading` must be a finite number"):
            Clutter((CAN.item.body(FRICTION),), table, heading=bad)
        with pytest.raises(InputError, match="`heading` must be a finite number"):
            heading_clearance(CAN, NEIGHBOURS, bad)
    with pytest.raises(InputError, match="`approach` must be a finite number >= 0"):
        Clutter((CAN.item.body(FRICTION),), table, approach=-0.01)
    with pytest.raises(InputError, match="at most 0.3 m above its grasp"):
        raised(CAN, Clutter((CAN.item.body(FRICTION),), table, approach=0.5))
