"""Inverse kinematics against forward kinematics (round trips), a second method (DLS) and geometry."""

from __future__ import annotations

import numpy as np
import pytest

import bhgrasp as bh
from bhgrasp.model.hand_ik import ik
from bhgrasp.model.ik import finger_ik, workspace


@pytest.mark.parametrize("finger", ["F1", "F2", "F3"])
def test_closed_form_reproduces_random_reachable_fingertips(barrett: bh.Hand, finger: str) -> None:
    rng = np.random.default_rng(hash(finger) % 2**32)
    index = barrett.fingers.index(finger)
    for _ in range(300):
        q = barrett.random_configuration(rng)
        target = barrett.fingertip_positions(q)[index]
        solution = finger_ik(barrett, finger, target, q0=q)
        reached = barrett.fingertip_positions(solution.apply(q))[index]
        assert np.linalg.norm(reached - target) < 1e-6
        assert np.all(solution.angles >= barrett.lower[solution.indices])
        assert np.all(solution.angles <= barrett.upper[solution.indices])
        assert solution.plane_residual < 1e-12
        # Away from the spread singularity (tip on the spread axis) the solution is the one we started from.
        if (
            finger == "F3"
            or np.linalg.norm(target[:2] - barrett.frame_placement(q, f"{finger}_spread").translation[:2]) > 1e-3
        ):
            np.testing.assert_allclose(solution.angles, q[solution.indices], atol=1e-6)


def test_closed_form_works_for_a_placed_hand() -> None:
    import pinocchio as pin

    placement = pin.SE3(pin.rpy.rpyToMatrix(0.5, 0.2, -1.0), np.array([0.3, 0.1, -0.2]))
    hand = bh.BarrettHand(base_placement=placement)
    q = hand.random_configuration(9)
    for i, finger in enumerate(hand.fingers):
        target = hand.fingertip_positions(q)[i]
        solution = finger_ik(hand, finger, target, q0=q)
        assert np.linalg.norm(hand.fingertip_positions(solution.apply(q))[i] - target) < 1e-9


def test_f3_reports_its_out_of_plane_residual(barrett: bh.Hand) -> None:
    q = barrett.configuration(F3_proximal=1.0, F3_distal=0.3)
    target = barrett.fingertip_positions(q)[2] + np.array([0.004, 0.0, 0.0])  # F3 moves in the x = 0 plane
    solution = finger_ik(barrett, "F3", target)
    assert solution.plane_residual == pytest.approx(0.004, abs=1e-12)
    np.testing.assert_allclose(solution.angles, [1.0, 0.3], atol=1e-9)
    with pytest.raises(bh.UnreachableError, match="out of finger 'F3'"):
        finger_ik(barrett, "F3", target, plane_tolerance=1e-3)


@pytest.mark.parametrize(
    ("finger", "target", "why"),
    [
        ("F1", [0.0, 0.0, 0.5], "out of reach"),  # 0.5 m above the palm: far beyond the 0.12 m finger
        ("F3", [0.0, 0.05, 0.0754], "out of reach"),  # on the F3 proximal axis itself: closer than |l2 - l3|
        ("F3", [0.0, 0.17, 0.05], "out of reach"),  # reachable length, but needs a negative proximal angle
    ],
)
def test_unreachable_targets_raise(barrett: bh.Hand, finger: str, target: list[float], why: str) -> None:
    with pytest.raises(bh.UnreachableError, match=why):
        finger_ik(barrett, finger, target)


def test_closed_form_agrees_with_dls(barrett: bh.Hand) -> None:
    """Two methods, one answer: DLS from the closed-form solution's neighbourhood lands on the same angles."""
    q = barrett.random_configuration(21)
    targets = dict(zip(barrett.fingers, barrett.fingertip_positions(q)))
    closed = barrett.neutral()
    for finger, target in targets.items():
        closed = finger_ik(barrett, finger, target, q0=q).apply(closed)
    numeric = ik(barrett, targets, q0=np.clip(closed + 0.05, barrett.lower, barrett.upper), tolerance=1e-10)
    np.testing.assert_allclose(numeric.q, closed, atol=1e-6)


@pytest.mark.parametrize("hand_name", ["barrett", "allegro"])
def test_dls_reaches_random_reachable_targets(request: pytest.FixtureRequest, hand_name: str) -> None:
    hand = request.getfixturevalue(hand_name)
    rng = np.random.default_rng(5)
    for trial in range(30):
        q = hand.random_configuration(rng)
        targets = dict(zip(hand.fingers, hand.fingertip_positions(q)))
        result = ik(hand, targets, restarts=30, rng=trial)
        assert result.converged and result.max_error < 1e-6
        assert hand.within_limits(result.q)
        np.testing.assert_allclose(hand.fingertip_positions(result.q), hand.fingertip_positions(q), atol=1e-6)


def test_dls_reports_an_unreachable_target_with_its_best_attempt(barrett: bh.Hand) -> None:
    with pytest.raises(bh.UnreachableError) as caught:
        ik(barrett, {"F1": [0.0, 0.0, 1.0]}, restarts=2, rng=0)
    best = caught.value.result
    assert isinstance(best, bh.IKResult) and not best.converged
    assert best.errors["F1"] > 0.8  # 1 m up, the finger reaches ~0.19 m


def test_workspace_matches_symmetry_and_reach(barrett: bh.Hand) -> None:
    f1, f2, f3 = (workspace(barrett, f, 4000, rng=1) for f in barrett.fingers)
    # F2 mirrors F1 in the y-z plane (same samples, opposite spread axis and side).
    np.testing.assert_allclose(f2.points * [-1, 1, 1], f1.points, atol=1e-12)
    assert np.all(np.abs(f3.points[:, 0]) < 1e-12)  # F3 has no spread: it stays in x = 0
    # Every point is at most l1 + l2 + l3 from its spread axis and never below the knuckle's lowest reach.
    radial = np.linalg.norm(f1.points[:, :2] - [-0.025, 0.0], axis=1)
    assert radial.max() <= 0.050 + 0.070 + 0.050 + 1e-9
    assert f1.points[:, 2].min() >= 0.0754 - 1e-9  # proximal in [0, 140] deg and the 40 deg bend point up
    np.testing.assert_array_equal(f1.lower, f1.points.min(axis=0))
