"""Hand kinematics and dynamics against independent truths: finite differences, conservation laws, identities."""

from __future__ import annotations

import copy
import pickle

import numpy as np
import pinocchio as pin
import pytest

import bhgrasp as bh

SEEDS = range(5)


def _potential(hand: bh.Hand, q: np.ndarray) -> float:
    """Gravitational potential energy [J] of the moving bodies, -m g . c, from Pinocchio's centre of mass."""
    data = hand.model.createData()
    com = pin.centerOfMass(hand.model, data, q)  # moving bodies only; data.mass[0] is their total mass
    return float(-data.mass[0] * hand.gravity @ com)


@pytest.fixture(params=["barrett", "allegro"])
def hand(request: pytest.FixtureRequest) -> bh.Hand:
    return request.getfixturevalue(request.param)


@pytest.mark.parametrize("seed", SEEDS)
def test_fingertip_jacobian_equals_finite_differences(hand: bh.Hand, seed: int) -> None:
    q = hand.random_configuration(seed)
    step = 1e-7
    for i, finger in enumerate(hand.fingers):
        numeric = np.empty((3, hand.nv))
        for k in range(hand.nv):
            dq = np.zeros(hand.nv)
            dq[k] = step
            numeric[:, k] = (hand.fingertip_positions(q + dq)[i] - hand.fingertip_positions(q - dq)[i]) / (2 * step)
        np.testing.assert_allclose(hand.fingertip_jacobian(q, finger), numeric, atol=1e-8)


@pytest.mark.parametrize("seed", SEEDS)
def test_mass_matrix_is_symmetric_positive_definite(hand: bh.Hand, seed: int) -> None:
    mass = hand.mass_matrix(hand.random_configuration(seed))
    np.testing.assert_array_equal(mass, mass.T)
    assert np.linalg.eigvalsh(mass).min() > 0


@pytest.mark.parametrize("seed", SEEDS)
def test_mdot_minus_two_c_is_skew_symmetric(hand: bh.Hand, seed: int) -> None:
    """Thesis (2.27), with M_dot from central differences of CRBA along v."""
    rng = np.random.default_rng(seed)
    q, v = hand.random_configuration(rng), rng.normal(size=hand.nv)
    h = 1e-6
    mass_dot = (hand.mass_matrix(q + h * v) - hand.mass_matrix(q - h * v)) / (2 * h)
    n = mass_dot - 2 * hand.coriolis_matrix(q, v)
    scale = np.abs(mass_dot).max()
    np.testing.assert_allclose(n + n.T, 0.0, atol=1e-6 * scale)
    assert np.abs(n).max() > 1e-3 * scale  # non-trivial: the property is not vacuous
    # C v + G is the nonlinear-effects vector, and C(q, 0) = 0.
    np.testing.assert_allclose(
        hand.coriolis_matrix(q, v) @ v + hand.gravity_torques(q), hand.nonlinear_effects(q, v), atol=1e-12
    )
    np.testing.assert_array_equal(hand.coriolis_matrix(q, np.zeros(hand.nv)), 0.0)


@pytest.mark.parametrize("seed", SEEDS)
def test_forward_dynamics_inverts_inverse_dynamics(hand: bh.Hand, seed: int) -> None:
    rng = np.random.default_rng(seed)
    q, v, a = hand.random_configuration(rng), rng.normal(size=hand.nv), rng.normal(size=hand.nv)
    tau = hand.inverse_dynamics(q, v, a)
    np.testing.assert_allclose(hand.forward_dynamics(q, v, tau), a, atol=1e-8)
    # ... and both agree with M a + C v + G assembled from the separate terms.
    np.testing.assert_allclose(tau, hand.mass_matrix(q) @ a + hand.nonlinear_effects(q, v), atol=1e-12)


@pytest.mark.parametrize("seed", SEEDS)
def test_regressor_times_parameters_is_inverse_dynamics(hand: bh.Hand, seed: int) -> None:
    rng = np.random.default_rng(seed)
    q, v, a = hand.random_configuration(rng), rng.normal(size=hand.nv), rng.normal(size=hand.nv)
    regressor = hand.regressor(q, v, a)
    assert regressor.shape == (hand.nv, hand.inertial_parameters().size)
    np.testing.assert_allclose(regressor @ hand.inertial_parameters(), hand.inverse_dynamics(q, v, a), atol=1e-12)


def test_regressor_parameters_hold_barretts_masses(barrett: bh.Hand) -> None:
    masses = barrett.inertial_parameters()[0::10]
    expected = [0.14109, 0.062139, 0.04166, 0.14109, 0.062139, 0.04166, 0.062139, 0.04166]
    np.testing.assert_allclose(masses, expected)


@pytest.mark.parametrize("seed", SEEDS)
def test_gravity_torques_are_the_gradient_of_potential_energy(hand: bh.Hand, seed: int) -> None:
    """G(q) = dV/dq with V = -m g . c(q), c from Pinocchio's centre of mass (a different algorithm)."""
    q = hand.random_configuration(seed)
    step = 1e-6
    gradient = [(_potential(hand, q + step * e) - _potential(hand, q - step * e)) / (2 * step) for e in np.eye(hand.nv)]
    np.testing.assert_allclose(hand.gravity_torques(q), gradient, atol=1e-8)


def test_energy_is_conserved_without_torques(barrett: bh.Hand) -> None:
    """Free motion under gravity (RK4, 0.5 s): kinetic + potential energy stays constant."""
    q, v = barrett.random_configuration(11), np.random.default_rng(11).normal(scale=0.5, size=barrett.nv)
    zero = np.zeros(barrett.nv)

    def energy(q: np.ndarray, v: np.ndarray) -> float:
        return 0.5 * v @ barrett.mass_matrix(q) @ v + _potential(barrett, q)

    def derivative(state: np.ndarray) -> np.ndarray:
        return np.concatenate((state[8:], barrett.forward_dynamics(state[:8], state[8:], zero)))

    state, dt, start = np.concatenate((q, v)), 1e-4, energy(q, v)
    for _ in range(5000):
        k1 = derivative(state)
        k2 = derivative(state + dt / 2 * k1)
        k3 = derivative(state + dt / 2 * k2)
        k4 = derivative(state + dt * k3)
        state = state + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    drift = abs(energy(state[:8], state[8:]) - start)
    assert drift < 1e-8
    assert np.linalg.norm(state[:8] - q) > 0.01  # it really moved


@pytest.mark.parametrize("seed", SEEDS)
def test_external_forces_act_through_the_jacobian_transpose(barrett: bh.Hand, seed: int) -> None:
    """RNEA with a fingertip force F equals RNEA without it minus J^T F (thesis (4.8))."""
    rng = np.random.default_rng(seed)
    q, v, a = barrett.random_configuration(rng), rng.normal(size=8), rng.normal(size=8)
    force = rng.normal(size=3)
    f_ext = barrett.external_forces(q, {"F2_tip": force})
    expected = barrett.inverse_dynamics(q, v, a) - barrett.fingertip_jacobian(q, "F2").T @ force
    np.testing.assert_allclose(barrett.inverse_dynamics(q, v, a, f_ext), expected, atol=1e-12)
    wrench = np.concatenate((force, rng.normal(size=3)))
    f_ext = barrett.external_forces(q, {"F2_tip": wrench})
    expected = barrett.inverse_dynamics(q, v, a) - barrett.frame_jacobian(q, "F2_tip").T @ wrench
    np.testing.assert_allclose(barrett.inverse_dynamics(q, v, a, f_ext), expected, atol=1e-12)
    tau = rng.normal(size=8)
    np.testing.assert_allclose(
        barrett.forward_dynamics(q, v, tau, f_ext),
        np.linalg.solve(
            barrett.mass_matrix(q),
            tau + barrett.frame_jacobian(q, "F2_tip").T @ wrench - barrett.nonlinear_effects(q, v),
        ),
        atol=1e-8,
    )


def test_base_placement_and_gravity_mount_the_hand_anywhere() -> None:
    """Turning the hand and gravity together changes world-frame outputs by that rotation and no torque."""
    rotation = pin.rpy.rpyToMatrix(0.3, -1.1, 2.0)
    placement = pin.SE3(rotation, np.array([0.1, -0.2, 0.5]))
    upright = bh.BarrettHand()
    turned = bh.BarrettHand(base_placement=placement, gravity=rotation @ np.array([0.0, 0.0, -9.81]))
    q, v = upright.random_configuration(5), np.linspace(-1, 1, 8)
    np.testing.assert_allclose(turned.gravity_torques(q), upright.gravity_torques(q), atol=1e-12)
    np.testing.assert_allclose(turned.nonlinear_effects(q, v), upright.nonlinear_effects(q, v), atol=1e-12)
    expected = upright.fingertip_positions(q) @ rotation.T + placement.translation
    np.testing.assert_allclose(turned.fingertip_positions(q), expected, atol=1e-12)
    np.testing.assert_allclose(
        turned.fingertip_jacobian(q, "F3"), rotation @ upright.fingertip_jacobian(q, "F3"), atol=1e-12
    )
    assert turned.frame_placement(q, "palm_surface").isApprox(placement * upright.frame_placement(q, "palm_surface"))
    # Hanging upside down (gravity along the palm normal) flips every gravity torque.
    hanging = bh.BarrettHand(gravity=(0.0, 0.0, 9.81))
    np.testing.assert_allclose(hanging.gravity_torques(q), -upright.gravity_torques(q), atol=1e-12)
    upright.gravity = (0.0, 0.0, 0.0)
    np.testing.assert_array_equal(upright.gravity_torques(q), 0.0)


def test_copies_are_independent(barrett: bh.Hand) -> None:
    """Deep copies and pickles (process pools) own their model and data."""
    q = barrett.random_configuration(8)
    for clone in (copy.deepcopy(barrett), pickle.loads(pickle.dumps(barrett))):
        assert clone.model is not barrett.model
        np.testing.assert_array_equal(clone.mass_matrix(q), barrett.mass_matrix(q))
        clone.gravity = (0.0, 0.0, 0.0)
        assert np.abs(barrett.gravity_torques(q)).max() > 0.01
        np.testing.assert_array_equal(clone.gravity_torques(q), 0.0)


def test_configuration_by_joint_name(barrett: bh.Hand) -> None:
    q = barrett.configuration(F3_proximal=0.8, F1_spread=1.0)
    assert q[barrett.joint_index("F3_proximal")] == 0.8 and q[0] == 1.0
    assert np.count_nonzero(q) == 2
    np.testing.assert_array_equal(barrett.neutral(), np.zeros(8))


def test_random_configuration_is_seeded_and_within_limits(barrett: bh.Hand) -> None:
    np.testing.assert_array_equal(barrett.random_configuration(4), barrett.random_configuration(4))
    samples = np.array([barrett.random_configuration(s) for s in range(200)])
    assert np.all(samples >= barrett.lower) and np.all(samples <= barrett.upper)
    assert barrett.within_limits(samples[0]) and not barrett.within_limits(barrett.upper + 0.1)


def test_finger_joints(barrett: bh.Hand) -> None:
    assert barrett.finger_joints("F1") == ("F1_spread", "F1_proximal", "F1_distal")
    assert barrett.finger_joints("F3") == ("F3_proximal", "F3_distal")
    np.testing.assert_array_equal(barrett.finger_indices("F2"), [3, 4, 5])


def test_allegro_is_a_working_hand(allegro: bh.Hand) -> None:
    assert allegro.nv == 16
    assert len(allegro.fingers) == 4
    assert all(frame.endswith("_tip") for frame in allegro.fingertip_frames.values())
    assert all(len(allegro.finger_joints(f)) == 4 for f in allegro.fingers)
    q = allegro.random_configuration(0)
    assert allegro.fingertip_positions(q).shape == (4, 3)
    assert allegro.forward_dynamics(q, np.zeros(16), allegro.gravity_torques(q)) == pytest.approx(
        np.zeros(16), abs=1e-9
    )


def test_fingertips_given_by_name(allegro: bh.Hand) -> None:
    path = bh.example_robot_data_urdf("allegro_hand_description/urdf/allegro_right_hand.urdf")
    hand = bh.Hand.from_urdf(path, fingertips={"index": "link_3.0_tip", "thumb": "link_15.0_tip"})
    assert hand.fingers == ("index", "thumb")
    q = hand.random_configuration(1)
    np.testing.assert_array_equal(hand.fingertip_positions(q)[1], allegro.fingertip_positions(q)[3])


def test_summary_lists_every_joint(barrett: bh.Hand) -> None:
    text = barrett.summary()
    assert all(joint in text for joint in barrett.joint_names)
    assert "1.2022 kg" in text


def test_point_jacobian_matches_finite_differences_of_a_carried_point(barrett):
    """A point fixed on a link, moved with the link: d/dt of its world position equals point_jacobian @ v."""
    rng = np.random.default_rng(11)
    hand = bh.BarrettHand(base_placement=pin.SE3(pin.exp3(np.array([0.3, -0.2, 0.5])), np.array([0.1, 0.0, 0.2])))
    q, v = hand.random_configuration(rng), rng.normal(size=hand.nv)
    link = "F1_distal_link"
    offset = np.array([0.02, 0.005, -0.003])  # in the link frame

    def carried(configuration):
        return hand.frame_placement(configuration, link).act(offset)

    h = 1e-7
    expected = (carried(q + h * v) - carried(q - h * v)) / (2 * h)
    np.testing.assert_allclose(hand.point_jacobian(q, link, carried(q)) @ v, expected, atol=1e-7)


@pytest.mark.parametrize("hand_name", ["barrett", "allegro"])
def test_point_jacobians_batch_matches_finite_differences(hand_name, allegro):
    """point_jacobians (one kinematics pass) against finite differences of carried points, on a placed base."""
    rng = np.random.default_rng(12)
    placement = pin.SE3(pin.exp3(np.array([-0.4, 0.1, 0.9])), np.array([0.0, 0.3, -0.1]))
    if hand_name == "barrett":
        hand = bh.BarrettHand(base_placement=placement)
    else:
        hand = bh.Hand(allegro.model, allegro.fingertip_frames, base_placement=placement)
    q, v = hand.random_configuration(rng), rng.normal(size=hand.nv)
    frames = [frame for frame in hand.frame_names() if frame != "universe"][2::3]
    offsets = rng.normal(scale=0.03, size=(len(frames), 3))  # in each frame

    def carried(configuration):
        return np.array([hand.frame_placement(configuration, f).act(o) for f, o in zip(frames, offsets)])

    h = 1e-7
    expected = (carried(q + h * v) - carried(q - h * v)) / (2 * h)
    np.testing.assert_allclose(hand.point_jacobians(q, frames, carried(q)) @ v, expected, atol=1e-7)
    with pytest.raises(bh.InputError, match="points"):
        hand.point_jacobians(q, frames, np.zeros((len(frames) + 1, 3)))


def test_point_jacobians_of_a_one_joint_hand_keep_their_shape() -> None:
    """A 1-DOF finger (Pinocchio returns its 6 x 1 Jacobian as a vector): v_p = omega x (p - o) by hand."""
    from bhgrasp.model.planar import thesis_one_link_finger

    hand = thesis_one_link_finger()
    q = np.array([0.4])
    frame = hand.fingertip_frames[hand.fingers[0]]
    point = hand.frame_placement(q, frame).translation
    jacobians = hand.point_jacobians(q, [frame], point[None, :])
    assert jacobians.shape == (1, 3, 1)
    assert hand.frame_jacobian(q, frame).shape == (6, 1)
    axis = hand.frame_jacobian(q, frame)[3:, 0]  # the joint's angular velocity per rad/s
    data = hand.model.createData()
    pin.forwardKinematics(hand.model, data, q)
    origin = hand.base_placement.act(data.oMi[1].translation)  # on the joint axis
    np.testing.assert_allclose(jacobians[0, :, 0], np.cross(axis, point - origin), atol=1e-12)


def test_one_hand_class_offers_every_algorithm_of_its_modules_as_a_method() -> None:
    import inspect

    from bhgrasp.model import hand as hand_module
    from bhgrasp.model import hand_dynamics, hand_joints, hand_kinematics

    assert bh.Hand.__mro__ == (bh.Hand, object)  # one class, no layers
    for module in (hand_joints, hand_kinematics, hand_dynamics):
        for name, function in inspect.getmembers(module, inspect.isfunction):
            if name.startswith("_") or function.__module__ != module.__name__:
                continue
            offered = inspect.getattr_static(bh.Hand, name)
            assert (offered.fget if isinstance(offered, property) else offered) is function, name
    assert "twin" not in pickle.loads(pickle.dumps(bh.BarrettHand())).__dict__  # rebuilt on first use
    assert hand_module.Hand is bh.Hand
    loaded = bh.BarrettHand.from_urdf(bh.barrett_urdf_path())  # a plain Hand, as from Hand.from_urdf
    assert type(loaded) is bh.Hand
    assert set(loaded.fingertip_frames.values()) == set(bh.BarrettHand().fingertip_frames.values())


def test_the_base_frame_is_new_after_each_change_and_read_only(barrett: bh.Hand) -> None:
    hand = copy.deepcopy(barrett)
    first = hand.base
    assert first.at_origin and hand.base is first
    hand.gravity = (0.0, -9.81, 0.0)
    assert hand.base is not first
    np.testing.assert_array_equal(hand.base.gravity, (0.0, -9.81, 0.0))
    hand.base_placement = pin.SE3(pin.utils.rotate("x", np.pi / 2), np.array([0.1, 0.0, 0.0]))
    assert not hand.base.at_origin
    np.testing.assert_allclose(hand.base.gravity, (0.0, 0.0, 9.81), atol=1e-12)  # gravity in base coordinates
    with pytest.raises(ValueError):
        hand.base.rotation[0, 0] = 2.0
