"""Clutter (bhgrasp.scenarios.clutter): piles that settle, checked against statics, geometry and closed forms."""

from __future__ import annotations

import pickle
from dataclasses import replace

import numpy as np
import pinocchio as pin
import pytest

import bhgrasp as bh
from bhgrasp.errors import InputError, NotSettled
from bhgrasp.model.objects import Box, Sphere, table
from bhgrasp.scenarios.clutter import MASS, SIZES, bin_walls, drop_pile, drop_poses, mixed_objects
from bhgrasp.sim import Simulator
from bhgrasp.sim.scene import Scene

INNER = np.array([0.24, 0.18])  # the bin of the tests [m], centred on the origin, its floor at z = 0
REGION = (-0.12, -0.09, 0.12, 0.09)


@pytest.fixture(scope="module")
def pile() -> bh.scenarios.clutter.Pile:
    return drop_pile(mixed_objects(8, seed=3), bin_walls(inner=INNER, height=0.1), REGION, seed=3)


def test_settled_pile_is_held_by_its_bin_with_its_weight(pile):
    """At rest the bin's total force on the objects is their weight (the object-object forces cancel in pairs)."""
    weight = sum(item.mass for item in pile.objects) * 9.81
    support = pile.support_force()
    # "at rest" leaves every point under 1 cm/s: the drag then is at most DRAG * 1.5 kg * 0.01 m/s = 0.07 N
    assert support[2] == pytest.approx(weight, rel=1e-4)  # measured: 4e-6
    assert np.linalg.norm(support[:2]) < 1e-3 * weight  # measured: 3e-4
    assert pile.settle_time < 3.0
    assert all(np.all(v == 0.0) for v in (item.velocity for item in pile.objects))


def test_settled_objects_lie_inside_the_bin_without_deep_overlap(pile):
    for item, pose in zip(pile.objects, pile.state.object_poses):
        assert np.array_equal(item.pose.homogeneous, pose.homogeneous)
        assert np.all(np.abs(pose.translation[:2]) < 0.5 * INNER), item.name  # inside the walls
        assert 0.0 < pose.translation[2] < 0.1, item.name  # above the floor, below the walls' top
    # nothing (object, wall or floor) interpenetrates deeper than the start check's quarter of max_penetration
    assert pile.simulator.check_start(pile.state) == []


def test_same_seed_same_bits_other_seed_other_pile():
    objects = mixed_objects(4, seed=11)
    walls = bin_walls(inner=INNER, height=0.1)
    first = drop_pile(objects, walls, REGION, seed=5)
    again = drop_pile(mixed_objects(4, seed=11), walls, REGION, seed=5)
    other = drop_pile(objects, walls, REGION, seed=7)
    assert np.array_equal(first.state.scene_q, again.state.scene_q) and first.settle_time == again.settle_time
    assert not np.array_equal(first.state.scene_q, other.state.scene_q)


def test_mixed_objects_are_drawn_from_their_ranges():
    objects = mixed_objects(40, seed=0)
    assert [o.name for o in objects] == [f"{type(o).__name__.lower()}{i}" for i, o in enumerate(objects)]
    assert {type(o).__name__.lower() for o in objects} == set(SIZES)
    for item in objects:
        assert MASS[0] <= item.mass <= MASS[1]
        for name, ranges in SIZES[type(item).__name__.lower()].items():
            values = np.atleast_1d(getattr(item, name))
            bounds = np.array(ranges).reshape(-1, 2)
            assert np.all((bounds[:, 0] <= values) & (values <= bounds[:, 1])), (item, name)
    again = mixed_objects(40, seed=0)
    assert all(repr(a) == repr(b) for a, b in zip(objects, again))


def test_drop_poses_keep_bounding_spheres_apart():
    objects = mixed_objects(30, seed=2)
    poses = drop_poses(objects, REGION, 0.0, np.random.default_rng(1))
    centres = np.array([p.translation for p in poses])
    radii = np.array([o.bounding_radius for o in objects])
    gaps = np.linalg.norm(centres[:, None] - centres[None], axis=2) - (radii[:, None] + radii[None])
    assert np.min(gaps[~np.eye(len(poses), dtype=bool)]) > 0.0
    assert np.all(centres[:, 2] - radii > 0.0)  # above the floor
    assert np.all(centres[:, :2] - radii[:, None] >= np.array(REGION[:2]) - 1e-12)
    assert np.all(centres[:, :2] + radii[:, None] <= np.array(REGION[2:]) + 1e-12)
    for pose in poses:
        assert np.allclose(pose.rotation @ pose.rotation.T, np.eye(3), atol=1e-12)


def test_bin_walls_bound_the_inner_rectangle():
    walls = bin_walls(centre=(0.1, -0.2), inner=(0.3, 0.2), height=0.08, floor=0.05, thickness=0.01)
    floor, *sides = walls
    assert floor.pose.translation[2] + 0.5 * floor.size[2] == pytest.approx(0.05)
    inner_faces = []
    for wall in sides:
        axis = int(np.argmin(wall.size))  # the wall's thin axis
        centre = wall.pose.translation[axis]
        inner_faces.append(centre - np.sign(centre - (0.1, -0.2)[axis]) * 0.5 * wall.size[axis])
        assert wall.pose.translation[2] - 0.5 * wall.size[2] == pytest.approx(0.05)
        assert wall.size[2] == pytest.approx(0.08)
    assert np.allclose(sorted(inner_faces), sorted([0.1 - 0.15, 0.1 + 0.15, -0.2 - 0.1, -0.2 + 0.1]))


@pytest.mark.parametrize("engine", ["compiled", "python"])
def test_object_drag_decays_velocity_as_the_implicit_step_does(engine):
    """A free sphere in zero gravity: each step divides its velocity and spin by exactly 1 + d dt."""
    hand = bh.BarrettHand()
    hand.gravity = np.zeros(3)
    start = pin.SE3(np.eye(3), np.array([0.0, 0.0, 1.0]))
    ball = Sphere(radius=0.03, mass=0.2, pose=start, velocity=(0.3, -0.1, 0.2, 2.0, 0.0, -1.0))
    drag, dt, steps = 4.0, 1e-3, 200
    simulator = Simulator(Scene(hand, [ball], object_drag=drag), dt=dt, engine=engine)
    state = simulator.initial_state()
    u = np.zeros(hand.nv)
    for _ in range(steps):
        state, _ = simulator.step(state, u)
    expected = np.asarray(ball.velocity) / (1.0 + drag * dt) ** steps
    assert np.allclose(state.object_twists[0], expected, rtol=1e-9, atol=1e-12)
    other = replace(ball, pose=pin.SE3(np.eye(3), np.array([0.0, 0.5, 1.0])), mass=0.2)  # apart: no contact
    per_object = Simulator(Scene(hand, [ball, other], object_drag=(0.0, drag)), dt=dt, engine=engine)
    state = per_object.initial_state()
    for _ in range(steps):
        state, _ = per_object.step(state, u)
    assert np.allclose(state.object_twists[0], ball.velocity, rtol=1e-12, atol=1e-12)  # no drag on the first
    assert np.allclose(state.object_twists[1], expected, rtol=1e-9, atol=1e-12)


@pytest.mark.parametrize("engine", ["compiled", "python"])
def test_object_drag_acts_in_the_body_frame_of_a_turned_box(engine):
    """A box turned at random, spinning about its own z (a principal axis: no gyroscopic torque) and sliding, in
    zero gravity: each step divides velocity and spin by 1 + d dt, whatever the box's orientation."""
    hand = bh.BarrettHand()
    hand.gravity = np.zeros(3)
    turned = pin.SE3(pin.exp3(np.array([0.4, -1.1, 0.7])), np.array([0.0, 0.0, 1.0]))
    spin = turned.rotation @ np.array([0.0, 0.0, 3.0])  # [rad/s] about the box's z, world-aligned
    box = Box(size=(0.08, 0.05, 0.03), mass=0.3, pose=turned, velocity=(0.1, 0.2, -0.1, *spin))
    drag, dt, steps = 3.0, 1e-3, 150
    simulator = Simulator(Scene(hand, [box], object_drag=drag), dt=dt, engine=engine)
    state = simulator.initial_state()
    for _ in range(steps):
        state, _ = simulator.step(state, np.zeros(hand.nv))
    expected = np.asarray(box.velocity) / (1.0 + drag * dt) ** steps
    assert np.allclose(state.object_twists[0], expected, rtol=1e-9, atol=1e-12)


def test_scene_keeps_its_drag_through_pickling():
    scene = Scene(bh.BarrettHand(), [Box(size=(0.05, 0.04, 0.03), mass=0.3)], [table()], object_drag=2.0)
    copy = pickle.loads(pickle.dumps(scene))
    assert copy.object_drag == (2.0,) and np.array_equal(copy.joint_damping, scene.joint_damping)
    assert np.allclose(scene.joint_damping[scene.nv_hand :][:3], 0.6)


def test_a_pile_without_time_to_settle_says_which_objects_move():
    objects = mixed_objects(3, seed=1)
    expected = r"did not settle in 0.05 s \(at rest: .*\): still moving faster than 0.01 m/s: "
    with pytest.raises(NotSettled, match=expected) as caught:
        drop_pile(objects, [table()], REGION, seed=1, max_time=0.05)
    assert list(caught.value.speeds) == [item.name for item in objects]  # every object's speed, by name
    assert max(caught.value.speeds.values()) > 0.01 and caught.value.time == pytest.approx(0.05)


@pytest.mark.parametrize(
    ("call", "message"),
    [
        (lambda: mixed_objects(0, seed=1), "`n` must be an int >= 1"),
        (lambda: mixed_objects(2, seed="a"), "`seed`"),
        (lambda: bin_walls(inner=(0.2, -0.1)), "`inner`"),
        (lambda: drop_pile([], [table()], REGION), "`objects`"),
        (lambda: drop_pile(mixed_objects(2, seed=1), [table()], (0, 0, 0.05, 0.05)), "`region`"),
        (lambda: drop_pile(mixed_objects(2, seed=1), [table()], REGION, max_time=0), "`max_time`"),
        (lambda: Scene(bh.BarrettHand(), [], object_drag=-1.0), "`object_drag`"),
        (lambda: Scene(bh.BarrettHand(), [Sphere(radius=0.02, mass=0.1)], object_drag=(1.0, 2.0)), "one rate per item"),
    ],
)
def test_bad_input_is_named(call, message):
    with pytest.raises(InputError, match=message):
        call()
