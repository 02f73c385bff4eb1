"""Contact forces within the joints' torque limits (bhgrasp.grasp.torque_limited, GraspOptions.torque_limit).

The split against its definition (G f_w = G f, G f_i = 0, f_w in G's row space); the squeeze fraction against a
dense search of the same one-dimensional problem; the controllers against the limit they are told and the wrench
they must still exert; the demo against the drive that clips what a controller not told the limit asks.
"""

from __future__ import annotations

import numpy as np
import pytest

import bhgrasp as bh
from bhgrasp.controllers.adaptive_grasp import SMCAdaptiveGrasp
from bhgrasp.controllers.grasp_options import GraspOptions
from bhgrasp.grasp.torque_limited import internal_scale, split_internal
from bhgrasp.model.objects import Box
from bhgrasp.scenarios.grasp_demo import check_demo_arguments, run_grasp_demo


def test_the_split_exerts_the_wrench_and_leaves_an_internal_force() -> None:
    rng = np.random.default_rng(4)
    for contacts in (2, 3, 4):
        grasp_map = rng.normal(size=(6, 3 * contacts))
        forces = rng.normal(size=(contacts, 3))
        wrench_part, internal = split_internal(grasp_map, forces)
        assert wrench_part.shape == internal.shape == forces.shape
        np.testing.assert_allclose(wrench_part + internal, forces, atol=1e-12)
        np.testing.assert_allclose(grasp_map @ wrench_part.ravel(), grasp_map @ forces.ravel(), atol=1e-10)
        np.testing.assert_allclose(grasp_map @ internal.ravel(), 0.0, atol=1e-10)
        # f_w is in the row space of G: orthogonal to every internal force
        null = np.linalg.svd(grasp_map)[2][np.linalg.matrix_rank(grasp_map) :]
        np.testing.assert_allclose(null @ wrench_part.ravel(), 0.0, atol=1e-10)
    with pytest.raises(bh.InputError, match=r"`grasp_map` must be \(6, 9\)"):
        split_internal(np.zeros((6, 6)), np.zeros((3, 3)))


def search(torque, wrench_torque, limits, normals, wrench_normals) -> tuple[float, float]:
    """The least max(1, max_j |tau_j(beta)| / L_j) over a fine grid of beta keeping every normal >= 0 (the joints
    beta moves), and the largest beta at it."""
    internal = normals - wrench_normals
    betas = np.linspace(0.0, 1.0, 200_001)
    keep = np.all(wrench_normals[None, :] + betas[:, None] * internal[None, :] >= -1e-12, axis=1)
    betas = betas[keep]
    moved = torque != wrench_torque
    ratios = np.max(np.abs(wrench_torque + betas[:, None] * (torque - wrench_torque))[:, moved] / limits[moved], axis=1)
    worst = np.maximum(ratios, 1.0)
    return worst.min(), betas[worst <= worst.min() + 1e-9].max()


def test_the_squeeze_fraction_is_the_largest_that_keeps_the_joints_within_their_limits() -> None:
    rng = np.random.default_rng(11)
    within = reachable = 0
    for _ in range(300):
        nv, contacts = 4, 3
        wrench_torque = rng.normal(scale=0.3, size=nv)
        torque = wrench_torque + rng.normal(scale=0.6, size=nv)
        limits = rng.uniform(0.3, 1.5, size=nv)
        wrench_normals = rng.normal(scale=1.0, size=contacts)
        normals = np.maximum(wrench_normals + rng.uniform(0.0, 5.0, size=contacts), 0.5)
        beta = internal_scale(torque, wrench_torque, limits, normals, wrench_normals)
        best, largest = search(torque, wrench_torque, limits, normals, wrench_normals)
        ratio = np.max(np.abs(wrench_torque + beta * (torque - wrench_torque)) / limits)
        assert max(ratio, 1.0) <= best + 1e-6  # as good as the search's best
        assert beta >= largest - 1e-5  # and the largest such fraction (the search's grid is 5e-6)
        assert np.all(wrench_normals + beta * (normals - wrench_normals) >= -1e-9)  # every contact still presses
        within += bool(np.all(np.abs(torque) <= limits))
        reachable += best == 1.0
    # every kind of case was drawn: within the limits at beta = 1, within them at a smaller beta, never within
    assert within > 10 and reachable - within > 10 and 300 - reachable > 10, (within, reachable)


def test_within_the_limits_the_forces_are_left_alone() -> None:
    torque, limits = np.array([0.2, -0.5]), np.array([0.5, 0.5])
    assert internal_scale(torque, np.zeros(2), limits, np.ones(2), np.zeros(2)) == 1.0
    # joint 0 at 0.2 + 0.8 beta N m reaches its 0.5 N m at beta = 0.375; joint 1 does not depend on beta
    torque, wrench_torque = np.array([1.0, 0.1]), np.array([0.2, 0.1])
    beta = internal_scale(torque, wrench_torque, np.array([0.5, 0.5]), np.array([5.0]), np.array([0.0]))
    assert beta == pytest.approx((0.5 - 0.2) / (1.0 - 0.2))
    # an unlimited joint (inf) does not count
    assert internal_scale(np.array([9.0]), np.array([0.0]), np.array([np.inf]), np.ones(1), np.zeros(1)) == 1.0


def test_a_joint_the_squeeze_does_not_move_does_not_stop_it_helping_the_others() -> None:
    """Joint 1 carries 1.5 N m whatever the squeeze (over its 1 N m); joint 0, 0.2 + 2.8 beta, is within its limit
    from beta = 0.8 / 2.8 down: that beta, not one that leaves joint 0 at joint 1's ratio."""
    beta = internal_scale(np.array([3.0, 1.5]), np.array([0.2, 1.5]), np.ones(2), np.array([5.0]), np.array([0.0]))
    assert beta == pytest.approx(0.8 / 2.8)


def test_a_contact_at_the_least_normal_force_still_loses_squeeze() -> None:
    """The distribution put one contact at its least normal force (0.5 N), the wrench part presses it with 0.1 N: the
    limit comes first, down to where that contact would stop pressing."""
    torque, wrench_torque, limits = np.array([2.0]), np.array([0.0]), np.array([1.0])
    normals, wrench_normals = np.array([0.5, 6.0]), np.array([0.1, 1.0])
    assert internal_scale(torque, wrench_torque, limits, normals, wrench_normals) == pytest.approx(0.5)
    # with the other contact's wrench part pulling (-0.4 N) the squeeze stops where it would let go: 0.4 / 5
    beta = internal_scale(np.array([20.0]), wrench_torque, limits, normals, np.array([0.1, -0.4]))
    assert beta == pytest.approx(0.4 / 6.4)


def test_the_options_check_the_limit() -> None:
    assert GraspOptions(torque_limit=0.75).torque_limit == 0.75
    assert GraspOptions(torque_limit=[1, 2, np.inf]).torque_limit == (1.0, 2.0, np.inf)
    for bad in (0.0, -1.0, "x", [], [[1.0]], True, np.nan, [1.0, np.nan]):
        with pytest.raises(bh.InputError, match="`torque_limit` must be None, a positive number or one per joint"):
            GraspOptions(torque_limit=bad)
    hand = bh.BarrettHand()
    box = Box(size=(0.06, 0.05, 0.05), mass=0.3)
    law = SMCAdaptiveGrasp(hand, box, options=GraspOptions(torque_limit=0.75))
    assert law.engine == "python" and law.torque_limit.tolist() == [0.75] * 8
    with pytest.raises(bh.InputError, match="does not cover torque_limit=0.75"):
        SMCAdaptiveGrasp(hand, box, options=GraspOptions(torque_limit=0.75), engine="compiled")
    with pytest.raises(bh.InputError, match="`torque_limit_known` must be True or False"):
        check_demo_arguments(torque_limit_known="yes")
    with pytest.raises(bh.InputError, match="but none was given"):
        check_demo_arguments(torque_limit_known=True)
    with pytest.raises(bh.InputError, match=r"one per joint \(8\), got \(1.0, 1.0\)"):
        SMCAdaptiveGrasp(hand, box, options=GraspOptions(torque_limit=(1.0, 1.0)))


HEAVY = {"mass": 0.998, "estimate": 0.5, "duration": 2.0, "torque_limit": 0.75}
"""The robustness table's heaviest box under its torque limit: the least peak torque that holds it inside the
assumed cones (mu 0.6) is above 0.75 N m, inside the true ones (0.8) below."""


@pytest.fixture(scope="module")
def heavy_runs() -> tuple:
    return run_grasp_demo(**HEAVY, torque_limit_known=True), run_grasp_demo(**HEAVY)


def test_a_controller_told_the_limit_commands_within_it_and_holds(heavy_runs) -> None:
    known, unknown = heavy_runs
    log = known.trajectory.log
    grasping = log["contacts"] >= 2
    scale = log["squeeze_scale"][grasping]
    assert scale.min() < 0.9 and np.all(scale <= 1.0)  # it squeezed less, and only less
    assert np.abs(known.trajectory.u[grasping]).max() <= 0.75 + 1e-9  # it commands within the limit
    assert np.abs(unknown.trajectory.u).max() > 0.8  # the other asks for more, and the drive clips it
    # the same wrench: the scaled forces still exert what the law asks
    assert log["wrench_residual"][grasping][scale < 1.0].max() < 1e-6
    # told the limit it moves the box where asked; clipped, F3 (opposing F1 and F2) presses less and the box turns
    assert known.true_position_error < 0.5e-3 and known.true_rotation_error < 5e-3 and known.slide <= 1e-4
    assert unknown.true_rotation_error > 5e-3


@pytest.mark.parametrize("controller", ["pd", "ctc"])
def test_every_grasp_law_keeps_within_the_limit_it_is_told(controller: str) -> None:
    run = run_grasp_demo(mass=0.4, duration=1.2, controller=controller, torque_limit=0.4, torque_limit_known=True)
    log = run.trajectory.log
    grasping = log["contacts"] >= 2
    scaled = grasping & (log["squeeze_scale"] < 1.0)
    assert scaled.any()  # the limit was met, and the law squeezed less
    assert np.abs(run.trajectory.u[grasping]).max() <= 0.4 + 1e-9
    assert log["wrench_residual"][scaled].max() < 1e-6  # |G f - w| of the forces it applied
