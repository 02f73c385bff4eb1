"""The grasp kernels of the object-space laws against independent truths: P_dot against central differences of P,
J_h against the hand's point Jacobians, on the reference hold, random configurations, a moved base and the Allegro.

Tolerances: a central difference of P with step h carries round-off ~ eps |P| / h and truncation h^2 |P'''| / 6;
with h = 1e-6 s, |P| <= ~100 and eps = 2.2e-16 the round-off is ~2e-8 and the truncation below 1e-10, so the
analytic P_dot must agree to 50 eps max|P| / h (about 1e-7 here) plus 1e-8 relative to max|P_dot|.

The compiled kernel (src/grasp.cpp, used by ``contact_kinematics``) against its Python twin
(``contact_kinematics_python``): all five maps to 1e-12 relative to their largest entry, for condition numbers
kappa <= 10 of J (its singular values that the pseudo-inverse keeps), and 1e-12 kappa / 10 beyond.  The two compute
the pseudo-inverse with different backward-stable SVDs (LAPACK's divide and conquer in NumPy, Eigen's two-sided
Jacobi), which agree to a few eps kappa; the Jacobians differ in summation order (the moved base's action, the lever
arms).  Over 1,200 random grasps of the three hands below the largest disagreement was 120 eps kappa (kappa 5),
and at most 1e-12 for kappa < 100.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import bhgrasp as bh
import bhgrasp.grasp.kinematics as kinematics_module
from bhgrasp import _native
from bhgrasp.grasp import ObjectState, contact_frames, contact_kinematics, contact_kinematics_python, grasp_kinematics
from bhgrasp.model.mount import mounted
from bhgrasp.scenarios.allegro_grasp import allegro_hand
from bhgrasp.scenarios.hold import reference_hold

STEP = 1e-6  # [s] of the central differences
EPS = np.finfo(float).eps


@pytest.fixture(scope="module")
def held():
    """The reference three-finger hold: hand, q, box, pose, contacts (object body frame), links."""
    hold = reference_hold()
    state = hold.state
    pose = state.object_poses[0]
    points_body = (state.contact_points - pose.translation) @ pose.rotation
    normals_body = state.contact_normals @ pose.rotation
    links = [a for a, _ in state.contact_bodies]
    return hold.simulator.scene.hand, state.q, hold.simulator.scene.objects[0], pose, points_body, normals_body, links


def random_twist(rng):
    return np.concatenate((0.05 * rng.normal(size=3), 0.5 * rng.normal(size=3)))  # [m/s], [rad/s]


def central_difference(hand, q, obj, points, normals, links, step=STEP):
    """(P(t + h) - P(t - h)) / 2h, the object advanced at its twist and the joints at q_dot = P x_dot."""
    q_dot = grasp_kinematics(hand, q, obj, points, normals, links).joint_map @ obj.twist
    ahead = grasp_kinematics(
        hand, pin.integrate(hand.model, q, step * q_dot), obj.advanced(step), points, normals, links
    )
    behind = grasp_kinematics(
        hand, pin.integrate(hand.model, q, -step * q_dot), obj.advanced(-step), points, normals, links
    )
    return (ahead.joint_map - behind.joint_map) / (2.0 * step)


def assert_rate_matches(kinematics, numeric, step=STEP):
    scale = np.max(np.abs(kinematics.joint_map))
    tolerance = 50.0 * EPS * scale / step + 1e-8 * np.max(np.abs(numeric))
    error = np.max(np.abs(kinematics.joint_map_rate - numeric))
    assert error < tolerance, f"|P_dot - central difference| = {error:.3g} > {tolerance:.3g}"


def moved(hand_factory):
    """A hand whose base is rotated and shifted in the world (the kinematics must carry the placement)."""
    hand = hand_factory()
    hand.base_placement = pin.SE3(pin.exp3(np.array([0.3, -0.5, 0.8])), np.array([0.1, -0.2, 0.05]))
    return hand


@pytest.mark.parametrize("fingers", [("F1", "F2", "F3"), ("F1", "F2")])
@pytest.mark.parametrize("seed", range(3))
def test_joint_map_rate_is_the_derivative_of_the_joint_map_on_the_hold(held, fingers, seed):
    """Three contacts: J (9, 8) full column rank; two: J (6, 8) full row rank (the null-space term of d(J^+))."""
    hand, q, box, pose, points, normals, links = held
    keep = [i for i, link in enumerate(links) if link.startswith(fingers)]
    obj = ObjectState(
        box.mass, box.inertia, pose.translation.copy(), pose.rotation.copy(), random_twist(np.random.default_rng(seed))
    )
    args = (hand, q, obj, points[keep], normals[keep], [links[i] for i in keep])
    assert_rate_matches(grasp_kinematics(*args), central_difference(*args))


HANDS = {
    "barrett": (bh.BarrettHand, None),
    "barrett-moved": (lambda: moved(bh.BarrettHand), None),
    # J (9, 8) of rank 7 whose left null vector (F1's plane normal) turns with F1's spread: every term of d(J^+)
    "barrett-proximal": (bh.BarrettHand, ["F1_proximal_link", "F2_distal_link", "F3_distal_link"]),
    "allegro": (allegro_hand, None),
}


@pytest.mark.filterwarnings("ignore:URDF .* no rigid body has the inertias")
@pytest.mark.parametrize("case", HANDS)
@pytest.mark.parametrize("seed", range(3))
def test_grasp_kinematics_agree_with_independent_truths_at_random_configurations(case, seed):
    """Points on the links near their frames (the fingertips by default), any normals, object pose and twist: P_dot
    against central differences, J_h against the hand's point Jacobians (Pinocchio frame Jacobians), J_h^+ and P
    against numpy's pinv."""
    factory, links = HANDS[case]
    hand = factory()
    rng = np.random.default_rng(seed)
    q = hand.random_configuration(rng)
    links = links or list(hand.fingertip_frames.values())[:3]
    points = np.array([hand.frame_placement(q, link).translation for link in links]) + 0.01 * rng.normal(size=(3, 3))
    normals = rng.normal(size=(3, 3))
    com = points.mean(axis=0) + 0.01 * rng.normal(size=3)
    rotation = pin.exp3(rng.normal(size=3))
    obj = ObjectState(0.3, np.diag([1e-4, 2e-4, 3e-4]), com, rotation, random_twist(rng))
    args = (hand, q, obj, (points - com) @ rotation, normals @ rotation, links)
    kinematics = grasp_kinematics(*args)
    assert_rate_matches(kinematics, central_difference(*args))
    np.testing.assert_allclose(
        kinematics.hand_jacobian, bh.hand_jacobian(hand, q, points, links, normals), rtol=0.0, atol=1e-14
    )
    np.testing.assert_allclose(kinematics.grasp_map, bh.grasp_map(points, normals, com), rtol=0.0, atol=1e-14)
    pinv = np.linalg.pinv(kinematics.hand_jacobian)
    np.testing.assert_allclose(kinematics.hand_jacobian_pinv, pinv, rtol=0.0, atol=1e-10 * np.max(np.abs(pinv)))
    np.testing.assert_allclose(
        kinematics.joint_map, pinv @ kinematics.grasp_map.T, rtol=0.0, atol=1e-10 * np.max(np.abs(kinematics.joint_map))
    )


def test_central_difference_error_shrinks_with_the_step_as_expected(held):
    """Down to the round-off floor the error of the central difference falls as h^2: the analytic P_dot is the
    limit, not merely close to one step's difference."""
    hand, q, box, pose, points, normals, links = held
    obj = ObjectState(
        box.mass,
        box.inertia,
        pose.translation.copy(),
        pose.rotation.copy(),
        np.array([0.02, -0.01, 0.03, 2.0, -1.0, 1.5]),
    )
    kinematics = grasp_kinematics(hand, q, obj, points, normals, links)
    errors = [
        np.max(np.abs(kinematics.joint_map_rate - central_difference(hand, q, obj, points, normals, links, h)))
        for h in (1e-2, 5e-3)
    ]
    assert errors[1] < 0.3 * errors[0]  # h^2: a quarter
    assert errors[1] > 1e3 * np.max(np.abs(kinematics.joint_map)) * EPS / 5e-3  # truncation, not round-off


def test_unknown_link_names_are_rejected_with_the_valid_ones(held):
    hand, q, box, pose, points, normals, links = held
    obj = ObjectState(box.mass, box.inertia, pose.translation, pose.rotation, np.zeros(6))
    with pytest.raises(bh.InputError, match="unknown frame 'F9_distal_link'; valid frames: "):
        grasp_kinematics(hand, q, obj, points, normals, [*links[:-1], "F9_distal_link"])


MAPS = ("joint_map", "joint_map_rate", "grasp_map", "hand_jacobian", "hand_jacobian_pinv")


def assert_twins_agree(hand, q, obj, points, frames, joints):
    """The compiled kernel and its Python twin agree on all five maps (tolerance: module docstring)."""
    assert kinematics_module.grasp_kinematics_kernel(hand) is not None, (
        "bhgrasp._core does not load: nothing compiled to compare"
    )
    compiled = contact_kinematics(hand, q, obj, points, frames, joints)
    python = contact_kinematics_python(hand, q, obj, points, frames, joints)
    singular = np.linalg.svd(python.hand_jacobian, compute_uv=False)
    kept = singular[singular > 1e-15 * singular[0]]
    tolerance = 1e-12 * max(1.0, kept[0] / kept[-1] / 10.0)
    for name in MAPS:
        ours, twin = getattr(compiled, name), getattr(python, name)
        assert ours.shape == twin.shape, name
        error = np.max(np.abs(ours - twin)) / np.max(np.abs(twin))
        assert error < tolerance, f"{name}: compiled and Python differ by {error:.3g} relative > {tolerance:.3g}"


def world_grasp(hand, links, rng, count=3):
    """A random configuration, contact points near the links' frames, any frames, object pose and twist (world)."""
    q = hand.random_configuration(rng)
    links = links[:count]
    points = np.array([hand.frame_placement(q, link).translation for link in links]) + 0.01 * rng.normal(
        size=(count, 3)
    )
    com = points.mean(axis=0) + 0.01 * rng.normal(size=3)
    obj = ObjectState(0.3, np.diag([1e-4, 2e-4, 3e-4]), com, pin.exp3(rng.normal(size=3)), random_twist(rng))
    return q, obj, points, contact_frames(rng.normal(size=(count, 3))), kinematics_module.parent_joints(hand, links)


@pytest.mark.parametrize("fingers", [("F1", "F2", "F3"), ("F1", "F2")])
@pytest.mark.parametrize("seed", range(3))
def test_compiled_kernel_agrees_with_its_python_twin_on_the_hold(held, fingers, seed):
    hand, q, box, pose, points, normals, links = held
    keep = [i for i, link in enumerate(links) if link.startswith(fingers)]
    obj = ObjectState(
        box.mass, box.inertia, pose.translation.copy(), pose.rotation.copy(), random_twist(np.random.default_rng(seed))
    )
    points_world = pose.translation + points[keep] @ pose.rotation.T
    frames = contact_frames(normals[keep] @ pose.rotation.T)
    joints = kinematics_module.parent_joints(hand, [links[i] for i in keep])
    assert_twins_agree(hand, q, obj, points_world, frames, joints)


@pytest.mark.filterwarnings("ignore:URDF .* no rigid body has the inertias")
@pytest.mark.parametrize("case", HANDS)
@pytest.mark.parametrize("count", [3, 2])
@pytest.mark.parametrize("seed", range(4))
def test_compiled_kernel_agrees_with_its_python_twin_at_random_configurations(case, count, seed):
    factory, links = HANDS[case]
    hand = factory()
    rng = np.random.default_rng(seed)
    assert_twins_agree(hand, *world_grasp(hand, links or list(hand.fingertip_frames.values()), rng, count))


def test_compiled_kernel_reads_the_base_placement_of_each_call():
    """One kernel per hand, cached; the base may move between calls (the model may not)."""
    hand = bh.BarrettHand()
    rng = np.random.default_rng(7)
    grasp = world_grasp(hand, list(hand.fingertip_frames.values()), rng)
    assert_twins_agree(hand, *grasp)
    kernel = kinematics_module.grasp_kinematics_kernel(hand)
    before = contact_kinematics(hand, *grasp)
    hand.base_placement = pin.SE3(pin.exp3(np.array([0.3, -0.5, 0.8])), np.array([0.1, -0.2, 0.05]))
    assert_twins_agree(hand, *grasp)
    assert kinematics_module.grasp_kinematics_kernel(hand) is kernel
    assert not np.allclose(contact_kinematics(hand, *grasp).joint_map, before.joint_map)


def test_without_the_compiled_core_the_kinematics_say_so_unless_python_is_the_default(monkeypatch):
    """No silent fallback: the default engine (compiled) raises, naming the switch; BHGRASP_ENGINE=python runs the
    twin (it used to fall back to the twin without a word)."""
    hand = bh.BarrettHand()
    grasp = world_grasp(hand, list(hand.fingertip_frames.values()), np.random.default_rng(3))
    monkeypatch.setitem(__import__("sys").modules, "bhgrasp._core", None)  # import of it now fails
    monkeypatch.delattr(bh, "_core", raising=False)
    with pytest.raises(bh.CompiledEngineUnavailable, match="BHGRASP_ENGINE=python for everything"):
        contact_kinematics(hand, *grasp)
    monkeypatch.setattr(_native, "DEFAULT_ENGINE", "python")
    assert kinematics_module.grasp_kinematics_kernel(hand) is None
    python_default, python = contact_kinematics(hand, *grasp), contact_kinematics_python(hand, *grasp)
    for name in MAPS:
        np.testing.assert_array_equal(getattr(python_default, name), getattr(python, name))


def test_compiled_kernel_rejects_arrays_of_the_wrong_size():
    """The binding's own checks (the Python callers validate first): a wrong call raises, it does not read astray."""
    hand = bh.BarrettHand()
    q, obj, points, frames, joints = world_grasp(hand, list(hand.fingertip_frames.values()), np.random.default_rng(0))
    kernel = kinematics_module.grasp_kinematics_kernel(hand)
    args = (np.eye(3), np.zeros(3), q, obj.com, obj.twist, points, frames.reshape(-1, 3), joints)
    kernel.compute(*args)
    for index, wrong in (
        (2, q[:-1]),
        (5, points[:0]),
        (6, frames.reshape(-1, 3)[:-3]),
        (7, joints[:-1]),
        (7, [*joints[:-1], hand.model.njoints]),
    ):
        with pytest.raises(ValueError, match="GraspKinematics.compute|joint the model lacks"):
            kernel.compute(*args[:index], wrong, *args[index + 1 :])


@pytest.mark.parametrize("mount", [False, True], ids=["hand", "mounted"])
@pytest.mark.parametrize("seed", range(3))
def test_the_block_pseudo_inverse_gathers_contacts_that_share_joints_and_leaves_the_palm_out(mount, seed):
    """The compiled J^+ goes block by block (contacts linked by shared joints): two contacts on F1 make one block of
    six rows, F3's its own, and a contact on the palm, which no joint moves, a zero block; on a mounted hand the mount's
    joints move every contact, the palm's too, and all make one block.  Against NumPy's pinv of the whole J (the
    twin)."""
    hand = mounted(bh.BarrettHand()) if mount else bh.BarrettHand()
    links = ["F1_distal_link", "F3_distal_link", "F1_proximal_link", "palm"]
    assert_twins_agree(hand, *world_grasp(hand, links, np.random.default_rng(seed), count=4))
