"""The least joint torque that holds a wrench (bhgrasp.grasp.hold_torque): a closed form, a search, the demo's hold."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.linalg import null_space

import bhgrasp as bh
from bhgrasp.grasp.cones import friction_pyramid
from bhgrasp.grasp.frames import contact_frames, grasp_map_from_frames, hand_jacobian
from bhgrasp.grasp.hold_torque import grasp_contacts, least_hold_torque, static_hold_torque
from bhgrasp.scenarios.estimation import state_at
from bhgrasp.scenarios.grasp_demo import run_grasp_demo
from bhgrasp.scenarios.rollouts import final_hold_torque


def pinch(weight: float, half_width: float = 0.03):
    """Two contacts at (+-a, 0, 0) pressing inward along -+x, t1 vertical; one joint pushes each along its normal."""
    points = np.array([[-half_width, 0.0, 0.0], [half_width, 0.0, 0.0]])
    frames = np.zeros((2, 3, 3))
    for i, inward in enumerate((1.0, -1.0)):
        frames[i] = np.column_stack(([0.0, 0.0, 1.0], [0.0, inward, 0.0], [inward, 0.0, 0.0]))  # t1, t2, n
    grasp = grasp_map_from_frames(points, frames, np.zeros(3))
    jacobian = np.zeros((6, 2))
    jacobian[2, 0] = jacobian[5, 1] = 1.0  # joint i moves contact i's point along its normal
    wrench = np.array([0.0, 0.0, weight, 0.0, 0.0, 0.0])  # the contacts carry the weight
    return grasp, jacobian, wrench


def test_an_antipodal_pinch_needs_half_the_weight_over_mu_on_each_finger() -> None:
    """Each contact carries W/2 by friction (the moments about the centre balance), so f_n >= W / (2 mu): with a
    joint per finger pushing along its normal, tau = f_n and s* = W / (2 mu L).  Four facets put an edge of the
    pyramid on t1 (vertical), where the pyramid reaches the cone."""
    weight, mu, limit = 9.0, 0.6, 2.0
    grasp, jacobian, wrench = pinch(weight)
    hold = least_hold_torque(grasp, jacobian, wrench, mu, limits=limit, facets=4)
    assert hold.fraction == pytest.approx(weight / (2 * mu * limit), rel=1e-7)
    np.testing.assert_allclose(hold.forces[:, 2], weight / (2 * mu), rtol=1e-7)
    np.testing.assert_allclose(hold.forces[:, 0], weight / 2, rtol=1e-7)  # the vertical (t1) shares
    np.testing.assert_allclose(hold.torques, weight / (2 * mu), rtol=1e-7)
    assert not hold.within  # 7.5 N m needed, 2 N m given
    # a load the joints carry anyway adds to the torque: tau = tau_0 + f_n
    loaded = least_hold_torque(grasp, jacobian, wrench, mu, limits=limit, offset=[0.5, 0.5], facets=4)
    assert loaded.fraction == pytest.approx((0.5 + weight / (2 * mu)) / limit, rel=1e-7)
    # one joint unlimited: the other still presses as hard (the moment balance), the fraction is its own
    one = least_hold_torque(grasp, jacobian, wrench, mu, limits=[math.inf, limit], facets=4)
    assert one.fraction == pytest.approx(weight / (2 * mu * limit), rel=1e-7) and one.joint == 1


def test_no_friction_cannot_hold_a_weight() -> None:
    grasp, jacobian, wrench = pinch(1.0)
    hold = least_hold_torque(grasp, jacobian, wrench, 0.0, facets=4)
    assert hold.fraction == math.inf and hold.forces is None and hold.torques is None and hold.joint == -1
    assert not hold.within


def test_bad_inputs_are_named() -> None:
    grasp, jacobian, wrench = pinch(1.0)
    with pytest.raises(bh.InputError, match="`limits` must be > 0"):
        least_hold_torque(grasp, jacobian, wrench, 0.5, limits=[1.0, 0.0])
    with pytest.raises(bh.InputError, match="`limits` must be one number or 2 numbers"):
        least_hold_torque(grasp, jacobian, wrench, 0.5, limits=[1.0, 1.0, 1.0])
    with pytest.raises(bh.InputError, match="at least one joint"):
        least_hold_torque(grasp, jacobian, wrench, 0.5, limits=math.inf)
    with pytest.raises(bh.InputError, match="`grasp_map` must have shape"):
        least_hold_torque(grasp[:, :5], jacobian, wrench, 0.5)
    with pytest.raises(bh.InputError, match="`wrench` must be finite"):
        least_hold_torque(grasp, jacobian, [np.nan, 0, 0, 0, 0, 0], 0.5)
    with pytest.raises(bh.InputError, match="`min_normal_force`"):
        least_hold_torque(grasp, jacobian, wrench, 0.5, min_normal_force=-1.0)


@pytest.fixture(scope="module")
def heavy_hold():
    """The demo's 0.9 kg box held in its pinch under a 0.75 N m torque limit (the robustness table's scenario)."""
    result = run_grasp_demo(mass=0.9, duration=1.5, torque_limit=0.75)
    return result, state_at(result.trajectory, len(result.trajectory.t) - 1)


def test_no_forces_of_the_model_hold_the_demos_box_with_less_torque(heavy_hold) -> None:
    """A second method: forces drawn at random on the internal-force space of G f = w (f = f* + N z) inside the
    pyramids never need less peak torque than the LP's optimum, and the LP's own forces meet every constraint."""
    result, state = heavy_hold
    hand, body = result.scene.hand, result.trajectory.object_names[0]
    hold = static_hold_torque(hand, state, body, 0.9, 0.6)
    assert 0.7 < hold.fraction < 1.0  # F3's inner joint: it opposes F1 and F2 together
    assert result.trajectory.joint_names[hold.joint] == "F3_proximal"
    points, normals, links = grasp_contacts(hand, state, body)
    assert len(links) == 3  # one per finger
    grasp = grasp_map_from_frames(points, contact_frames(normals), state.object_poses[0].translation)
    jacobian = hand_jacobian(hand, state.q, points, links, normals)
    wrench = np.array([0.0, 0.0, 0.9 * 9.81, 0.0, 0.0, 0.0])
    tau_0 = hand.gravity_torques(state.q)
    pyramid, _ = friction_pyramid(0.6, 8)
    f = hold.forces.ravel()
    np.testing.assert_allclose(grasp @ f, wrench, atol=1e-6)
    assert np.max(np.einsum("fk,nk->nf", pyramid, hold.forces)) <= 1e-7
    np.testing.assert_allclose(hold.torques, tau_0 + jacobian.T @ f, atol=1e-12)
    assert np.max(np.abs(hold.torques)) == pytest.approx(hold.fraction, rel=1e-6)
    basis = null_space(grasp)  # (9, 3): the internal forces
    draws = np.random.default_rng(0).normal(scale=2.0, size=(20000, basis.shape[1]))
    candidates = f + draws @ basis.T
    inside = np.all(np.einsum("fk,snk->snf", pyramid, candidates.reshape(len(draws), -1, 3)) <= 0.0, axis=(1, 2))
    peaks = np.max(np.abs(tau_0 + candidates[inside] @ jacobian), axis=1)
    assert inside.sum() > 1000 and peaks.min() >= hold.fraction - 1e-9


def test_the_joints_carry_the_gravity_torques_and_the_contacts_at_rest() -> None:
    """The convention against the simulator: in the demo's hold at rest, tau = g(q) + J_h^T f with every contact
    point on its own link and f the simulated forces on the box (contact frames) is the torque the joints apply."""
    result = run_grasp_demo(mass=0.5, duration=3.0)
    trajectory, hand = result.trajectory, result.scene.hand
    k = len(trajectory.t) - 1
    state, body = state_at(trajectory, k), trajectory.object_names[0]
    assert np.abs(state.v).max() < 1e-3  # at rest
    points, normals, links = grasp_contacts(hand, state, body, contacts="point")
    on_box = [
        i for i, (link, other) in enumerate(state.contact_bodies) if other == body and hand.model.existFrame(link)
    ]
    forces = np.einsum("nji,nj->ni", contact_frames(normals), state.contact_forces[on_box]).ravel()
    predicted = hand.gravity_torques(state.q) + hand_jacobian(hand, state.q, points, links, normals).T @ forces
    np.testing.assert_allclose(predicted, trajectory.tau[k], atol=2e-3 * np.abs(trajectory.tau[k]).max())


def test_the_circumscribed_pyramid_holds_the_cone() -> None:
    """Four facets put the inscribed pyramid's edges on the cone along t1; the circumscribed one's faces touch it,
    its edges at mu / cos(pi / 4): the pinch needs f_n = W cos(pi / 4) / (2 mu)."""
    weight, mu = 9.0, 0.6
    grasp, jacobian, wrench = pinch(weight)
    outer = least_hold_torque(grasp, jacobian, wrench, mu, facets=4, cone="circumscribed")
    assert outer.fraction == pytest.approx(weight * math.cos(math.pi / 4) / (2 * mu), rel=1e-7)
    with pytest.raises(bh.InputError, match="`cone` must be one of"):
        least_hold_torque(grasp, jacobian, wrench, mu, cone="exact")


def test_the_rollouts_figure_falls_with_more_friction(heavy_hold) -> None:
    result, _ = heavy_hold
    assumed, true = final_hold_torque(result, 0.6), final_hold_torque(result, 0.8)
    assert 0.7 < assumed < 1.0 and true < assumed  # more friction, less squeeze: less torque


def test_the_table_counts_the_boxes_beyond_the_limit() -> None:
    """summarise's hold-torque figures on three runs: one held within the limit, one held beyond it, one failed."""
    import pandas as pd

    from bhgrasp.thesis.robustness import summarise

    frame = pd.DataFrame(
        {
            "mass": [0.3, 0.8, 0.9],
            "status": ["ok"] * 3,
            "true_position_error": [1e-5] * 3,
            "true_rotation_error": [1e-4, 3e-3, 8e-3],  # the last beyond the 5 mrad bound
            "slip_events": [0.0] * 3,
            "slide": [0.0] * 3,
            "force_error": [0.01] * 3,
            "mass_estimate": [0.3, 0.8, 0.9],
            "motion_end": [2.0] * 3,
            "duration": [4.0] * 3,
            "torque_limit": [0.75] * 3,
            "hold_torque": [0.3, 0.76, 0.79],
            "hold_torque_true_mu": [0.2, 0.55, 0.57],
        }
    )
    figures = summarise(frame)
    assert figures["hold_torque_success_max_nm"] == 0.76 and figures["hold_torque_failure_min_nm"] == 0.79
    assert figures["hold_torque_true_mu_max_nm"] == 0.57
    assert figures["over_torque_limit_runs"] == 2 and figures["over_torque_limit_failures"] == 1
    assert figures["within_torque_limit_failures"] == 0
