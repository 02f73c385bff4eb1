"""Reference generators against finite differences, closed-form boundary values and forward kinematics."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pinocchio as pin
import pytest

import bhgrasp as bh
from bhgrasp.motion.fingertip_reference import CartesianReference
from bhgrasp.motion.pose_references import PoseMotion, PosePath
from bhgrasp.motion.trajectories import (
    Constant,
    Quintic,
    Reference,
    Sinusoid,
    SmoothStep,
    exponential_approach,
    minimum_jerk,
)

STEP = 1e-5  # [s] central-difference step


def assert_derivatives(ref: Reference, times: list[float], atol: float = 1e-6) -> None:
    """Velocity = d/dt position and acceleration = d/dt velocity, by central differences."""
    for t in times:
        _, velocity, acceleration = ref(t)
        (p_plus, v_plus, _), (p_minus, v_minus, _) = ref(t + STEP), ref(t - STEP)
        scale_v, scale_a = 1.0 + np.abs(velocity).max(), 1.0 + np.abs(acceleration).max()
        np.testing.assert_allclose((p_plus - p_minus) / (2 * STEP), velocity, rtol=0, atol=atol * scale_v)
        np.testing.assert_allclose((v_plus - v_minus) / (2 * STEP), acceleration, rtol=0, atol=atol * scale_a)


# Kinks (delays, ends of quintics) at 0, 0.25, 0.3, 0.5, 0.7 and 1.0 s: no time below is within STEP of one.
TIMES = [-0.3, 0.13, 0.41, 0.66, 0.97, 1.5, 3.2]
GENERATORS: dict[str, Callable[[], Reference]] = {
    "smooth_step_delays": lambda: SmoothStep([0.1, -0.2, 0.5], [1.2, 0.4, 0.5], 0.3, delay=[0.0, 0.25, 0.5]),
    "smooth_step_time_constants": lambda: SmoothStep([0.0, 1.0, -1.0], 2.0, [0.2, 0.5, 1.0]),
    "exponential_approach": lambda: exponential_approach([0.0, 1.0], [2.0, -1.0], 3.0),
    "sinusoid": lambda: Sinusoid([0.1, 0.2, 0.3], [0.5, -0.2, 1.0], [0.5, 2.0, 1.3], phase=[0.0, 1.0, -2.0]),
    "sinusoid_broadcast": lambda: Sinusoid(0.2, [1.0, 2.0], 0.7),
    "quintic": lambda: Quintic([0.1, -0.3], [1.0, 0.6], duration=[1.0, 0.4], delay=[0.0, 0.3]),
    "constant": lambda: Constant([1.0, 2.0, 3.0]),
}


@pytest.mark.parametrize("name", GENERATORS)
def test_derivatives_match_finite_differences(name: str) -> None:
    ref = GENERATORS[name]()
    assert_derivatives(ref, TIMES)
    for array in ref(0.42):
        assert array.dtype == np.float64
        assert array.shape == (ref.size,)


def test_quintic_boundary_values_are_exact() -> None:
    start, goal = np.array([0.1, -0.3, 0.7]), np.array([1.0, 0.6, 0.7])
    ref = Quintic(start, goal, duration=0.8, delay=0.2)
    for t in (-1.0, 0.0, 0.2):
        position, velocity, acceleration = ref(t)
        np.testing.assert_array_equal(position, start)
        np.testing.assert_array_equal(velocity, 0.0)
        np.testing.assert_array_equal(acceleration, 0.0)
    for t in (1.0, 1.5, 100.0):
        position, velocity, acceleration = ref(t)
        np.testing.assert_array_equal(position, goal)
        np.testing.assert_array_equal(velocity, 0.0)
        np.testing.assert_array_equal(acceleration, 0.0)
    position, velocity, acceleration = ref(0.6)  # midpoint: half way, peak speed 1.875 d / T, no acceleration
    np.testing.assert_allclose(position, 0.5 * (start + goal), atol=1e-15)
    np.testing.assert_allclose(velocity, 1.875 * (goal - start) / 0.8, atol=1e-14)
    np.testing.assert_allclose(acceleration, 0.0, atol=1e-13)


def test_quintic_is_the_rest_to_rest_polynomial() -> None:
    """Independent solution: the quintic whose 6 coefficients satisfy the 6 boundary conditions."""
    start, goal, duration = 0.3, -1.1, 1.7
    powers = np.arange(6)
    rows = []
    for t in (0.0, duration):
        rows.append(t**powers)
        rows.append(np.r_[0.0, powers[1:] * t ** (powers[1:] - 1)])
        rows.append(np.r_[0.0, 0.0, powers[2:] * (powers[2:] - 1) * t ** (powers[2:] - 2)])
    coefficients = np.linalg.solve(np.array(rows), [start, 0.0, 0.0, goal, 0.0, 0.0])
    polynomial = np.polynomial.Polynomial(coefficients)
    ref = Quintic(start, goal, duration)
    for t in np.linspace(0.0, duration, 9):
        position, velocity, acceleration = ref(t)
        assert position[0] == pytest.approx(polynomial(t), abs=1e-12)
        assert velocity[0] == pytest.approx(polynomial.deriv()(t), abs=1e-12)
        assert acceleration[0] == pytest.approx(polynomial.deriv(2)(t), abs=1e-11)


def test_minimum_jerk_gives_the_same_bits_for_floats_and_arrays() -> None:
    """The profile is products only: one float at a time equals the vectorised call, bit for bit."""
    s = np.concatenate(([0.0, 0.5, 1.0], np.random.default_rng(3).uniform(0.0, 1.0, 2000)))
    vectorised = minimum_jerk(s)
    for k, value in enumerate(s.tolist()):
        assert minimum_jerk(value) == tuple(float(part[k]) for part in vectorised)
    assert minimum_jerk(0.0) == (0.0, 0.0, 0.0)
    assert minimum_jerk(1.0) == (1.0, 0.0, 0.0)


def test_pose_motion_turns_about_a_fixed_world_axis_with_the_quintic_blend() -> None:
    """x = x_0 + b dx, R = exp(b dtheta) R_0; the twist is d/dt of the pose (finite differences); b as Quintic's."""
    start = pin.SE3(pin.exp3(np.array([0.3, -0.2, 0.5])), np.array([0.1, 0.0, 0.2]))
    offset = np.array([0.0, 0.004, 0.01, 0.1, -0.05, 0.2])
    ref, blend = PoseMotion(start, offset, 0.8, delay=0.3), Quintic(0.0, 1.0, 0.8, delay=0.3)
    for t in np.linspace(0.0, 1.5, 301):
        sample, twist, derivative = ref(t)
        b, rate, curvature = (float(part[0]) for part in blend(t))
        np.testing.assert_array_equal(sample[:3], start.translation + b * offset[:3])
        np.testing.assert_array_equal(twist, rate * offset)
        np.testing.assert_array_equal(derivative, curvature * offset)
        np.testing.assert_allclose(pin.exp3(sample[3:]), pin.exp3(b * offset[3:]) @ start.rotation, atol=1e-15)
    for t in (0.47, 0.7, 0.93):  # away from the kinks at 0.3 and 1.1 s
        (x_plus, v_plus, _), (x_minus, v_minus, _) = ref(t + STEP), ref(t - STEP)
        _, twist, derivative = ref(t)
        rotation_rate = (pin.exp3(x_plus[3:]) - pin.exp3(x_minus[3:])) / (2 * STEP)
        omega = pin.unSkew(rotation_rate @ pin.exp3(ref(t)[0][3:]).T)
        np.testing.assert_allclose((x_plus[:3] - x_minus[:3]) / (2 * STEP), twist[:3], atol=1e-9)
        np.testing.assert_allclose(omega, twist[3:], atol=1e-8)
        np.testing.assert_allclose((v_plus - v_minus) / (2 * STEP), derivative, atol=1e-7)
    np.testing.assert_allclose(pin.exp3(ref(5.0)[0][3:]), pin.exp3(offset[3:]) @ start.rotation, atol=1e-15)


def test_pose_path_moves_back_to_back_and_composes_rotations_about_world_axes() -> None:
    """Waypoints are the cumulative offsets (R_k = exp(dtheta_k) R_k-1), reached at rest at each join; between
    joins the twist is d/dt of the pose (finite differences); a zero offset holds the pose."""
    start = pin.SE3(pin.exp3(np.array([0.1, 0.2, -0.3])), np.array([0.0, 0.1, 0.3]))
    moves = [
        ([0.0, 0.0, -0.05, 0.0, 0.0, 0.0], 1.0),
        ([0.0] * 6, 0.5),
        ([0.02, 0.0, 0.1, 0.0, 0.3, 0.0], 0.8),
        ([0.0, 0.0, 0.0, 0.2, 0.0, 0.0], 0.6),
    ]
    path = PosePath(start, moves, delay=0.2)
    pose, t = pin.SE3(start), 0.2
    for offset, duration in moves:
        offset = np.array(offset)
        sample, twist, derivative = path(t)  # the join: the pose reached, at rest
        np.testing.assert_allclose(sample[:3], pose.translation, atol=1e-15)
        np.testing.assert_allclose(pin.exp3(sample[3:]), pose.rotation, atol=1e-14)
        assert not twist.any() and not derivative.any()
        pose = pin.SE3(pin.exp3(offset[3:]) @ pose.rotation, pose.translation + offset[:3])
        t += duration
    assert path.end_time == pytest.approx(t)
    np.testing.assert_allclose(pin.exp3(path(10.0)[0][3:]), pose.rotation, atol=1e-14)
    for t in (0.55, 1.45, 1.9, 2.3, 2.8, 3.05):  # inside moves: v, omega, and their rates by finite differences
        (x_plus, v_plus, _), (x_minus, v_minus, _) = path(t + STEP), path(t - STEP)
        sample, twist, derivative = path(t)
        rotation_rate = (pin.exp3(x_plus[3:]) - pin.exp3(x_minus[3:])) / (2 * STEP)
        np.testing.assert_allclose((x_plus[:3] - x_minus[:3]) / (2 * STEP), twist[:3], atol=1e-9)
        np.testing.assert_allclose(pin.unSkew(rotation_rate @ pin.exp3(sample[3:]).T), twist[3:], atol=1e-8)
        np.testing.assert_allclose((v_plus - v_minus) / (2 * STEP), derivative, atol=1e-6)
    (hold_start, *_), (hold_end, *_) = path(1.25), path(1.65)
    np.testing.assert_array_equal(hold_start, hold_end)  # the pause
    with pytest.raises(bh.InputError, match="`moves` must hold at least one"):
        PosePath(start, [])
    with pytest.raises(bh.InputError, match=r"`moves\[0\]` must be an \(offset"):
        PosePath(start, [([0.0] * 6,)])


def test_smooth_step_follows_thesis_5_36_with_per_component_delays() -> None:
    start, goal, a = np.array([0.0, 0.2, 1.0]), np.array([1.5, 1.0, -0.5]), 0.25
    delays = np.array([0.0, 0.5, 1.0])  # e.g. the spread first, the fingers later
    ref = SmoothStep(start, goal, a, delay=delays)
    np.testing.assert_array_equal(ref(-1.0)[0], start)
    np.testing.assert_array_equal(ref(0.0)[0], start)
    position, velocity, _ = ref(0.7)  # components 0, 1 moving, component 2 still waiting
    expected = start + (goal - start) * (1.0 - np.exp(-(0.7 - delays) / a))
    np.testing.assert_allclose(position[:2], expected[:2], atol=1e-15)
    assert position[2] == start[2]
    assert velocity[2] == 0.0
    for i, delay in enumerate(delays):  # each component starts exactly at its own delay...
        assert ref(delay - 1e-9)[1][i] == 0.0
        assert ref(delay)[0][i] == start[i]
        # ... with the thesis' velocity jump to (goal - start) / a
        assert ref(delay)[1][i] == pytest.approx((goal[i] - start[i]) / a, rel=1e-12)
        assert ref(delay + 20 * a)[0][i] == pytest.approx(goal[i], abs=1e-6)
    np.testing.assert_allclose(ref(1.0 + 20 * a)[0], goal, atol=1e-6)


def test_exponential_approach_is_thesis_4_29() -> None:
    x_i, x_f, rate = np.array([0.05, -0.02, 0.1]), np.array([0.0, 0.03, 0.12]), 4.0
    ref = exponential_approach(x_i, x_f, rate)
    assert isinstance(ref, SmoothStep)
    for t in (0.0, 0.1, 0.5, 2.0):
        expected = x_i * np.exp(-rate * t) + x_f * (1.0 - np.exp(-rate * t))
        np.testing.assert_allclose(ref(t)[0], expected, atol=1e-15)
        np.testing.assert_allclose(ref(t)[1], rate * (x_f - x_i) * np.exp(-rate * t), atol=1e-14)


def test_sinusoid_formula_broadcast_and_period() -> None:
    ref = Sinusoid([0.1, 0.2, 0.3], 0.5, 2.0, phase=[0.0, np.pi / 2, np.pi])
    assert ref.size == 3
    np.testing.assert_allclose(ref(0.0)[0], [0.1, 0.7, 0.3], atol=1e-15)
    t = 0.123
    np.testing.assert_allclose(ref(t)[0], ref(t + 0.5)[0], atol=1e-14)  # 2 Hz: period 0.5 s
    np.testing.assert_allclose(ref(t)[0], [0.1, 0.2, 0.3] + 0.5 * np.sin(4 * np.pi * t + ref.phase), atol=1e-15)
    assert Sinusoid(1.0, 2.0, 3.0).size == 1


def test_constant_returns_fresh_copies() -> None:
    ref = Constant([1.0, 2.0])
    position, velocity, acceleration = ref(5.0)
    position[0] = 99.0
    np.testing.assert_array_equal(ref(0.0)[0], [1.0, 2.0])
    np.testing.assert_array_equal(velocity, 0.0)
    np.testing.assert_array_equal(acceleration, 0.0)
    assert Constant(0.5).size == 1


# ---------------------------------------------------------------------- Cartesian -> joint references
def tip(hand: bh.Hand, finger: str, q: np.ndarray) -> np.ndarray:
    return hand.fingertip_positions(q)[hand.fingers.index(finger)]


def check_cartesian(hand: bh.Hand, finger: str, cartesian: Reference, q_rest: np.ndarray, times: np.ndarray) -> None:
    ref = CartesianReference(hand, finger, cartesian, q_rest)
    assert ref.size == hand.nv
    others = np.setdiff1d(np.arange(hand.nv), hand.finger_indices(finger))
    for t in times:
        q, v, a = ref(t)
        x, xdot, _ = cartesian(t)
        np.testing.assert_allclose(tip(hand, finger, q), x, rtol=0, atol=1e-9)
        np.testing.assert_allclose(hand.fingertip_jacobian(q, finger) @ v, xdot, rtol=0, atol=1e-9)
        np.testing.assert_array_equal(q[others], q_rest[others])
        np.testing.assert_array_equal(v[others], 0.0)
        np.testing.assert_array_equal(a[others], 0.0)
        assert hand.within_limits(q)
    assert_derivatives(ref, list(times), atol=1e-5)


def line(hand: bh.Hand, finger: str, q_a: np.ndarray, q_b: np.ndarray) -> Quintic:
    """Minimum-jerk straight line between the fingertip positions of two configurations [m]."""
    return Quintic(tip(hand, finger, q_a), tip(hand, finger, q_b), duration=1.0, delay=0.1)


def circle(center: np.ndarray, e1: np.ndarray, e2: np.ndarray, radius: float, frequency: float) -> Sinusoid:
    """``center + radius (e1 sin(w t) + e2 cos(w t))`` written as one sinusoid per component."""
    return Sinusoid(center, radius * np.hypot(e1, e2), frequency, phase=np.arctan2(e2, e1))


TIMES_CARTESIAN = np.array([0.0, 0.23, 0.5, 0.61, 0.87, 1.05, 1.4])


def test_cartesian_line_f1(barrett: bh.Hand) -> None:
    q_a = barrett.configuration(F1_spread=0.3, F1_proximal=0.6, F1_distal=0.3, F2_proximal=0.4, F3_distal=0.2)
    q_b = barrett.configuration(F1_spread=0.6, F1_proximal=1.0, F1_distal=0.5, F2_proximal=0.4, F3_distal=0.2)
    check_cartesian(barrett, "F1", line(barrett, "F1", q_a, q_b), q_a, TIMES_CARTESIAN)
    ref = CartesianReference(barrett, "F1", line(barrett, "F1", q_a, q_b), q_a)
    np.testing.assert_allclose(ref(0.0)[0], q_a, atol=1e-9)  # the IK branch of the start configuration...
    np.testing.assert_allclose(ref(2.0)[0], q_b, atol=1e-9)  # ... followed continuously to the goal's


def test_cartesian_circle_f1(barrett: bh.Hand) -> None:
    """A curved path: the acceleration's Jdot qdot term is large."""
    q_rest = barrett.configuration(F1_spread=0.45, F1_proximal=0.8, F1_distal=0.4)
    center = tip(barrett, "F1", q_rest)
    e1, e2 = np.array([1.0, 0.0, 0.0]), np.array([0.0, 0.6, 0.8])
    check_cartesian(barrett, "F1", circle(center, e1, e2, 0.01, 0.8), q_rest, TIMES_CARTESIAN)


def test_cartesian_f1_on_a_placed_hand() -> None:
    placement = pin.SE3(pin.rpy.rpyToMatrix(0.5, 0.2, -1.0), np.array([0.3, 0.1, -0.2]))
    hand = bh.BarrettHand(base_placement=placement)
    q_rest = hand.configuration(F1_spread=0.45, F1_proximal=0.8, F1_distal=0.4)
    center = tip(hand, "F1", q_rest)
    e1, e2 = np.array([0.0, 0.0, 1.0]), np.array([0.8, -0.6, 0.0])
    check_cartesian(hand, "F1", circle(center, e1, e2, 0.01, 0.8), q_rest, TIMES_CARTESIAN)


def test_cartesian_line_f3_two_joints(barrett: bh.Hand) -> None:
    q_a = barrett.configuration(F3_proximal=0.6, F3_distal=0.3, F1_spread=0.5, F1_proximal=0.7)
    q_b = barrett.configuration(F3_proximal=1.0, F3_distal=0.5, F1_spread=0.5, F1_proximal=0.7)
    check_cartesian(barrett, "F3", line(barrett, "F3", q_a, q_b), q_a, TIMES_CARTESIAN)


def test_cartesian_circle_f3_in_its_plane(barrett: bh.Hand) -> None:
    pairs = [(0.9, 0.5), (1.1, 0.5), (0.9, 0.6)]  # (proximal, distal) [rad]: three points spanning the plane
    configurations = [barrett.configuration(F3_proximal=p, F3_distal=d) for p, d in pairs]
    points = [tip(barrett, "F3", q) for q in configurations]
    e1 = (points[1] - points[0]) / np.linalg.norm(points[1] - points[0])
    e2 = points[2] - points[0] - (points[2] - points[0]) @ e1 * e1
    e2 /= np.linalg.norm(e2)
    check_cartesian(barrett, "F3", circle(points[0], e1, e2, 0.005, 0.8), configurations[0], TIMES_CARTESIAN)


def test_cartesian_f3_out_of_its_plane_raises(barrett: bh.Hand) -> None:
    q = barrett.configuration(F3_proximal=0.8, F3_distal=0.4)
    off_plane = Constant(tip(barrett, "F3", q) + np.array([0.004, 0.0, 0.0]))  # F3 moves in the x = 0 plane
    with pytest.raises(bh.UnreachableError, match="out of finger 'F3'"):
        CartesianReference(barrett, "F3", off_plane, q)(0.0)


def test_cartesian_reset_restores_the_first_seed(barrett: bh.Hand) -> None:
    q_rest = barrett.configuration(F1_spread=0.45, F1_proximal=0.8, F1_distal=0.4)
    ref = CartesianReference(barrett, "F1", Constant(tip(barrett, "F1", q_rest)), q_rest)
    first = ref(0.0)[0]
    ref.reset()
    np.testing.assert_array_equal(ref(0.0)[0], first)
    np.testing.assert_allclose(first, q_rest, atol=1e-9)


# ---------------------------------------------------------------------- errors
@pytest.mark.parametrize(
    ("build", "match"),
    [
        (lambda: SmoothStep([0.0, 1.0], [0.0, 1.0, 2.0], 1.0), "same shape"),
        (lambda: SmoothStep([0.0, 1.0], [0.0, 1.0], 1.0, delay=[0.0, 1.0, 2.0]), "same shape"),
        (lambda: SmoothStep([0.0, np.nan], [0.0, 1.0], 1.0), "`start` must be finite"),
        (lambda: SmoothStep(0.0, 1.0, 0.0), "`time_constant` must be > 0"),
        (lambda: SmoothStep([0.0, 0.0], 1.0, [1.0, -1.0]), "`time_constant` must be > 0"),
        (lambda: SmoothStep(0.0, 1.0, 1.0, delay=-0.1), "`delay` must be >= 0"),
        (lambda: exponential_approach(0.0, 1.0, 0.0), "`rate` must be > 0"),
        (lambda: Sinusoid(0.0, 1.0, -1.0), "`frequency` must be >= 0"),
        (lambda: Sinusoid([[0.0, 1.0]], 1.0, 1.0), "`offset` must have shape"),
        (lambda: Quintic(0.0, 1.0, 0.0), "`duration` must be > 0"),
        (lambda: Quintic(0.0, 1.0, np.inf), "`duration` must be a finite number"),
        (lambda: Quintic([0.0], [1.0], 1.0, delay=[-1.0]), "`delay` must be >= 0"),
        (lambda: Constant([]), "at least one component"),
        (lambda: Constant("abc"), "`value` must be a finite number"),
    ],
)
def test_invalid_arguments_raise(build: Callable[[], Reference], match: str) -> None:
    with pytest.raises(bh.InputError, match=match):
        build()


@pytest.mark.parametrize("name", GENERATORS)
@pytest.mark.parametrize("t", [np.nan, np.inf, -np.inf, "soon"])
def test_non_finite_time_raises(name: str, t: object) -> None:
    with pytest.raises(bh.InputError, match="`t` must be a finite number"):
        GENERATORS[name]()(t)


def test_cartesian_reference_arguments(barrett: bh.Hand) -> None:
    q = barrett.configuration(F1_spread=0.45, F1_proximal=0.8, F1_distal=0.4)
    point = Constant(tip(barrett, "F1", q))
    with pytest.raises(bh.InputError, match="size 3.*got size 2"):
        CartesianReference(barrett, "F1", Constant([0.0, 0.1]), q)
    with pytest.raises(bh.InputError, match="`reference` must be a Reference"):
        CartesianReference(barrett, "F1", lambda t: (q, q, q), q)
    with pytest.raises(bh.InputError, match="unknown finger 'F4'"):
        CartesianReference(barrett, "F4", point, q)
    with pytest.raises(bh.InputError, match=r"`q_rest` must have shape \(8,\)"):
        CartesianReference(barrett, "F1", point, q[:3])
    with pytest.raises(bh.InputError, match="`plane_tolerance`"):
        CartesianReference(barrett, "F1", point, q, plane_tolerance=0.0)
    with pytest.raises(bh.InputError, match="`hand` must be a bhgrasp Hand"):
        CartesianReference("barrett", "F1", point, q)
    with pytest.raises(bh.InputError, match="`t` must be a finite number"):
        CartesianReference(barrett, "F1", point, q)(np.nan)


def test_repr_names_the_class_and_size() -> None:
    assert repr(Quintic([0.0, 1.0], 2.0, 1.0)) == "Quintic(size=2)"


def test_a_smooth_steps_table_is_its_samples_to_the_bit() -> None:
    """Per-component delays (some times before them, one at a delay), every row as ``__call__`` gives it."""
    rng = np.random.default_rng(4)
    start, goal = rng.normal(size=7), rng.normal(size=7)
    goal[2] = start[2]  # a component that does not move (its acceleration -0.0)
    step = SmoothStep(start, goal, rng.uniform(0.05, 0.3, 7), rng.uniform(0.0, 0.2, 7))
    times = np.concatenate((np.arange(0, 1500) * 1e-3, step.delay[:1]))
    table = step.table(times)
    assert table.shape == (len(times), 21)
    for row, t in zip(table, times):
        assert row.tobytes() == np.concatenate(step(float(t))).tobytes(), t
    with pytest.raises(bh.InputError, match="times"):
        step.table([0.1, np.nan])
