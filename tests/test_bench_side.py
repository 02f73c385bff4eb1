"""The grasp benchmark's side pinch (bhgrasp.bench.side): where a top-down grasp has no height, F1 and F2 pinch the
object in a horizontal plane with the palm sideways; checked against the hand's geometry and against Newton."""

from __future__ import annotations

import coal
import numpy as np
import pinocchio as pin
import pytest

from bhgrasp.bench.heading import hand_base
from bhgrasp.bench.height import STAND_HEIGHT, STAND_MARGIN
from bhgrasp.bench.metrics import least_grip
from bhgrasp.bench.objects import DEVELOPMENT_SET, HELD_OUT_SET, HELD_OUT_SET_2, HELD_OUT_SET_3, BenchObject
from bhgrasp.bench.protocol import CLOSE_AT, FRICTION, HELD_AT, LIFT_AT, PRESHAPE, Trial, spread_of
from bhgrasp.bench.reach import SIDEWAYS, hand_depth
from bhgrasp.bench.side import (
    PINCH,
    SIDE_SPREAD,
    approach_of,
    closing_fingers,
    finger_half_width,
    pinch_height,
    side_centre,
    trial_opening,
    trial_reach,
    trial_spread,
    way_in,
)
from bhgrasp.bench.trial import BenchController, setup, simulate_trial
from bhgrasp.grasp.probes import coal_transform

G = 9.81
TUNA = BenchObject.parse("cylinder:0.043x0.033:0.17")  # the held-out set's short wide can
FLAT = DEVELOPMENT_SET[3]  # the development set's 3 cm flat box


# the objects whose trials failed for want of a grasp height before the side pinch (the committed report of main
# 904705d, docs/results/grasp_benchmark.md): an independent list of the low and small objects
NO_HEIGHT_FROM_ABOVE = {
    *("flat box", "tuna can", "pudding box", "tennis ball", "gelatin box", "racquetball", "golf ball"),
    *("sponge", "peach", "plum", "lemon"),  # held-out-3's, seen in its one run
}
# held-out-3's 70 mm ball: no height at the pre-shape, whose open F3 it reaches into; from above with the hand opened
# wider (bench.opening), where its one run pinched it from the side
SOCCER_BALL = BenchObject.parse("sphere:0.07:0.123")


def test_a_side_pinch_is_taken_exactly_where_no_top_down_height_qualifies() -> None:
    """The eleven low or small objects of the four sets pinch from the side, every other object keeps its top-down
    grasp (the 70 mm ball with its hand opened wider); a study of the spread never pinches; on a table no pinch
    qualifies for any of them."""
    for item in (*DEVELOPMENT_SET, *HELD_OUT_SET, *HELD_OUT_SET_2, *HELD_OUT_SET_3):
        for grasp in ("power", "precision"):
            trial = Trial(item, grasp)
            low = item.name in NO_HEIGHT_FROM_ABOVE
            assert approach_of(trial) == ("side" if low else "top"), (item.name, grasp)
            assert closing_fingers(trial) == (PINCH if low else ("F1", "F2", "F3"))
            assert trial_spread(trial) == (SIDE_SPREAD if low else spread_of(item))
            assert trial_opening(trial) == (PRESHAPE if item.spec != SOCCER_BALL.spec else pytest.approx(0.69))
            if low:
                assert side_centre(item, grasp, table=True) is None, item.name
                assert approach_of(Trial(item, grasp, table=True)) == "top"
    assert approach_of(Trial(FLAT, "power", spread=0.0)) == "top"


def test_the_rule_rests_a_box_on_the_knuckle_housings_and_a_round_object_just_off_them() -> None:
    """For each of the eleven, the rule's first grid point qualifies (the object's near side on the housings' plane):
    a box's face touches the housings (coal: within 1e-6 m), a ball or the tuna can, tangent to the palm's axis
    there, clears the housings, which stand to its sides, by 1.4-2.9 mm (coal; 1.47 mm the tuna can's)."""
    for item in (*DEVELOPMENT_SET, *HELD_OUT_SET, *HELD_OUT_SET_2, *HELD_OUT_SET_3):
        if item.name not in NO_HEIGHT_FROM_ABOVE:
            continue
        reach, centre = trial_reach(Trial(item, "power"))
        assert centre[2] == pytest.approx(hand_depth(SIDE_SPREAD, PRESHAPE) + item.half_extents[0], abs=1e-12)
        pin.updateGeometryPlacements(
            reach.hand.model, reach.model_data, reach.geometry, reach.data, reach.configuration(PRESHAPE)
        )
        where = coal.Transform3s(reach.axes, centre)
        gap = min(
            coal.distance(
                shape.geometry,
                coal_transform(reach.data.oMg[i]),
                reach.shape,
                where,
                coal.DistanceRequest(),
                coal.DistanceResult(),
            )
            for i, shape in enumerate(reach.geometry.geometryObjects)
            if "knuckle" in shape.name
        )
        if item.kind == "box":
            assert abs(gap) < 1e-6, item.name
        else:
            assert 1.4e-3 < gap < 3.0e-3, (item.name, gap)


def test_on_a_table_the_sideways_palm_would_be_inside_it() -> None:
    """Why no pinch qualifies on a table: at the flat box's pinch (found on its stand), the palm's cylinder reaches
    below the table's top, which the stand's footprint leaves free (coal, in the world)."""
    base = hand_base(Trial(FLAT, "power"))
    reach, _ = trial_reach(Trial(FLAT, "power"))
    pin.updateGeometryPlacements(
        reach.hand.model, reach.model_data, reach.geometry, reach.data, reach.configuration(PRESHAPE)
    )
    palm = reach.geometry.getGeometryId("palm_0")
    frame = coal_transform(base * reach.data.oMg[palm])
    shape = reach.geometry.geometryObjects[palm].geometry
    table = coal.Box(0.4, 0.4, 0.02)
    stand = coal.Box(*(2 * FLAT.half_extents[:2]), STAND_HEIGHT)
    gap = lambda box, depth: coal.distance(  # noqa: E731
        shape,
        frame,
        box,
        coal.Transform3s(np.eye(3), np.array([0, 0, -depth])),
        coal.DistanceRequest(),
        coal.DistanceResult(),
    )
    assert gap(table, 0.01) < -0.02  # over 2 cm into the table
    assert gap(stand, 0.5 * STAND_HEIGHT) >= STAND_MARGIN


def test_the_pinch_plane_and_the_fingers_stand_where_the_rule_says() -> None:
    """The geometry in closed form: the pinch plane at the object's mid-height or a finger's half width plus the
    margin above the stand; F1 and F2 at the side spread face each other across the hand (their closing planes are
    one plane, the hand's y = 0); the hand base puts the object's centre where side_centre says, palm sideways."""
    assert finger_half_width() == pytest.approx(0.025 / 2 + 0.0003, abs=1e-9)  # the knuckle housing: 25 mm, 0.3 off
    assert pinch_height(FLAT) == pytest.approx(finger_half_width() + STAND_MARGIN)  # 15 mm to its middle: too low
    tall = BenchObject.parse("box:0.06x0.05x0.05:0.3")
    assert pinch_height(tall) == pytest.approx(0.025)
    trial = Trial(TUNA, "precision")
    reach, centre = trial_reach(trial)
    assert centre[0] == 0.0 and centre[1] == pytest.approx(TUNA.half_extents[2] - pinch_height(TUNA))
    base = hand_base(trial)
    np.testing.assert_allclose(base.rotation, SIDEWAYS)
    np.testing.assert_allclose(base.act(centre), [0.0, 0.0, TUNA.half_extents[2]], atol=1e-12)
    np.testing.assert_allclose(way_in(trial), base.rotation[:, 2])  # in along the palm's normal
    np.testing.assert_allclose(hand_base(trial, 0.05).translation, base.translation - 0.05 * way_in(trial))
    # at the side spread F1's and F2's proximal axes are both along hand y: the fingers close in planes normal to it
    hand = reach.hand
    data = hand.model.createData()
    pin.forwardKinematics(hand.model, data, reach.configuration(PRESHAPE))
    for finger in PINCH:
        joint = data.oMi[hand.model.getJointId(f"{finger}_proximal")]
        assert abs(joint.rotation[:, 2] @ [0, 1, 0]) == pytest.approx(1.0) and joint.translation[1] == pytest.approx(0)


def test_the_side_rule_keeps_the_hand_off_the_stand_and_touches_with_the_fingertips() -> None:
    """A second method for part of the rule: at the planned grasp every shape of the open hand is at least the
    margin from the stand (coal, the hand and the stand placed in the world), and each pinching finger's first touch
    is on its distal link, within a finger's half width of the pinch plane."""
    trial = Trial(TUNA, "precision")
    reach, centre = trial_reach(trial)
    base = hand_base(trial)
    stand = coal.Box(*(2 * TUNA.half_extents[:2]), STAND_HEIGHT)
    where = coal.Transform3s(np.eye(3), np.array([0.0, 0.0, -0.5 * STAND_HEIGHT]))
    q = reach.configuration(PRESHAPE)
    pin.updateGeometryPlacements(reach.hand.model, reach.model_data, reach.geometry, reach.data, q)
    for i, shape in enumerate(reach.geometry.geometryObjects):
        frame = coal_transform(base * reach.data.oMg[i])
        gap = coal.distance(shape.geometry, frame, stand, where, coal.DistanceRequest(), coal.DistanceResult())
        assert gap >= STAND_MARGIN, shape.name
    plane = pinch_height(TUNA) - TUNA.half_extents[2]  # the pinch plane, the can's frame
    for finger in PINCH:
        link, point = reach.first_touch(finger, centre)
        assert "distal" in link and abs(point[2] - plane) <= finger_half_width(), (finger, link, point)


def test_a_side_pinch_closes_f1_and_f2_only_and_holds_f3_open() -> None:
    """The driver closes F1 and F2 (their pucks drive, F3's does not); the idealised hand holds F3 where it was: a
    push off its start meets a restoring torque."""
    trial = Trial(TUNA, "precision")
    _, state, hand, path = setup(trial)
    assert state.q[hand.joint_index("F1_spread")] == SIDE_SPREAD == state.q[hand.joint_index("F2_spread")]
    controller = BenchController(trial, hand, path)
    controller.reset(state)
    for t in np.arange(0.0, CLOSE_AT + 0.01, 0.0025):  # the state held still: the pucks stall out later
        u = controller(float(t), state)
    assert u[1] > 0.0 and u[2] > 0.0 and u[3] == 0.0  # the pucks of F1, F2, F3 just after the close: F1, F2 drive
    full = Trial(TUNA, "precision", "full")
    simulator, state, hand, path = setup(full)
    controller = BenchController(full, hand, path)
    controller.reset(state)
    for link in ("proximal", "distal"):
        joint = hand.joint_index(f"F3_{link}")
        assert controller(CLOSE_AT + 0.1, state)[joint] == 0.0  # at its start, at rest: nothing to hold
        assert controller(CLOSE_AT + 0.1, state)[hand.joint_index(f"F1_{link}")] > 0.0
        q = np.array(state.q)
        q[joint] += 0.05
        assert controller(CLOSE_AT + 0.1, simulator.initial_state(q))[joint] < 0.0  # pushed off: pulled back


def test_a_turned_side_pinch_keeps_the_object_where_the_rule_puts_it() -> None:
    """A heading turns the hand about the object's vertical axis: the object's centre stays at the grasp, the palm's
    normal turns in the horizontal plane, the base's way in with it."""
    trial = Trial(TUNA, "precision")
    _, centre = trial_reach(trial)
    for heading in (0.7, np.pi):
        base = hand_base(trial, 0.0, heading)
        turn = pin.rpy.rpyToMatrix(0.0, 0.0, heading)
        np.testing.assert_allclose(base.rotation, turn @ SIDEWAYS, atol=1e-15)
        np.testing.assert_allclose(base.act(centre), [0.0, 0.0, TUNA.half_extents[2]], atol=1e-12)
        back = hand_base(trial, 0.05, heading).translation - base.translation
        np.testing.assert_allclose(back, -0.05 * turn @ way_in(trial), atol=1e-15)
        assert back[2] == pytest.approx(0.0, abs=1e-15)


def test_the_tuna_can_pinched_from_the_side_hangs_from_two_fingers_by_friction() -> None:
    """Newton at rest once lifted: F1's and F2's contacts carry the can's weight, F3 touches nothing; each fingertip
    presses at least its share m g / (2 mu); the can rests on both knuckle housings (the rule puts it there); no
    finger touches the stand; the can rose with the wrist."""
    trial = Trial(TUNA, "precision")
    trajectory, _ = simulate_trial(trial, duration=HELD_AT)
    name = trajectory.object_names[0]
    window = range(int(np.searchsorted(trajectory.t, HELD_AT - 0.3)), len(trajectory.t))  # the can at rest: its
    carried = []  # momentum constant, so the mean of the stiff contacts' chatter (+/-0.2 N) carries the weight
    for k in window:
        contacts = trajectory.contacts_at(k)
        on = [i for i, (a, b) in enumerate(contacts["bodies"]) if b == name and a != "pedestal"]
        assert on and {contacts["bodies"][i][0][:2] for i in on} == set(PINCH)
        assert not any("pedestal" in pair for pair in contacts["bodies"])
        carried.append(contacts["force"][on].sum(axis=0))
    np.testing.assert_allclose(np.mean(carried, axis=0), [0, 0, TUNA.mass * G], atol=0.01 * TUNA.mass * G)
    assert np.ptp([trajectory.object_position[k, 0] for k in window], axis=0).max() < 1e-5
    pressing = np.einsum("ij,ij->i", contacts["normal"][on], contacts["force"][on])  # the last sample
    links = [contacts["bodies"][i][0] for i in on]
    for finger in PINCH:  # the fingers' links (the record's held force), not their knuckle housings
        mine = sum(max(float(p), 0.0) for link, p in zip(links, pressing) if link.startswith(f"{finger}_distal"))
        assert mine >= least_grip(TUNA.mass, 2) == pytest.approx(TUNA.mass * G / (2 * FRICTION))
    assert {"F1_knuckle_link", "F2_knuckle_link"} <= set(links)  # the rule's premise: the can on the housings
    start = int(np.searchsorted(trajectory.t, LIFT_AT - 1e-9))
    assert trajectory.object_position[k, 0, 2] - trajectory.object_position[start, 0, 2] == pytest.approx(0.1, abs=2e-3)


def test_the_readme_states_the_committed_figures_of_the_held_grasps() -> None:
    """The README's figures of the held-out sets' held grasps, from above and pinched from the side, are the committed
    report's (regenerated and compared in CI): the worst displacement and turn, the fingers' held forces, the most
    loaded joint's fraction of its rating, the peak contact."""
    import json
    import math

    from bhgrasp.thesis.results import REFERENCE

    readme = " ".join((REFERENCE.parents[1] / "README.md").read_text().split())
    trials = json.loads((REFERENCE / "grasp_benchmark.json").read_text())["trials"]
    held = [t for t in trials if t["set"] != "development" and t["success"]]
    top = (
        "Over the five held-out sets, from above: at most {} mm and {} deg under the pushes, each finger pressing "
        "{}-{} N, every joint at most {} of its rating, no contact above {} N."
    )
    side = (
        "at most {} mm and {} deg, each pinching finger pressing {}-{} N, every joint at most {} of its rating, no "
        "contact above {} N."
    )
    for approach, fingers, text in (("top", ("F1", "F2", "F3"), top), ("side", PINCH, side)):
        group = [t for t in held if t["approach"] == approach]
        forces = [t[f"held_force_{finger}"] for t in group for finger in fingers]
        figures = (
            f"{1e3 * max(t['max_displacement'] for t in group):.1f}",
            f"{math.degrees(max(t['max_rotation'] for t in group)):.1f}",
            f"{min(forces):.0f}",
            f"{max(forces):.0f}",
            f"{max(t['torque_to_rating'] for t in group):.2f}",
            f"{max(t['peak_contact_force'] for t in group):.0f}",
        )
        assert text.format(*figures) in readme, (approach, figures)
