"""The compiled sensing, contact-frame and object-regressor kernels (src/sensing.cpp) against their NumPy twins.

Truths: the twins (bhgrasp.grasp.sensing.ContactSensing._fingers_python, adaptive_grasp.object_regressor_python), and
for the regressor also its defining identity Y_o sigma_o = M_o a_r + C_o(omega) v_r + N_o written out with the
world inertia.  The kernels sum in another order than NumPy's einsum and BLAS, so they agree to a few ulps:
1e-14 relative to the largest magnitude involved.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pinocchio as pin
import pytest

import bhgrasp as bh
from bhgrasp._native import core_loads
from bhgrasp.controllers.adaptive_grasp import object_parameters, object_regressor, object_regressor_python
from bhgrasp.errors import InputError
from bhgrasp.grasp.frames import _unit_normals, contact_frames, unit_normal_frames
from bhgrasp.grasp.sensing import ContactSensing
from bhgrasp.scenarios.hold import reference_hold

RELATIVE = 1e-14

pytestmark = pytest.mark.skipif(not core_loads(), reason="bhgrasp._core is not built")


def random_state(rng: np.random.Generator, hand: bh.Hand, m: int) -> bh.State:
    """m contacts on random links (palm and finger links), some pulling (n . f < 0), some with equal weights."""
    links = [
        "palm",
        "palm_surface",
        *[f"{finger}_{part}_link" for finger in hand.fingers for part in ("knuckle", "proximal", "distal")],
    ]
    links = [link for link in links if hand.model.existFrame(link)]
    normals = rng.normal(size=(m, 3))
    normals /= np.linalg.norm(normals, axis=1)[:, None]
    forces = rng.normal(scale=3.0, size=(m, 3))
    if m >= 2:  # a tie: two contacts of one link pressing equally hard
        normals[1], forces[1] = normals[0], forces[0]
    bodies = tuple((links[rng.integers(len(links))], "box") for _ in range(m))
    if m >= 2:
        bodies = (bodies[0], bodies[0], *bodies[2:])
    return bh.State(
        0.0,
        hand.neutral(),
        np.zeros(hand.nv),
        contact_points=rng.normal(scale=0.05, size=(m, 3)),
        contact_normals=normals,
        contact_forces=forces,
        contact_bodies=bodies,
    )


def assert_same_fingers(sensing: ContactSensing, state: bh.State, body: str | None = None) -> None:
    compiled, python = sensing.fingers(state, body), sensing._fingers_python(state, body)
    assert list(compiled) == list(python)
    scale = max(1.0, float(np.abs(state.contact_forces).max(initial=0.0)))
    for finger, expected in python.items():
        got = compiled[finger]
        assert (got.count, got.link, got.touching) == (expected.count, expected.link, expected.touching), finger
        for name in ("force", "normal", "point"):
            np.testing.assert_allclose(getattr(got, name), getattr(expected, name), rtol=0, atol=RELATIVE * scale)
        assert abs(got.normal_force - expected.normal_force) <= RELATIVE * scale


@pytest.mark.parametrize("m", [0, 1, 2, 3, 5, 9])
def test_finger_sums_match_the_numpy_twin(m: int) -> None:
    hand = bh.BarrettHand()
    sensing = ContactSensing(hand)
    rng = np.random.default_rng(m)
    for _ in range(50):
        assert_same_fingers(sensing, random_state(rng, hand, m))


@pytest.mark.parametrize("m", [0, 1, 4, 9])
def test_finger_sums_of_one_body_are_those_of_its_rows_alone(m: int) -> None:
    """``fingers(state, body)``: exactly (to the bit) the sums of a state holding only ``body``'s rows."""
    hand = bh.BarrettHand()
    sensing = ContactSensing(hand)
    rng = np.random.default_rng(10 + m)
    for _ in range(20):
        state = random_state(rng, hand, m)
        bodies = tuple((link, "box" if rng.random() < 0.5 else "table") for link, _ in state.contact_bodies)
        state = replace(state, contact_bodies=bodies)
        rows = [k for k, (_, other) in enumerate(bodies) if other == "box"]
        alone = replace(
            state,
            contact_points=state.contact_points[rows],
            contact_normals=state.contact_normals[rows],
            contact_forces=state.contact_forces[rows],
            contact_bodies=tuple(bodies[k] for k in rows),
        )
        assert_same_fingers(sensing, state, "box")  # the twins agree with the body given, too
        for fingers in (sensing.fingers, sensing._fingers_python):
            got, expected = fingers(state, "box"), fingers(alone)
            for finger, contact in expected.items():
                assert (got[finger].count, got[finger].link) == (contact.count, contact.link)
                for name in ("force", "normal", "point", "normal_force"):
                    np.testing.assert_array_equal(getattr(got[finger], name), getattr(contact, name))


def test_finger_sums_match_along_a_held_grasp() -> None:
    hold = reference_hold()
    sensing = ContactSensing(hold.simulator.scene.hand)
    state = hold.state
    for _ in range(300):
        state, _ = hold.simulator.step(state, hold.controller(state.t, state))
        assert_same_fingers(sensing, state)
    assert all(contact.touching for contact in sensing.fingers(state).values())


@pytest.mark.parametrize("moved", [False, True])
def test_reaction_torques_match_the_numpy_twin(moved: bool) -> None:
    hand = bh.BarrettHand()
    if moved:
        hand.base_placement = pin.SE3(pin.exp3(np.array([0.4, -1.2, 0.3])), np.array([0.1, 0.0, 0.2]))
    sensing = ContactSensing(hand)
    rng = np.random.default_rng(7)
    for m in (1, 2, 3, 5, 9):
        for _ in range(20):
            state = random_state(rng, hand, m)
            state = replace(state, q=hand.random_configuration(rng))
            expected = sensing._reaction_torques_python(state)
            scale = max(1.0, float(np.abs(expected).max()))
            np.testing.assert_allclose(sensing.reaction_torques(state), expected, rtol=0, atol=RELATIVE * scale)
    assert not np.any(sensing.reaction_torques(random_state(rng, hand, 0)))


def test_reaction_torques_refuse_a_non_finite_point() -> None:
    hand = bh.BarrettHand()
    state = random_state(np.random.default_rng(8), hand, 2)
    state.contact_points[1, 2] = np.nan
    with pytest.raises(InputError, match="points"):
        ContactSensing(hand).reaction_torques(state)


def test_a_finger_that_only_pulls_has_no_strongest_link() -> None:
    hand = bh.BarrettHand()
    state = bh.State(
        0.0,
        hand.neutral(),
        np.zeros(hand.nv),
        contact_points=np.array([[0.01, 0.0, 0.1]]),
        contact_normals=np.array([[0.0, 0.0, 1.0]]),
        contact_forces=np.array([[0.5, 0.0, -2.0]]),
        contact_bodies=(("F1_distal_link", "box"),),
    )
    contact = ContactSensing(hand).fingers(state)["F1"]
    assert contact.count == 1 and contact.link is None and not contact.touching
    np.testing.assert_array_equal(contact.normal, [0.0, 0.0, 1.0])
    np.testing.assert_array_equal(contact.point, np.zeros(3))
    assert contact.normal_force == -2.0


def regressor_truth(rotation, twist, v_r, a_r, gravity, sigma) -> np.ndarray:
    """M_o a_r + C_o v_r + N_o with I_w = R I R^T and C = (skew(w) I_w - I_w skew(w) - skew(I_w w)) / 2."""
    mass, inertia = (
        sigma[0],
        np.array([[sigma[1], sigma[2], sigma[3]], [sigma[2], sigma[4], sigma[5]], [sigma[3], sigma[5], sigma[6]]]),
    )
    world = rotation @ inertia @ rotation.T
    omega = twist[3:]
    coriolis = 0.5 * (pin.skew(omega) @ world - world @ pin.skew(omega) - pin.skew(world @ omega))
    return np.concatenate((mass * (a_r[:3] - gravity), world @ a_r[3:] + coriolis @ v_r[3:]))


def test_object_regressor_matches_its_twin_and_its_definition() -> None:
    rng = np.random.default_rng(7)
    gravity = np.array([0.0, 0.0, -9.81])
    for _ in range(200):
        rotation = pin.exp3(rng.normal(size=3))
        twist, v_r, a_r = rng.normal(size=6), rng.normal(size=6), rng.normal(scale=5.0, size=6)
        compiled = object_regressor(rotation, twist, v_r, a_r, gravity)
        python = object_regressor_python(rotation, twist, v_r, a_r, gravity)
        scale = max(1.0, float(np.abs(python).max()))
        np.testing.assert_allclose(compiled, python, rtol=0, atol=RELATIVE * scale)
        inertia = np.diag(rng.uniform(1e-4, 1e-3, size=3))
        sigma = object_parameters(rng.uniform(0.1, 1.0), rotation.T @ inertia @ rotation)
        np.testing.assert_allclose(
            compiled @ sigma, regressor_truth(rotation, twist, v_r, a_r, gravity, sigma), rtol=0, atol=RELATIVE * scale
        )


def test_contact_frames_match_the_numpy_twin() -> None:
    """Random normals of any length, some across the tangent switch |n_x| = 0.9, the axes themselves."""
    rng = np.random.default_rng(3)
    normals = rng.normal(size=(500, 3)) * rng.uniform(1e-3, 1e3, size=(500, 1))
    normals[:50] = np.c_[np.full(50, 0.9), rng.normal(scale=1e-3, size=(50, 2))]  # at the switch
    normals[50:56] = np.vstack((np.eye(3), -np.eye(3)))
    compiled = contact_frames(normals)
    np.testing.assert_allclose(compiled, unit_normal_frames(_unit_normals(normals)), rtol=0, atol=RELATIVE)
    np.testing.assert_allclose(
        compiled.transpose(0, 2, 1) @ compiled, np.broadcast_to(np.eye(3), (500, 3, 3)), rtol=0, atol=RELATIVE
    )
    np.testing.assert_allclose(np.linalg.det(compiled), 1.0, rtol=0, atol=RELATIVE)


def test_a_zero_normal_is_named() -> None:
    with pytest.raises(InputError, match=r"zero normal at contact index \[1\]"):
        contact_frames([[0.0, 0.0, 1.0], [0.0, 0.0, 0.0], [1.0, 0.0, 0.0]])
