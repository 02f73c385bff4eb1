"""The internal-force QP against an independent solver (quadprog), the cones, and the pseudo-inverse baseline."""

from __future__ import annotations

import numpy as np
import pytest
import quadprog

import bhgrasp as bh
from bhgrasp.grasp import friction_pyramid, grasp_map
from bhgrasp.grasp_forces import ContactForceQP, cone_violations, pseudo_inverse_forces

GRAVITY_WRENCH = np.array([0.0, 0.0, 0.2 * 9.81, 0.0, 0.0, 0.0])  # what the contacts must exert to hold 0.2 kg


def sphere_contacts(n: int = 3, radius: float = 0.04, tilt: float = 0.0):
    """n contacts on a sphere's equator (optionally tilted below it), normals towards the centre."""
    angles = 2 * np.pi * np.arange(n) / n + 0.3
    points = radius * np.column_stack((np.cos(angles) * np.cos(tilt), np.sin(angles) * np.cos(tilt),
                                       np.full(n, -np.sin(tilt))))  # fmt: skip
    return points, -points / radius


def reference_qp(gmap, w, mu, facets, f_min, desired=None):
    """The same problem solved by quadprog (Goldfarb-Idnani active set): an independent solver."""
    n = gmap.shape[1] // 3
    pyramid, _ = friction_pyramid(mu, facets)
    blocks = np.zeros((n * len(pyramid), 3 * n))
    normals = np.zeros((n, 3 * n))
    for i in range(n):
        blocks[i * len(pyramid) : (i + 1) * len(pyramid), 3 * i : 3 * i + 3] = -pyramid
        normals[i, 3 * i + 2] = 1.0
    constraints = np.vstack((gmap, blocks, normals))
    b = np.concatenate((w, np.zeros(len(blocks)), np.full(n, f_min)))
    a = np.zeros(3 * n) if desired is None else np.ravel(desired)
    return quadprog.solve_qp(np.eye(3 * n), a, constraints.T, b, meq=6)[0].reshape(n, 3)


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
    best = quadprog.solve_qp(hessian, gmap.T @ GRAVITY_WRENCH, np.vstack((blocks, normals_rows)).T,
                             np.zeros(len(blocks) + n), meq=0)[0]  # fmt: skip
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
