"""Coupled hand-object dynamics (thesis (5.25), Definition 5.1) and grasp mobility against independent truths."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import bhgrasp as bh
from bhgrasp.grasp import ObjectState, grasp_dynamics, grasp_mobility
from bhgrasp.scenarios.hold import reference_hold


@pytest.fixture(scope="module")
def held():
    """The reference three-finger hold: hand, q, contacts (object body frame) and the box."""
    hold = reference_hold()
    state = hold.state
    pose = state.object_poses[0]
    box = hold.simulator.scene.objects[0]
    points_body = (state.contact_points - pose.translation) @ pose.rotation
    normals_body = state.contact_normals @ pose.rotation
    links = [a for a, _ in state.contact_bodies]
    return hold.simulator.scene.hand, state.q, box, pose, points_body, normals_body, links


def object_state(box, pose, twist):
    return ObjectState(box.mass, box.inertia, pose.translation.copy(), pose.rotation.copy(), np.asarray(twist, float))


def test_effective_mass_is_symmetric_positive_definite(held):
    hand, q, box, pose, points, normals, links = held
    twist = np.array([0.01, -0.02, 0.03, 0.2, -0.1, 0.3])
    dyn = grasp_dynamics(hand, q, object_state(box, pose, twist), points, normals, links)
    np.testing.assert_allclose(dyn.mass, dyn.mass.T, atol=1e-15)
    assert np.linalg.eigvalsh(dyn.mass).min() > 0.0  # positive definite
    # kinetic energy: the object's plus the hand's at q_dot = P x_dot
    q_dot = dyn.joint_map @ twist
    inertia_world = pose.rotation @ box.inertia @ pose.rotation.T
    energy = 0.5 * box.mass * twist[:3] @ twist[:3] + 0.5 * twist[3:] @ inertia_world @ twist[3:]
    energy += 0.5 * q_dot @ hand.mass_matrix(q) @ q_dot
    assert 0.5 * twist @ dyn.mass @ twist == pytest.approx(energy, rel=1e-12)


@pytest.mark.parametrize("seed", range(3))
def test_mdot_minus_two_c_is_skew_symmetric(held, seed):
    """Definition 5.1 (2): M~_dot (central differences along the motion) - 2 C~ is skew-symmetric."""
    hand, q, box, pose, points, normals, links = held
    rng = np.random.default_rng(seed)
    twist = np.concatenate((0.05 * rng.normal(size=3), 0.5 * rng.normal(size=3)))
    obj = object_state(box, pose, twist)
    dyn = grasp_dynamics(hand, q, obj, points, normals, links)
    h = 1e-6
    q_dot = dyn.joint_map @ twist
    ahead = grasp_dynamics(hand, pin.integrate(hand.model, q, h * q_dot), obj.advanced(h), points, normals, links)
    behind = grasp_dynamics(hand, pin.integrate(hand.model, q, -h * q_dot), obj.advanced(-h), points, normals, links)
    m_dot = (ahead.mass - behind.mass) / (2 * h)
    n = m_dot - 2 * dyn.coriolis
    assert np.max(np.abs(n + n.T)) < 1e-5 * max(1.0, np.max(np.abs(m_dot)))
    for s in rng.normal(size=(5, 6)):
        assert abs(s @ n @ s) < 1e-5 * (s @ s) * max(1.0, np.max(np.abs(m_dot)))


def test_square_hand_jacobian_gives_the_thesis_formula(held):
    """Two contacts on F1 and F2 (3 joints each): J_h is square on those joints and (5.25) holds as printed."""
    hand, q, box, pose, points, normals, links = held
    keep = [i for i, link in enumerate(links) if link.startswith(("F1", "F2"))]
    obj = object_state(box, pose, np.zeros(6))
    dyn = grasp_dynamics(hand, q, obj, points[keep], normals[keep], [links[i] for i in keep])
    joints = np.concatenate((hand.finger_indices("F1"), hand.finger_indices("F2")))
    square = dyn.hand_jacobian[:, joints]
    inverse = np.linalg.inv(square)
    mass_f = hand.mass_matrix(q)[np.ix_(joints, joints)]
    inertia_world = pose.rotation @ box.inertia @ pose.rotation.T
    mass_o = np.block([[box.mass * np.eye(3), np.zeros((3, 3))], [np.zeros((3, 3)), inertia_world]])
    thesis = mass_o + dyn.grasp_map @ inverse.T @ mass_f @ inverse @ dyn.grasp_map.T
    np.testing.assert_allclose(dyn.mass, thesis, rtol=1e-9, atol=1e-12)
    gravity = np.concatenate((box.mass * 9.81 * np.array([0, 0, 1.0]), np.zeros(3)))
    np.testing.assert_allclose(
        dyn.gravity, gravity + dyn.grasp_map @ inverse.T @ hand.gravity_torques(q)[joints], rtol=1e-9, atol=1e-12
    )


def test_three_fingertip_contacts_leave_the_barrett_five_object_motions(held):
    hand, q, box, pose, points, normals, links = held
    dyn = grasp_dynamics(hand, q, object_state(box, pose, np.zeros(6)), points, normals, links)
    basis = grasp_mobility(dyn.grasp_map, dyn.hand_jacobian)
    assert basis.shape == (6, 5)
    np.testing.assert_allclose(basis.T @ basis, np.eye(5), atol=1e-10)
    for twist in basis.T:  # each allowed twist is produced by some joint velocity: G^T x = J_h q_dot exactly
        q_dot = np.linalg.lstsq(dyn.hand_jacobian, dyn.grasp_map.T @ twist, rcond=None)[0]
        np.testing.assert_allclose(dyn.hand_jacobian @ q_dot, dyn.grasp_map.T @ twist, atol=1e-10)
    forbidden = np.linalg.svd(basis.T)[2][-1]  # the twist orthogonal to the allowed ones
    q_dot = np.linalg.lstsq(dyn.hand_jacobian, dyn.grasp_map.T @ forbidden, rcond=None)[0]
    assert np.linalg.norm(dyn.hand_jacobian @ q_dot - dyn.grasp_map.T @ forbidden) > 1e-3
    two = [i for i, link in enumerate(links) if link.startswith(("F1", "F2"))]
    g2 = bh.grasp_map(
        points[two] @ pose.rotation.T + pose.translation, normals[two] @ pose.rotation.T, pose.translation
    )
    j2 = dyn.hand_jacobian[[3 * i + k for i in two for k in range(3)]]
    assert grasp_mobility(g2, j2).shape == (6, 6)  # two 3-DOF fingers: every object twist


def test_bad_inputs(held):
    hand, q, box, pose, points, normals, links = held
    with pytest.raises(bh.InputError, match="obj"):
        grasp_dynamics(hand, q, "box", points, normals, links)
    with pytest.raises(bh.InputError, match="normals_body"):
        grasp_dynamics(hand, q, object_state(box, pose, np.zeros(6)), points, normals[:2], links)
    with pytest.raises(bh.InputError, match="jacobian"):
        grasp_mobility(np.zeros((6, 9)), np.zeros((6, 8)))
