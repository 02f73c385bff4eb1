"""The internal-force QP against independent solvers (quadprog, HiGHS), the cones, and the pseudo-inverse baseline.

Infeasible requests: detected in a bounded number of iterations and answered by the nearest admissible forces,
checked against quadprog on the same problem and against HiGHS' feasibility LP.
"""

from __future__ import annotations

import time

import numpy as np
import pytest
import quadprog
from scipy.optimize import linprog, lsq_linear

import bhgrasp as bh
from bhgrasp.grasp import (
    ContactForceQP,
    cone_violations,
    default_torque_scale,
    friction_cone_edges,
    friction_pyramid,
    grasp_map,
    pseudo_inverse_forces,
)
from bhgrasp.grasp.forces import NEAREST_WEIGHT

GRAVITY_WRENCH = np.array([0.0, 0.0, 0.2 * 9.81, 0.0, 0.0, 0.0])  # what the contacts must exert to hold 0.2 kg


def sphere_contacts(n: int = 3, radius: float = 0.04, tilt: float = 0.0):
    """n contacts on a sphere's equator (optionally tilted below it), normals towards the centre."""
    angles = 2 * np.pi * np.arange(n) / n + 0.3
    points = radius * np.column_stack(
        (np.cos(angles) * np.cos(tilt), np.sin(angles) * np.cos(tilt), np.full(n, -np.sin(tilt)))
    )
    return points, -points / radius


def cone_rows(n, mu, facets=8):
    """quadprog's rows C f >= c of the pyramids (-P f >= 0) and normal bounds (f_n >= f_min) and the equality
    rows E f = 0 that replace the pyramids when mu = 0 (f_t = 0; quadprog rejects the 8 degenerate facets)."""
    pyramid, _ = friction_pyramid(mu, facets)
    blocks = np.zeros((n * len(pyramid), 3 * n))
    normals = np.zeros((n, 3 * n))
    tangents = np.zeros((2 * n, 3 * n))
    for i in range(n):
        blocks[i * len(pyramid) : (i + 1) * len(pyramid), 3 * i : 3 * i + 3] = -pyramid
        normals[i, 3 * i + 2] = 1.0
        tangents[2 * i, 3 * i] = tangents[2 * i + 1, 3 * i + 1] = 1.0
    return (tangents, normals) if mu == 0 else (np.zeros((0, 3 * n)), np.vstack((blocks, normals)))


def quadprog_solve(hessian, a, equalities, e, gmap_columns, mu, f_min, facets=8, extra=0):
    """min 1/2 x^T H x - a^T x with equalities (rows, rhs), the pyramids and normal bounds on the first 3n."""
    n = gmap_columns // 3
    fixed, rows = (np.hstack((m, np.zeros((len(m), extra)))) for m in cone_rows(n, mu, facets))
    lower = np.zeros(len(rows))
    lower[-n:] = f_min
    constraints = np.vstack((equalities, fixed, rows))
    b = np.concatenate((e, np.zeros(len(fixed)), lower))
    return quadprog.solve_qp(hessian, a, constraints.T, b, meq=len(equalities) + len(fixed))[0]


def reference_qp(gmap, w, mu, facets, f_min, desired=None):
    """The same problem solved by quadprog (Goldfarb-Idnani active set): an independent solver."""
    n = gmap.shape[1] // 3
    a = np.zeros(3 * n) if desired is None else np.ravel(desired)
    return quadprog_solve(np.eye(3 * n), a, gmap, w, 3 * n, mu, f_min, facets).reshape(n, 3)


def reference_nearest(gmap, w, mu, f_min, desired=None, facets=8):
    """The nearest problem of the module docstring, by quadprog in the variables (f, e): min 1/2 |f - f_d|^2 +
    W/2 |e|^2, S (G f - w) = e, f admissible."""
    n = gmap.shape[1] // 3
    scale = np.concatenate((np.ones(3), np.full(3, 1.0 / default_torque_scale(gmap))))
    hessian = np.diag(np.concatenate((np.ones(3 * n), np.full(6, NEAREST_WEIGHT))))
    a = np.concatenate((np.zeros(3 * n) if desired is None else np.ravel(desired), np.zeros(6)))
    equality = np.hstack((scale[:, None] * gmap, -np.eye(6)))
    x = quadprog_solve(hessian, a, equality, scale * w, 3 * n, mu, f_min, facets, extra=6)
    return x[: 3 * n].reshape(n, 3)


def least_scaled_error(gmap, w, mu, f_min, facets=8):
    """min |S (G f - w)| over admissible f, by quadprog on the normal equations (tiny ridge): e* of the docstring."""
    n = gmap.shape[1] // 3
    scale = np.concatenate((np.ones(3), np.full(3, 1.0 / default_torque_scale(gmap))))
    a = scale[:, None] * gmap
    f = quadprog_solve(
        a.T @ a + 1e-10 * np.eye(3 * n), a.T @ (scale * w), np.zeros((0, 3 * n)), np.zeros(0), 3 * n, mu, f_min, facets
    )
    return float(np.linalg.norm(a @ f - scale * w))


def kkt_residual(gmap, mu, f_min, forces, desired, facets=8, active=1e-7):
    """Stationarity residual of the KKT conditions at ``forces``: min |f - f_d + G^T y + P_a^T l - N_a^T v| over
    y free, l, v >= 0 (P_a, N_a the pyramid facets and normal bounds active within ``active``), by bounded least
    squares.  ~0 proves (with feasibility) that ``forces`` is the optimum, degenerate active sets included, where
    quadprog reports "constraints are inconsistent"."""
    n = gmap.shape[1] // 3
    f = np.ravel(forces)
    pyramid, _ = friction_pyramid(mu, facets)
    rows = np.zeros((n * len(pyramid), 3 * n))
    for i in range(n):
        rows[i * len(pyramid) : (i + 1) * len(pyramid), 3 * i : 3 * i + 3] = pyramid
    facets_active = rows[rows @ f >= -active]
    normals_active = np.eye(3 * n)[2::3][f[2::3] - f_min <= active]
    columns = np.hstack((gmap.T, facets_active.T, -normals_active.T))
    lower = np.concatenate((np.full(6, -np.inf), np.zeros(len(facets_active) + len(normals_active))))
    solution = lsq_linear(columns, -(f - np.ravel(desired)), bounds=(lower, np.inf), method="bvls", tol=1e-14)
    return float(np.linalg.norm(columns @ solution.x + f - np.ravel(desired)))


def lp_feasible(gmap, w, mu, f_min, facets=8):
    """Whether G f = w has admissible forces: HiGHS on the feasibility LP (no objective)."""
    n = gmap.shape[1] // 3
    pyramid, _ = friction_pyramid(mu, facets)
    rows = np.zeros((n * len(pyramid) + n, 3 * n))
    for i in range(n):
        rows[i * len(pyramid) : (i + 1) * len(pyramid), 3 * i : 3 * i + 3] = pyramid
        rows[n * len(pyramid) + i, 3 * i + 2] = -1.0
    bound = np.concatenate((np.zeros(n * len(pyramid)), np.full(n, -f_min)))
    result = linprog(np.zeros(3 * n), A_ub=rows, b_ub=bound, A_eq=gmap, b_eq=w, bounds=(None, None), method="highs")
    assert result.status in (0, 2), result.message
    return result.status == 0


@pytest.mark.parametrize("seed", range(5))
@pytest.mark.parametrize("with_desired", [False, True])
def test_qp_optimum_matches_quadprog(seed, with_desired):
    rng = np.random.default_rng(seed)
    points, normals = sphere_contacts(3 + seed % 2, tilt=0.3 * rng.random())
    gmap = grasp_map(points, normals, np.zeros(3))
    wrench = GRAVITY_WRENCH + np.concatenate((0.3 * rng.normal(size=3), 0.003 * rng.normal(size=3)))
    desired = np.tile([0.0, 0.0, 4.0], (len(points), 1)) if with_desired else None
    qp = ContactForceQP(len(points), 0.6, facets=8, min_normal_force=0.5)
    result = qp.solve(gmap, wrench, desired)
    expected = reference_qp(gmap, wrench, 0.6, 8, 0.5, desired)
    assert result.feasible and result.status == "PROXQP_SOLVED"
    np.testing.assert_allclose(result.forces, expected, atol=1e-6)
    assert result.wrench_residual < 1e-8 and result.cone_violation <= 1e-9 and result.normal_margin >= -1e-9


def test_warm_start_follows_a_drifting_wrench_in_few_iterations():
    points, normals = sphere_contacts(3)
    gmap = grasp_map(points, normals, np.zeros(3))
    qp = ContactForceQP(3, 0.5, facets=8, min_normal_force=1.0)
    first = qp.solve(gmap, GRAVITY_WRENCH)
    iterations = []
    for k in range(1, 50):
        w = GRAVITY_WRENCH + 0.01 * k * np.array([0.1, 0.0, 0.0, 0.0, 0.001, 0.0])
        result = qp.solve(gmap, w)
        np.testing.assert_allclose(result.forces, reference_qp(gmap, w, 0.5, 8, 1.0), atol=1e-6)
        iterations.append(result.iterations)
    assert np.mean(iterations) <= first.iterations


def test_infeasible_wrench_is_reported_with_the_least_residual():
    """Contacts above the equator only push down: they cannot hold the weight; infeasible, and by how much."""
    points, normals = sphere_contacts(3, tilt=-0.6)  # 34 deg above the equator; cones 17 deg wide (mu 0.3)
    gmap = grasp_map(points, normals, np.zeros(3))
    mu = 0.3
    result = ContactForceQP(3, mu, facets=8, min_normal_force=0.0).solve(gmap, GRAVITY_WRENCH)
    assert not result.feasible and result.status != "PROXQP_SOLVED"
    assert result.cone_violation <= 1e-6 and result.normal_margin >= -1e-6  # admissible forces nonetheless
    # independent: the least |G f - w| over the pyramids, by quadprog on the normal equations (tiny ridge)
    n = 3
    pyramid, _ = friction_pyramid(mu, 8)
    blocks = np.zeros((n * len(pyramid), 3 * n))
    normals_rows = np.zeros((n, 3 * n))
    for i in range(n):
        blocks[i * len(pyramid) : (i + 1) * len(pyramid), 3 * i : 3 * i + 3] = -pyramid
        normals_rows[i, 3 * i + 2] = 1.0
    hessian = gmap.T @ gmap + 1e-9 * np.eye(3 * n)
    best = quadprog.solve_qp(
        hessian, gmap.T @ GRAVITY_WRENCH, np.vstack((blocks, normals_rows)).T, np.zeros(len(blocks) + n), meq=0
    )[0]
    least = np.linalg.norm(gmap @ best - GRAVITY_WRENCH)
    assert least > 0.1 and result.wrench_residual == pytest.approx(least, rel=1e-3)
    assert result.wrench_residual == pytest.approx(GRAVITY_WRENCH[2], rel=1e-3)  # none of the weight is carried


def test_pseudo_inverse_baseline_leaves_the_cone_where_the_qp_does_not():
    """Thesis (5.45) with a small squeeze meets G f = w but slips; the QP squeezes harder and stays inside."""
    points, normals = sphere_contacts(3)
    gmap = grasp_map(points, normals, np.zeros(3))
    mu = 0.4
    desired = np.tile([0.0, 0.0, 1.0], (3, 1))
    baseline = pseudo_inverse_forces(gmap, GRAVITY_WRENCH, desired)
    np.testing.assert_allclose(gmap @ baseline.ravel(), GRAVITY_WRENCH, atol=1e-12)
    assert np.max(cone_violations(baseline, mu)) > 0.1
    result = ContactForceQP(3, mu, facets=8).solve(gmap, GRAVITY_WRENCH, desired)
    assert result.feasible and np.max(cone_violations(result.forces, mu)) <= 1e-9


def test_bad_inputs():
    with pytest.raises(bh.InputError, match="n_contacts"):
        ContactForceQP(0, 0.5)
    with pytest.raises(bh.InputError, match="max_iter"):
        ContactForceQP(3, 0.5, max_iter=0)
    with pytest.raises(bh.InputError, match="max_iter_in"):
        ContactForceQP(3, 0.5, max_iter_in=2.5)
    with pytest.raises(bh.InputError, match="mu"):
        ContactForceQP(3, -0.5)
    qp = ContactForceQP(3, 0.5)
    with pytest.raises(bh.InputError, match="grasp_map"):
        qp.solve(np.zeros((6, 6)), GRAVITY_WRENCH)
    with pytest.raises(bh.InputError, match="wrench"):
        qp.solve(np.zeros((6, 9)), np.full(6, np.nan))
    with pytest.raises(bh.InputError, match="desired"):
        qp.solve(np.zeros((6, 9)), GRAVITY_WRENCH, np.zeros((2, 3)))


def test_one_shot_internal_forces_equals_the_persistent_qp():
    points, normals = sphere_contacts(3)
    gmap = bh.grasp_map(points, normals, np.zeros(3))
    once = bh.internal_forces(gmap, GRAVITY_WRENCH, 0.5, min_normal_force=1.0)
    persistent = ContactForceQP(3, 0.5, min_normal_force=1.0).solve(gmap, GRAVITY_WRENCH)
    np.testing.assert_allclose(once.forces, persistent.forces, atol=1e-12)
    with pytest.raises(bh.InputError, match="grasp_map"):
        bh.internal_forces(np.zeros((6, 4)), GRAVITY_WRENCH, 0.5)


# ------------------------------------------------------------------ infeasible requests: bounded, nearest answer
def equator_grasp(n=3, radius=0.04, angles=(90.0, 210.0, 330.0)):
    angles = np.radians(angles)
    points = radius * np.column_stack((np.cos(angles), np.sin(angles), np.zeros(n)))
    return grasp_map(points, -points / radius, np.zeros(3))


def test_frictionless_weight_is_infeasible_in_a_few_iterations():
    """The README's grasp with mu = 0: horizontal pushes cannot hold 0.2 kg.  It used to take 8.5 M iterations and
    9 minutes; now the certificate ends it in ~20, and the answer is the nearest admissible forces: every normal
    force at f_min (they cancel), no tangential force, and the whole weight missing."""
    gmap = equator_grasp()
    start = time.perf_counter()
    result = bh.internal_forces(gmap, GRAVITY_WRENCH, mu=0.0, min_normal_force=1.0)
    wall = time.perf_counter() - start
    assert not result.feasible and result.status == "PROXQP_PRIMAL_INFEASIBLE"
    assert result.iterations <= 60  # 19 on proxsuite 0.8 (the bound is 3300)
    assert wall < 0.5  # [s] generous: ~0.3 ms
    np.testing.assert_allclose(result.forces, np.tile([0.0, 0.0, 1.0], (3, 1)), atol=1e-9)
    np.testing.assert_allclose(result.wrench_error, -GRAVITY_WRENCH, atol=1e-9)
    assert result.wrench_residual == pytest.approx(GRAVITY_WRENCH[2], rel=1e-9)
    assert not lp_feasible(gmap, GRAVITY_WRENCH, 0.0, 1.0)
    qp = ContactForceQP(3, 0.0, min_normal_force=1.0)
    first, again = qp.solve(gmap, GRAVITY_WRENCH), qp.solve(gmap, GRAVITY_WRENCH)
    assert again.iterations <= 3 and not again.feasible  # still infeasible: one warm-started nearest solve
    np.testing.assert_allclose(again.forces, first.forces, atol=1e-9)
    assert first.iterations <= qp.iteration_bound == 3300


@pytest.mark.parametrize(("mu", "tilt", "with_desired"), [(0.3, -0.6, False), (0.3, -0.6, True), (0.0, 0.4, True)])
def test_nearest_admissible_forces_match_quadprog(mu, tilt, with_desired):
    """Contacts above the equator cannot lift; with mu = 0 below it they cannot hold a sideways push either.  The
    answer is the nearest problem's optimum (quadprog, variables (f, e)), and its wrench error is within the
    docstring's bound of the least any admissible forces reach (quadprog on the normal equations)."""
    points, normals = sphere_contacts(3, tilt=tilt)
    gmap = grasp_map(points, normals, np.zeros(3))
    wrench = GRAVITY_WRENCH + np.array([1.5, -0.5, 0.0, 0.0, 0.01, 0.002])
    desired = np.tile([0.0, 0.0, 4.0], (3, 1)) if with_desired else None
    assert not lp_feasible(gmap, wrench, mu, 0.5)
    result = ContactForceQP(3, mu, min_normal_force=0.5).solve(gmap, wrench, desired)
    assert not result.feasible and result.iterations <= 1000
    np.testing.assert_allclose(result.forces, reference_nearest(gmap, wrench, mu, 0.5, desired), atol=1e-6)
    assert result.normal_margin >= -1e-9 and result.cone_violation <= 1e-9
    scale = np.concatenate((np.ones(3), np.full(3, 1.0 / default_torque_scale(gmap))))
    error = np.linalg.norm(scale * result.wrench_error)
    least = least_scaled_error(gmap, wrench, mu, 0.5)
    f_d = np.zeros(9) if desired is None else desired.ravel()
    assert least > 0.1 and least - 1e-9 <= error <= least + np.sum((result.forces.ravel() - f_d) ** 2) / (
        NEAREST_WEIGHT * least
    )


def random_request(seed):
    """A random grasp (2-4 contacts on a 2-6 cm sphere, normals tilted up to ~25 deg, mu in [0, 1], f_min in
    {0, 0.5, 1} N) and a wrench: random (mostly infeasible), inside the cones, or degenerate (every contact on a
    pyramid edge at f_min, every facet and normal bound active), in turn."""
    rng = np.random.default_rng(seed)
    n = int(rng.integers(2, 5))
    directions = rng.normal(size=(n, 3))
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    normals = -directions + 0.4 * rng.normal(size=(n, 3))
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    gmap = grasp_map(rng.uniform(0.02, 0.06) * directions, normals, np.zeros(3))
    mu = 0.0 if seed % 10 == 0 else rng.uniform(0.0, 1.0)
    f_min = float(rng.choice([0.0, 0.5, 1.0]))
    if seed % 3 == 0:
        return gmap, np.concatenate((rng.normal(scale=2.0, size=3), rng.normal(scale=0.05, size=3))), mu, f_min
    edges = friction_cone_edges(mu, 8)
    if seed % 3 == 1:
        normal = f_min + rng.uniform(0.0, 3.0, n)
        forces = normal[:, None] * edges[rng.integers(8, size=n)] / edges[0, 2] * rng.uniform(0.0, 1.0, (n, 1))
        forces[:, 2] = normal
    else:
        forces = max(f_min, 0.5) * edges[rng.integers(8, size=n)] / edges[0, 2]
        f_min = max(f_min, 0.5)
    return gmap, gmap @ forces.ravel(), mu, f_min


@pytest.mark.parametrize("seed", range(60))
def test_random_requests_end_in_bounded_iterations_with_verified_answers(seed):
    gmap, wrench, mu, f_min = random_request(seed)
    n = gmap.shape[1] // 3
    desired = np.tile([0.0, 0.0, 3.0], (n, 1))
    qp = ContactForceQP(n, mu, min_normal_force=f_min)
    result = qp.solve(gmap, wrench, desired)
    assert result.iterations <= qp.iteration_bound
    assert result.iterations <= 2000  # <= ~1700 over 1000 such requests
    pyramid_rows = cone_rows(n, mu)[1][:-n] if mu > 0 else np.zeros((0, 3 * n))
    assert np.all(pyramid_rows @ result.forces.ravel() >= -1e-7) and result.normal_margin >= -1e-7
    assert result.feasible == lp_feasible(gmap, wrench, mu, f_min)  # HiGHS agrees, both ways
    if result.feasible:
        assert result.wrench_residual <= 1e-6 * max(1.0, np.linalg.norm(wrench))
        assert kkt_residual(gmap, mu, f_min, result.forces, desired) < 1e-6  # optimal, by its KKT conditions
        if seed % 3 != 2:  # and quadprog's optimum, where its active set is not degenerate
            np.testing.assert_allclose(result.forces, reference_qp(gmap, wrench, mu, 8, f_min, desired), atol=1e-6)
    else:
        assert result.wrench_residual > 1e-6


def test_a_false_infeasibility_certificate_is_overruled():
    """A feasible wrench (benchmarks/bench_qp.py, cycle 161) for which proxsuite's certificate fires at eps 1e-6:
    the nearest problem's tiny error makes the QP run again without the test, and the optimum is found."""
    gmap = equator_grasp()
    t = 0.161
    wrench = np.array(
        [
            0.3 * np.sin(t),
            0.2 * np.cos(t),
            9.81 * 0.2 + 0.1 * np.sin(2 * t),
            0.002 * np.sin(t),
            0.001 * np.cos(t),
            0.0005 * np.sin(3 * t),
        ]
    )
    qp = ContactForceQP(3, 0.5, min_normal_force=1.0)
    result = qp.solve(gmap, wrench)
    assert result.feasible and result.status == "PROXQP_SOLVED" and result.iterations <= qp.iteration_bound
    np.testing.assert_allclose(result.forces, reference_qp(gmap, wrench, 0.5, 8, 1.0), atol=1e-8)
    # the next cycle starts from the check's optimum, not from the QP's own failed iterate (which, in the grasp
    # demo moved 3 mm along x, failed again and again: 1160 cycles of 50 outer iterations)
    again = qp.solve(gmap, wrench)
    assert again.feasible and again.iterations == 0


def test_control_loop_in_and_out_of_feasibility():
    """Warm-started cycles whose vertical force swings between pushing down (feasible) and lifting (infeasible:
    the contacts are above the equator): every answer equals a fresh solve's, feasible ones quadprog's, infeasible
    ones the nearest problem's, and a persistently infeasible request costs a few iterations per cycle."""
    points, normals = sphere_contacts(3, tilt=-0.6)
    gmap = grasp_map(points, normals, np.zeros(3))
    qp = ContactForceQP(3, 0.3, min_normal_force=1.0)
    desired = np.tile([0.0, 0.0, 3.0], (3, 1))
    infeasible_costs, verdicts = [], set()
    for k in range(150):
        s = k / 150
        wrench = np.array([0.5 * np.sin(6 * s), 0.0, 3.0 * np.sin(6 * np.pi * s), 0.01 * np.cos(5 * s), 0.0, 0.002])
        result = qp.solve(gmap, wrench, desired)
        fresh = ContactForceQP(3, 0.3, min_normal_force=1.0).solve(gmap, wrench, desired)
        assert result.feasible == fresh.feasible == lp_feasible(gmap, wrench, 0.3, 1.0)
        np.testing.assert_allclose(result.forces, fresh.forces, atol=1e-6)
        expected = reference_qp if result.feasible else None
        if expected is not None:
            np.testing.assert_allclose(result.forces, expected(gmap, wrench, 0.3, 8, 1.0, desired), atol=1e-6)
        else:
            np.testing.assert_allclose(result.forces, reference_nearest(gmap, wrench, 0.3, 1.0, desired), atol=1e-6)
            infeasible_costs.append(result.iterations)
        assert result.iterations <= qp.iteration_bound
        verdicts.add(result.feasible)
    assert verdicts == {True, False} and np.median(infeasible_costs) <= 5
