"""Continuous object paths (:mod:`bhgrasp.motion.paths`) and the chapter-5 circle: closed forms against finite
differences and plane geometry, and a grasped box carried around the circle without slip."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import bhgrasp as bh
from bhgrasp.motion.paths import PoseCircle, PoseWaypoints
from bhgrasp.motion.pose_references import PosePath
from bhgrasp.scenarios.carry import PLANES, WAYPOINTS, circle, run_path, waypoints
from bhgrasp.scenarios.object_grasp import OBJECTS, object_grasp

START = pin.SE3(pin.rpy.rpyToMatrix(0.1, -0.2, 0.3), np.array([0.01, -0.02, 0.17]))
TILTED = (np.array([0.0, 1.0, 1.0]) / np.sqrt(2.0), np.array([1.0, 0.0, 0.0]))


@pytest.mark.parametrize("turns", [1.0, 2.5])
def test_velocity_and_acceleration_are_the_derivatives_of_the_pose(turns) -> None:
    circle = PoseCircle(START, 0.004, TILTED, duration=1.5, delay=0.2, turns=turns)
    h = 1e-6
    for t in np.linspace(0.0, circle.end_time + 0.1, 41):
        x, v, a = circle(t)
        x_minus, v_minus, _ = circle(t - h)
        x_plus, v_plus, _ = circle(t + h)
        np.testing.assert_allclose(v[:3], (x_plus[:3] - x_minus[:3]) / (2 * h), atol=2e-7)
        np.testing.assert_allclose(a[:3], (v_plus[:3] - v_minus[:3]) / (2 * h), atol=5e-5)
        np.testing.assert_allclose(x[3:], pin.log3(START.rotation), atol=1e-15)  # the orientation is held
        assert not v[3:].any() and not a[3:].any()


def test_the_path_lies_on_its_circle_and_closes_at_rest() -> None:
    radius, lift = 0.004, np.array([0.0, 0.0, 0.01])
    circle = PoseCircle(START, radius, TILTED, duration=2.0, delay=0.3, lift=lift, lift_time=0.5)
    lifted = START.translation + lift
    centre = lifted + radius * TILTED[0]
    normal = np.cross(*TILTED)
    for t in np.linspace(circle.delay + circle.lift_time, circle.end_time, 50):
        x = circle(t)[0][:3]
        assert np.linalg.norm(x - centre) == pytest.approx(radius, abs=1e-15)  # on the circle
        assert abs((x - centre) @ normal) < 1e-16  # in its plane
    end, velocity, acceleration = circle(circle.end_time + 1.0)
    np.testing.assert_allclose(end[:3], lifted, atol=1e-15)  # once around: back at the lifted point
    assert not velocity.any() and not acceleration.any()
    np.testing.assert_allclose(
        circle(circle.delay + circle.lift_time + 1.0)[0][:3], lifted + 2 * radius * TILTED[0], atol=1e-15
    )  # halfway (the blend's midpoint): across the centre
    assert circle(0.29)[0][:3] == pytest.approx(START.translation, abs=1e-15)  # before the delay: at the start


def test_extremes_are_points_of_the_path() -> None:
    circle = PoseCircle(pin.SE3.Identity(), 0.004, PLANES["y-z"])
    extremes = circle.extremes()
    assert extremes.shape == (8, 6) and not extremes[:, 3:].any()
    np.testing.assert_allclose(extremes[0, :3], circle.lift)
    for row in extremes[1:]:
        assert np.linalg.norm(row[:3] - circle.lift - [0.0, 0.004, 0.0]) == pytest.approx(0.004)


@pytest.mark.parametrize(
    ("arguments", "message"),
    [
        ({"radius": 0.0}, "radius"),
        ({"radius": 0.004, "plane": ((0, 1, 0), (0, 1, 0))}, "orthonormal"),
        ({"radius": 0.004, "plane": ((0, 2, 0), (0, 0, 1))}, "orthonormal"),
        ({"radius": 0.004, "turns": -1.0}, "turns"),
        ({"radius": 0.004, "duration": np.nan}, "duration"),
    ],
)
def test_bad_circles_are_refused_with_the_value(arguments, message) -> None:
    with pytest.raises(bh.InputError, match=message):
        PoseCircle(START, **arguments)


@pytest.fixture(scope="module")
def box_setup():
    return object_grasp(OBJECTS["box"][1])


def test_the_thesis_pinch_carries_the_box_around_a_vertical_circle_without_slip(box_setup) -> None:
    run = run_path(box_setup, circle())
    assert run.slip_events == 0 and run.cone_margin > 0.0  # the commanded forces inside the assumed cones
    assert run.success and run.max_deviation < 0.5e-3  # [m] from the path, all the way around
    centre = run.reference[0] + [0.0, 0.004, 0.0]
    assert np.abs(np.linalg.norm(run.position - centre, axis=1) - 0.004).max() < 0.5e-3  # the object's own circle


def test_a_horizontal_circle_is_refused_before_simulating(box_setup) -> None:
    with pytest.raises(bh.UnreachableError, match="missing: translation along x"):
        run_path(box_setup, circle(plane="x-y"))


MOVES = [
    ((0.0, 0.0, 0.01, 0.0, 0.0, 0.0), 0.6),
    ((0.0, 0.003, 0.0, 0.15, 0.0, 0.0), 0.8),
    ((0.0, -0.003, 0.0, 0.0, 0.15, 0.0), 0.8),
    ((0.0, 0.0, 0.0, -0.15, -0.15, 0.0), 1.0),
]


def _rotation(sample: np.ndarray) -> np.ndarray:
    return pin.exp3(sample[3:])


def test_blended_waypoints_have_the_derivatives_of_their_pose() -> None:
    path = PoseWaypoints(START, MOVES, overlap=0.3, delay=0.1)
    h = 1e-6
    for t in np.linspace(0.0, path.end_time + 0.1, 61):
        _, v, a = path(t)
        (x_minus, v_minus, _), (x_plus, v_plus, _) = path(t - h), path(t + h)
        np.testing.assert_allclose(v[:3], (x_plus[:3] - x_minus[:3]) / (2 * h), atol=2e-7)
        omega = pin.log3(_rotation(x_plus) @ _rotation(x_minus).T) / (2 * h)  # world angular velocity
        np.testing.assert_allclose(v[3:], omega, atol=2e-6)
        np.testing.assert_allclose(a, (v_plus - v_minus) / (2 * h), atol=5e-4)


def test_without_overlap_the_waypoints_are_the_pose_path_and_with_it_the_path_never_stops() -> None:
    joined, rest = PoseWaypoints(START, MOVES), PosePath(START, MOVES)
    for t in np.linspace(0.0, rest.end_time, 37):
        for ours, theirs in zip(joined(t), rest(t)):
            np.testing.assert_allclose(ours, theirs, atol=1e-12)
    blended = PoseWaypoints(START, MOVES, overlap=0.3)
    assert blended.end_time == pytest.approx(rest.end_time - 3 * 0.3)
    end = blended(blended.end_time + 1.0)
    np.testing.assert_allclose(end[0][:3], rest.end.translation, atol=1e-15)  # the same last waypoint
    np.testing.assert_allclose(_rotation(end[0]), rest.end.rotation, atol=1e-12)
    assert not end[1].any() and not end[2].any()  # at rest there
    inner = np.linspace(0.05, blended.end_time - 0.05, 200)
    assert min(np.linalg.norm(blended(t)[1]) for t in inner) > 1e-4  # never at rest on the way
    with pytest.raises(bh.InputError, match="overlap"):
        PoseWaypoints(START, MOVES, overlap=0.6)


def test_the_thesis_pinch_follows_blended_waypoints_without_slipping(box_setup) -> None:
    run = run_path(box_setup, waypoints(WAYPOINTS["box"]))
    assert run.slip_events == 0 and run.cone_margin > 0.0 and run.success
    assert run.max_deviation < 0.5e-3 and run.max_rotation < 10e-3  # [m], [rad] from the path all along
