"""Impedance control of thesis chapter 4 against independent truths: scipy's bilinear discretisation, the analytic
second-order response, RNEA with external forces, the Lyapunov function of the estimator, and force tracking on
the simulator's contacts."""

from __future__ import annotations

import functools
from fractions import Fraction

import numpy as np
import pytest
from scipy.signal import cont2discrete, lfilter

import bhgrasp as bh
from bhgrasp.controllers.adaptive_impedance import AdaptiveForceImpedance
from bhgrasp.controllers.impedance import (
    ForceImpedance,
    PositionImpedance,
)
from bhgrasp.controllers.impedance_controller import ImpedanceController
from bhgrasp.controllers.impedance_filter import ImpedanceFilter, TustinImpedanceFilter, critical_damping
from bhgrasp.grasp.sensing import ContactSensing, FingerContact
from bhgrasp.motion.trajectories import Constant, SmoothStep
from bhgrasp.scenarios import finger_press, press_fitness
from bhgrasp.thesis import chapter4, chapter4_closed_form, chapter4_tuning


@pytest.mark.parametrize(
    ("mass", "damping", "stiffness", "period"),
    [(0.5, 3.0, 40.0, 1e-3), (8.9, 167.0, 560.0, 2e-3), (0.005, 0.3, 4.76, 1e-3)],
)
def test_tustin_filter_matches_scipy_bilinear(mass, damping, stiffness, period):
    tustin = TustinImpedanceFilter(mass, damping, stiffness, period, size=1)
    num, den, _ = cont2discrete(([1.0], [mass, damping, stiffness]), period, method="bilinear")
    numerator, denominator = tustin.coefficients()
    np.testing.assert_allclose(numerator, num.ravel() / den[0], rtol=0, atol=1e-12)
    np.testing.assert_allclose(denominator, den / den[0], rtol=0, atol=1e-12)
    # scipy rounds (relative 1e-10 on the numerator); the closed form (4.47) agrees with exact rational arithmetic
    m, b, k, t = (Fraction(value) for value in (mass, damping, stiffness, period))
    w1, w2, w3 = 4 * m + 2 * b * t + k * t * t, 2 * k * t * t - 8 * m, 4 * m + k * t * t - 2 * b * t
    exact_num = [float(t * t / w1), float(2 * t * t / w1), float(t * t / w1)]
    np.testing.assert_allclose(numerator, exact_num, rtol=1e-15)
    np.testing.assert_allclose(denominator, [1.0, float(w2 / w1), float(w3 / w1)], rtol=1e-15)
    forces = np.random.default_rng(1).normal(size=400)
    expected = lfilter(num.ravel(), den, forces)
    produced = np.array([tustin.step([f], period)[0][0] for f in forces])
    np.testing.assert_allclose(produced, expected, rtol=0, atol=1e-12 * max(1.0, np.abs(expected).max()))


def test_tustin_filter_uses_changed_parameters_from_the_next_sample():
    """The filter caches its coefficients; a changed M_I, B_I, K_I or T takes effect as if they were recomputed."""
    tustin = TustinImpedanceFilter(0.5, 3.0, 40.0, 1e-3, size=1)
    forces = np.random.default_rng(2).normal(size=40)
    history = [0.0, 0.0, 0.0, 0.0]  # E(n-1), E(n-2) and F(n-1), F(n-2)
    for n, force in enumerate(forces):
        if n == 20:
            tustin.stiffness, tustin.damping = 80.0, 5.0
        numerator, denominator = tustin.coefficients()
        expected = (
            numerator[0] * force
            + numerator[1] * history[2]
            + numerator[2] * history[3]
            - denominator[1] * history[0]
            - denominator[2] * history[1]
        )
        assert tustin.step([force], 1e-3)[0][0] == expected
        history = [expected, history[0], force, history[2]]


def test_continuous_filter_follows_the_second_order_step_response():
    """M x'' + B x' + K x = F from rest: x(t) = F/K (1 - e^{-z w t}(cos w_d t + z/sqrt(1-z^2) sin w_d t))."""
    m, b, k, force, dt = 0.5, 3.0, 40.0, 2.0, 1e-4
    wn, zeta = np.sqrt(k / m), b / (2 * np.sqrt(k * m))
    wd = wn * np.sqrt(1 - zeta**2)
    filt = ImpedanceFilter(m, b, k, size=1)
    times = np.arange(1, 20001) * dt
    produced = np.array([filt.step([force], dt)[0][0] for _ in times])
    exact = (
        force
        / k
        * (1 - np.exp(-zeta * wn * times) * (np.cos(wd * times) + zeta / np.sqrt(1 - zeta**2) * np.sin(wd * times)))
    )
    assert np.max(np.abs(produced - exact)) < 2e-3 * force / k  # implicit Euler, first order in dt
    for _ in range(10):
        final = filt.step([force], 1.0)[0][0]  # implicit Euler is stable for any step, and converges to F / K
    assert final == pytest.approx(force / k, rel=1e-6)


def test_critical_damping_and_filter_validation():
    assert critical_damping(2.0, 50.0) == pytest.approx(2 * np.sqrt(100.0))
    assert critical_damping(2.0, 50.0, environment_stiffness=150.0) == pytest.approx(2 * np.sqrt(400.0))
    for args in ((-1.0, 1.0, 1.0), (1.0, -1.0, 1.0), (1.0, 1.0, 0.0), (np.nan, 1.0, 1.0)):
        with pytest.raises(bh.InputError):
            ImpedanceFilter(*args)
    tustin = TustinImpedanceFilter(1.0, 1.0, 1.0, 1e-3)
    with pytest.raises(bh.InputError, match="period"):
        tustin.step(np.zeros(3), 2e-3)
    with pytest.raises(bh.InputError, match="force"):
        ImpedanceFilter(1.0, 1.0, 1.0).step([np.nan, 0.0, 0.0], 1e-3)


def test_reaction_torques_equal_rnea_with_external_forces(barrett):
    """J_p^T F of sensed contacts equals the torque difference RNEA computes for the same forces as f_ext."""
    rng = np.random.default_rng(2)
    q = barrett.configuration(F1_spread=0.4, F1_proximal=0.7, F1_distal=0.3, F3_proximal=0.8, F3_distal=0.4)
    links = ("F1_distal_link", "F3_distal_link", "F3_proximal_link")
    points = np.array([barrett.frame_placement(q, link).translation + 0.01 * rng.normal(size=3) for link in links])
    forces = rng.normal(size=(3, 3))  # on the object
    state = bh.State(
        0.0,
        q,
        np.zeros(8),
        contact_points=points,
        contact_normals=np.tile([0, 0, 1.0], (3, 1)),
        contact_forces=forces,
        contact_bodies=tuple((link, "object") for link in links),
    )
    sensed = ContactSensing(barrett).reaction_torques(state)
    wrenches = {}
    for link, point, force in zip(links, points, forces):
        origin = barrett.frame_placement(q, link).translation
        wrenches[link] = np.concatenate((-force, np.cross(point - origin, -force)))  # on the hand, about origin
    zero = np.zeros(8)
    f_ext = barrett.external_forces(q, wrenches)
    expected = barrett.inverse_dynamics(q, zero, zero) - barrett.inverse_dynamics(q, zero, zero, f_ext)
    np.testing.assert_allclose(sensed, expected, atol=1e-12)
    per_finger = ContactSensing(barrett).fingers(state)
    np.testing.assert_allclose(per_finger["F3"].force, forces[1] + forces[2])
    assert per_finger["F2"].count == 0 and not per_finger["F2"].touching


def synthetic_contact(force_along_normal: float, normal: np.ndarray) -> FingerContact:
    return FingerContact(force_along_normal * normal, force_along_normal, normal, 1)


def test_gradient_estimator_lyapunov_function_never_grows():
    """theta = (k_e, k_e (x_e - c)): V = theta~^T Gamma^-1 theta~ / 2 is non-increasing and f_hat -> f.

    (The discrete gradient step contracts V while dt phi^T Gamma phi < 2, here about 0.54.)  The theory promises
    no parameter convergence without persistent excitation, and the test asks for none: that is why the
    least-squares estimator is the default.
    """
    normal = np.array([0.0, 0.0, 1.0])
    k_e, x_e = 2000.0, 0.03
    law = AdaptiveForceImpedance(
        Constant(np.zeros(3)),
        normal,
        5.0,
        np.array([0, 0, 0.02]),
        1000.0,
        gamma=(200.0, 0.5),
        estimator="gradient",
        quasi_static_speed=10.0,
    )
    true = np.array([k_e, k_e * (x_e - law._centre)])
    values, errors = [], []
    for k, t in enumerate(np.arange(0, 6.0, 1e-3)):
        x = np.array([0.0, 0.0, x_e + 0.004 + 0.003 * np.sin(3 * t)])  # pressing, varying depth
        force = k_e * (x[2] - x_e)
        law.command(t, x, synthetic_contact(force, normal), 1e-3 if k else 0.0)
        values.append(0.5 * np.sum((law.theta - true) ** 2 / law.gamma))
        errors.append(law.log["force_estimate"] - force)
    values = np.array(values)
    assert np.all(np.diff(values[1:]) <= 1e-12 * values[1]) and values[-1] < values[1]
    assert abs(errors[0]) > 1.0 and np.max(np.abs(errors[-1000:])) < 0.01 * k_e * 0.004


def test_least_squares_estimator_identifies_the_environment_from_two_force_levels():
    normal = np.array([0.0, 0.6, 0.8])  # any 3-D direction
    k_e, x_e = 3.0e4, 0.05
    law = AdaptiveForceImpedance(Constant(np.zeros(3)), normal, 5.0, 0.5 * x_e * normal, 0.5 * k_e)
    for k, depth in enumerate([1e-4] * 50 + [3e-4] * 50):
        x = (x_e + depth) * normal
        law.command(0.001 * k, x, synthetic_contact(k_e * depth, normal), 1e-3 if k else 0.0)
    # exact up to the (weak) prior: 2e-4 m of depth variation carries little information about k_e
    assert law.environment_stiffness == pytest.approx(k_e, rel=1e-4)
    assert law.surface == pytest.approx(x_e, abs=1e-8)


def planar_fim(setup) -> ForceImpedance:
    """FIM on the planar finger pressing 10 N, known environment, the impedance M 8.9, B 167, K 560."""
    return ForceImpedance(
        Constant(setup.tip0),
        setup.normal,
        10.0,
        setup.surface_point(),
        setup.k_e,
        mass=8.9,
        damping=167.0,
        stiffness=560.0,
    )


def test_fim_tracks_the_force_with_known_environment_on_the_planar_finger():
    setup = finger_press.planar_setup(1000.0)
    law = planar_fim(setup)
    traj = finger_press.run(setup, ImpedanceController(setup.hand, {"tip": law}, *finger_press.PLANAR_GAINS), 3.0)
    force = finger_press.normal_force(setup, traj)
    assert abs(np.mean(force[-200:]) - 10.0) < 0.02 * 10.0


@pytest.fixture(scope="module")
def f3_setups():
    return {spring: finger_press.f3_setup(spring) for spring in (1e3, 1e4, 5e4)}


@pytest.mark.parametrize("spring", [1e3, 1e4, 5e4])
def test_adaptive_fim_on_f3_finds_the_environment_and_tracks_the_force(f3_setups, spring):
    """Estimates start at half k_e and 1 cm short of the surface; FIM with the true values is the reference."""
    setup = f3_setups[spring]
    still = Constant(setup.tip0)
    known = ForceImpedance(still, setup.normal, 10.0, setup.surface_point(), setup.k_e, **finger_press.F3_IMPEDANCE)
    traj = finger_press.run(setup, ImpedanceController(setup.hand, {"F3": known}, *finger_press.F3_GAINS), 2.0)
    assert abs(np.mean(finger_press.normal_force(setup, traj)[-100:]) - 10.0) < 0.2  # < 2 %
    profile = SmoothStep([5.0], [10.0], 0.3, delay=2.0)
    adaptive = AdaptiveForceImpedance(
        still,
        setup.normal,
        profile,
        setup.surface_point() - 0.01 * setup.normal,
        0.5 * setup.k_e,
        **finger_press.F3_IMPEDANCE,
    )
    traj = finger_press.run(setup, ImpedanceController(setup.hand, {"F3": adaptive}, *finger_press.F3_GAINS), 4.5)
    force = finger_press.normal_force(setup, traj)
    assert abs(np.mean(force[-100:]) - 10.0) < 0.2
    assert traj.log["F3/stiffness_estimate"][-1] == pytest.approx(setup.k_e, rel=0.05)
    assert abs(traj.log["F3/surface_estimate"][-1] - setup.surface) < 0.05 * 10.0 / setup.k_e + 1e-5
    assert np.max(np.abs(traj.v)) < 5.0  # stable: no joint speed blow-up


def test_steady_force_solves_the_static_balance_of_filter_environment_and_inner_loop():
    """The closed form against a direct solve of the four linear rest equations in (x, x_c, dx, f)."""
    f_d, k_e, x_e, k_i, k_p, delta = 10.0, 9901.0, 0.035, 100.0, 11.8, -0.02
    for k_hat, feedforward in ((k_e, False), (0.5 * k_e, False), (k_e, True), (3.0 * k_e, True)):
        x_hat = x_e + 1e-3  # any estimate consistent at the operating point: k^ (x - x^) = f there
        f_ff = f_d if feedforward else 0.0
        # x_c = x_d - dx;  k_i dx = f - f_d;  x = x_c - (f - f_ff)/k_p - delta;  f = k^ (x - x^)  (x_d = x^ + f_d/k^)
        a = np.array([[0.0, 1.0, 1.0, 0.0], [0.0, 0.0, k_i, -1.0], [1.0, -1.0, 0.0, 1.0 / k_p], [-k_hat, 0, 0, 1.0]])
        b = np.array([x_hat + f_d / k_hat, -f_d, f_ff / k_p - delta, -k_hat * x_hat])
        *_, f = np.linalg.solve(a, b)
        assert chapter4.steady_force(f_d, k_i, k_p, k_hat, feedforward, delta) == pytest.approx(f, rel=1e-12)
    assert chapter4.steady_force(f_d, k_i, 1e12, k_e) == pytest.approx(f_d, rel=1e-9)  # X = X_c: (4.25) = 0
    assert chapter4.steady_force(f_d, k_i, 1.0, k_e, feedforward=True) == pytest.approx(f_d, rel=1e-12)


@pytest.mark.parametrize("friction", [0.0, 0.5])
def test_printed_fim_settles_where_the_closed_form_says_and_the_feedforward_at_f_d(friction):
    """Planar finger, k_e = 999 N/m, K_I = 560 N/m: the thesis' law without J^T f_d n settles near 2.2 N for 10 N.

    On a frictionless face the closed form needs nothing from the run but the final pose's effective mass; with
    friction it adds the deflection of the measured tangential force.
    """
    setup = finger_press.planar_setup(1000.0, friction=friction)
    finals = {}
    for feedforward in (False, True):
        law = planar_fim(setup)
        if not feedforward:
            chapter4.as_printed(law)
        controller = ImpedanceController(setup.hand, {"tip": law}, *finger_press.PLANAR_GAINS, feedforward=feedforward)
        traj = finger_press.run(setup, controller, 4.0)
        force = finger_press.normal_force(setup, traj)
        assert np.ptp(force[-500:]) < 1e-3  # at rest
        final = float(np.mean(force[-200:]))
        inner, frictionless, measured = chapter4_closed_form.closed_form_force(
            setup, traj, force, law, 80.0, feedforward
        )
        assert inner == pytest.approx(chapter4.inner_loop_stiffness(setup, traj.q[-1], 80.0))
        assert 80.0 < inner < 120.0  # Kp x ~1.25 kg
        assert final == pytest.approx(measured, rel=1e-4)
        if friction == 0.0:
            assert final == pytest.approx(frictionless, rel=1e-4)
        finals[feedforward] = final
    assert finals[True] == pytest.approx(10.0, abs=0.02 if friction else 1e-4)
    assert 2.0 < finals[False] < 2.6


def test_printed_fim_on_f3_misses_f_d_as_the_closed_form_with_friction_predicts(f3_setups):
    setup = f3_setups[1e4]
    law = chapter4.as_printed(
        ForceImpedance(
            Constant(setup.tip0), setup.normal, 10.0, setup.surface_point(), setup.k_e, **finger_press.F3_IMPEDANCE
        )
    )
    controller = ImpedanceController(setup.hand, {"F3": law}, *finger_press.F3_GAINS, feedforward=False)
    traj = finger_press.run(setup, controller, 3.0)
    force = finger_press.normal_force(setup, traj)
    inner, frictionless, measured = chapter4_closed_form.closed_form_force(
        setup, traj, force, law, finger_press.F3_GAINS[0], False
    )
    final = float(np.mean(force[-150:]))
    assert 1.4 < final < 2.0  # 10 N asked
    assert final == pytest.approx(measured, rel=0.01)
    assert 10.0 < inner < 14.0 and frictionless < final  # k_p = 430 x ~0.027 kg; friction holds the tip deeper


def test_pim_lowers_peak_and_steady_force_against_the_uncontrolled_push():
    case = chapter4.f3_push(1.0)
    rows = {row[0]: row for row in case.table}
    for spring in finger_press.STIFFNESSES:
        plain, pim = rows[f"uncontrolled, K_s = {spring:g}"], rows[f"PIM, K_s = {spring:g}"]
        assert float(pim[3]) < float(plain[3])  # push peak (after the impact window)
        assert float(pim[4]) < float(plain[4])  # steady force


def test_three_fingers_track_their_desired_forces():
    case = chapter4.three_fingers(1.0)
    for finger in ("F1", "F2", "F3"):
        _, force, desired = case.traces[finger]
        assert abs(np.mean(force[-100:]) - desired) < 0.02 * desired


def test_tuning_plan_scales_runs_and_evaluations_but_never_skips():
    runs, cap = chapter4.tuning_plan(1.0)
    assert len(runs) == len(chapter4_tuning.TUNING_STARTS) * len(chapter4_tuning.TUNING_SEEDS) and cap == 600
    assert len(set(runs)) == len(runs)
    for scale in (0.01, 0.2, 0.5):
        fewer, smaller = chapter4.tuning_plan(scale)
        assert 1 <= len(fewer) <= len(runs) and fewer == runs[: len(fewer)] and 12 <= smaller <= cap
    assert chapter4.tuning_plan(0.2) == (runs[:1], 24)
    for start in chapter4_tuning.TUNING_STARTS:  # starts inside the bounds, or clipped onto them
        assert np.all(np.asarray(start) > chapter4_tuning.TUNING_BOUNDS[0])
    # K_I below the environment's stiffness
    assert chapter4_tuning.TUNING_BOUNDS[1][1] <= press_fitness.TUNING_SPRING


def test_tuned_impedance_beats_its_start_on_a_held_out_force_and_is_reproducible():
    objective = functools.partial(press_fitness.impedance_fitness, duration=1.0)
    start = np.log10([5.0, 5.0])
    first = bh.tuning.cma_es(objective, start, 0.5, seed=4, max_generations=3, population=6)  # process pool
    again = bh.tuning.cma_es(objective, start, 0.5, seed=4, max_generations=3, population=6, executor="serial")
    np.testing.assert_array_equal(first.history_parameters, again.history_parameters)
    np.testing.assert_array_equal(first.history_fitness, again.history_fitness)
    untuned, _ = press_fitness.evaluate_press((5.0, 5.0), 8.0)
    tuned, _ = press_fitness.evaluate_press(tuple(10.0**first.best), 8.0)
    assert tuned.settling < untuned.settling and tuned.overshoot <= untuned.overshoot


@pytest.mark.parametrize(
    ("params", "force"),
    [((0.01, 100.0), 6.0), ((0.005, 4.7561), 4.0), ((0.0011, 3.1387), 6.0), ((1e-4, 1.0), 8.0), ((0.1, 500.0), 6.0)],
)
def test_fitness_runs_continue_the_shared_approach_to_the_bit(params, force):
    """_discrete_fim continues the approach that every (M_I, K_I) shares; the run from the start is the same."""
    t, measured = press_fitness._discrete_fim(*params, force, press_fitness.TUNING_SPRING, 1.0)
    start, _, _ = press_fitness._approach(press_fitness.TUNING_SPRING, force, 1.0)
    assert 0.1 < start.t < 0.9  # the runs share ~a third of their samples
    setup = press_fitness.cached_f3_setup(press_fitness.TUNING_SPRING)
    traj = finger_press.run(setup, press_fitness._discrete_fim_controller(setup, *params, force), 1.0)
    np.testing.assert_array_equal(t, traj.t)
    np.testing.assert_array_equal(measured, finger_press.normal_force(setup, traj))


def test_bad_impedance_inputs_raise_clear_errors():
    ref = Constant(np.zeros(3))
    normal = np.array([1.0, 0.0, 0.0])
    with pytest.raises(bh.InputError, match="mass"):
        PositionImpedance(ref, mass=-1.0)
    with pytest.raises(bh.InputError, match="stiffness"):
        ForceImpedance(ref, normal, 5.0, np.zeros(3), -100.0)
    with pytest.raises(bh.InputError, match="force"):
        ForceImpedance(ref, normal, -5.0, np.zeros(3), 100.0)
    with pytest.raises(bh.InputError, match="damping"):
        ForceImpedance(ref, normal, 5.0, np.zeros(3), 1e4, mass=1.0, damping=1.0, stiffness=100.0)
    with pytest.raises(bh.InputError, match="normal"):
        ForceImpedance(ref, np.zeros(3), 5.0, np.zeros(3), 100.0)
    with pytest.raises(bh.InputError, match="estimator"):
        AdaptiveForceImpedance(ref, normal, 5.0, np.zeros(3), 100.0, estimator="kalman")
    law = ForceImpedance(ref, normal, SmoothStep([5.0], [-1.0], 0.1), np.zeros(3), 100.0)
    with pytest.raises(bh.InputError, match="desired force"):
        law.command(1.0, np.zeros(3), synthetic_contact(1.0, normal), 1e-3)
    with pytest.raises(bh.InputError, match="ImpedanceLaw"):
        ImpedanceController(bh.BarrettHand(), {"F3": "fim"})
