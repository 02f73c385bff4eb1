"""The thesis' planar fingers against the textbook closed form, derived here by hand.

Two links in the x-y plane, point masses m1, m2 at the link ends, angles from +x (q2 relative), gravity -y.
Positions: p1 = l1 (c1, s1), p2 = p1 + l2 (c12, s12).  The Lagrangian gives (e.g. Spong, Hutchinson &
Vidyasagar, "Robot Modeling and Control", 7.4.1, with point masses):
    M11 = (m1 + m2) l1^2 + m2 l2^2 + 2 m2 l1 l2 c2,  M12 = m2 l2^2 + m2 l1 l2 c2,  M22 = m2 l2^2
    C = h [[qd2, qd1 + qd2], [-qd1, 0]],  h = -m2 l1 l2 s2   (Christoffel symbols)
    G1 = (m1 + m2) g l1 c1 + m2 g l2 c12,  G2 = m2 g l2 c12
The thesis' (2.22) has M11 with c23 where c2 belongs (and a doubled term), M21 != M12, and C with s23.
"""

from __future__ import annotations

import numpy as np
import pytest

import bhgrasp as bh
from bhgrasp.model.planar import planar_finger, thesis_impedance_finger, thesis_one_link_finger, thesis_two_link_finger

G = 9.81


def closed_form(q: np.ndarray, v: np.ndarray, l1: float, l2: float, m1: float, m2: float) -> tuple:
    c1, c2, c12, s2 = np.cos(q[0]), np.cos(q[1]), np.cos(q[0] + q[1]), np.sin(q[1])
    mass = np.array(
        [
            [(m1 + m2) * l1**2 + m2 * l2**2 + 2 * m2 * l1 * l2 * c2, m2 * l2**2 + m2 * l1 * l2 * c2],
            [m2 * l2**2 + m2 * l1 * l2 * c2, m2 * l2**2],
        ]
    )
    h = -m2 * l1 * l2 * s2
    coriolis = np.array([[h * v[1], h * (v[0] + v[1])], [-h * v[0], 0.0]])
    gravity = np.array([(m1 + m2) * G * l1 * c1 + m2 * G * l2 * c12, m2 * G * l2 * c12])
    return mass, coriolis, gravity


@pytest.mark.parametrize(
    ("factory", "params"),
    [(thesis_two_link_finger, (0.05, 0.05, 0.0579, 0.0342)), (thesis_impedance_finger, (0.5, 0.5, 1.0, 1.0))],
)
def test_two_link_matches_the_closed_form(factory, params: tuple) -> None:
    finger = factory()
    rng = np.random.default_rng(0)
    for _ in range(20):
        q, v = rng.uniform(-np.pi, np.pi, 2), rng.normal(size=2)
        mass, coriolis, gravity = closed_form(q, v, *params)
        np.testing.assert_allclose(finger.mass_matrix(q), mass, rtol=1e-12, atol=1e-15)
        np.testing.assert_allclose(finger.coriolis_matrix(q, v), coriolis, rtol=1e-10, atol=1e-14)
        np.testing.assert_allclose(finger.gravity_torques(q), gravity, rtol=1e-12, atol=1e-14)
        l1, l2 = params[:2]
        tip = [l1 * np.cos(q[0]) + l2 * np.cos(q.sum()), l1 * np.sin(q[0]) + l2 * np.sin(q.sum()), 0.0]
        np.testing.assert_allclose(finger.fingertip_positions(q)[0], tip, atol=1e-15)


def test_rod_links_use_the_slender_rod_inertia() -> None:
    """One uniform rod about its end: M = m l^2 / 3, G = m g (l / 2) cos(q)."""
    rod = planar_finger((0.3,), (2.0,), rods=True)
    q = np.array([0.4])
    np.testing.assert_allclose(rod.mass_matrix(q), [[2.0 * 0.3**2 / 3]])
    np.testing.assert_allclose(rod.gravity_torques(q), [2.0 * G * 0.15 * np.cos(0.4)])


def test_one_link_pendulum_swings_at_its_analytic_period() -> None:
    """Small oscillations of a point mass on a massless link: period 2 pi sqrt(l / g)."""
    pendulum = thesis_one_link_finger()
    q, v, dt, t = np.array([-np.pi / 2 + 0.01]), np.zeros(1), 1e-4, 0.0
    crossings = []
    while len(crossings) < 3:
        a = pendulum.forward_dynamics(q, v, np.zeros(1))
        v_new = v + dt * a
        q_new = q + dt * v_new
        if (q[0] + np.pi / 2) * (q_new[0] + np.pi / 2) < 0:
            crossings.append(t)
        q, v, t = q_new, v_new, t + dt
    period = 2 * (crossings[2] - crossings[1])
    assert period == pytest.approx(2 * np.pi * np.sqrt(0.2 / G), rel=1e-3)


def test_planar_finger_is_a_hand_with_one_fingertip() -> None:
    finger = thesis_two_link_finger()
    assert isinstance(finger, bh.Hand)
    assert finger.fingers == ("tip",) and finger.joint_names == ("joint1", "joint2")
    assert finger.finger_joints("tip") == ("joint1", "joint2")


def test_invalid_planar_parameters_raise() -> None:
    with pytest.raises(bh.InputError, match="masses"):
        planar_finger((0.1, 0.1), (1.0,))
    with pytest.raises(bh.InputError, match=r"lengths\[1\]"):
        planar_finger((0.1, -0.1), (1.0, 1.0))
    with pytest.raises(bh.InputError, match="`masses` must be finite"):
        planar_finger((0.1,), (float("nan"),))
