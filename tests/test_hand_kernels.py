"""The compiled hand dynamics (src/dynamics.cpp: HandDynamics) against Pinocchio's Python API.

Truths: the NumPy twin (hand_dynamics._slotine_li_torque_python, the same three RNEA passes: equal to the bit), and the
defining identity M a + C(q, v) v + G = RNEA(q, v, a) when the reference velocity is the velocity itself.
"""

from __future__ import annotations

import copy
import pickle

import numpy as np
import pinocchio as pin
import pytest

import bhgrasp as bh
from bhgrasp._native import core_loads
from bhgrasp.model import hand_dynamics
from bhgrasp.scenarios.allegro_grasp import allegro_hand

pytestmark = pytest.mark.skipif(not core_loads(), reason="bhgrasp._core is not built")


def hands():
    yield bh.BarrettHand()
    yield bh.BarrettHand().perturbed(0.7, payload=("F1_tip", 0.05))
    tilted = bh.BarrettHand()
    tilted.base_placement = pin.SE3(pin.exp3(np.array([0.4, -1.2, 0.3])), np.array([0.1, 0.0, 0.2]))
    yield tilted  # gravity in the model frame turns with the base
    yield allegro_hand()


@pytest.mark.parametrize("hand", list(hands()), ids=["barrett", "perturbed", "tilted", "allegro"])
def test_slotine_li_torque_is_the_python_twin_to_the_bit(hand: bh.Hand) -> None:
    rng = np.random.default_rng(0)
    for _ in range(200):
        q = pin.randomConfiguration(hand.model)
        v, v_r, a_r = (rng.normal(size=hand.nv) for _ in range(3))
        compiled = hand.slotine_li_torque(q, v, v_r, a_r)
        np.testing.assert_array_equal(compiled, hand_dynamics._slotine_li_torque_python(hand, q, v, v_r, a_r))
        truth = pin.rnea(hand.model, hand.model.createData(), q, v, a_r)
        np.testing.assert_allclose(
            hand.slotine_li_torque(q, v, v, a_r), truth, rtol=0, atol=1e-12 * max(1.0, np.abs(truth).max())
        )


@pytest.mark.parametrize("hand", list(hands()), ids=["barrett", "perturbed", "tilted", "allegro"])
def test_the_kernels_inverse_dynamics_is_pinocchios_rnea_to_the_bit(hand: bh.Hand) -> None:
    """What the compiled approach takes for ComputedTorque's pin.rnea: random states, signed zeros, gravity."""
    rng = np.random.default_rng(2)
    kernel, gravity = hand.compiled_dynamics(), hand.model.gravity.linear
    for k in range(200):
        q = pin.randomConfiguration(hand.model)
        v, a = rng.normal(size=hand.nv), rng.normal(size=hand.nv)
        if k % 4 == 0:
            v[::2], a[1::2] = -0.0, -0.0
        truth = pin.rnea(hand.model, hand.data, q, v, a)
        assert kernel.inverse_dynamics(gravity, q, v, a).tobytes() == truth.tobytes()


def test_a_changed_gravity_reaches_the_kernel() -> None:
    hand = bh.BarrettHand()
    q, zero = hand.configuration(F1_proximal=0.7), np.zeros(hand.nv)
    hand.slotine_li_torque(q, zero, zero, zero)  # builds the kernel
    hand.gravity = (0.0, 9.81, 0.0)
    np.testing.assert_array_equal(hand.slotine_li_torque(q, zero, zero, zero), hand.gravity_torques(q))


def test_copies_and_pickles_of_a_hand_rebuild_the_kernel() -> None:
    hand = bh.BarrettHand()
    q, v = hand.configuration(F2_proximal=0.5), np.full(hand.nv, 0.3)
    expected = hand.slotine_li_torque(q, v, v, v)
    for other in (copy.deepcopy(hand), pickle.loads(pickle.dumps(hand))):
        np.testing.assert_array_equal(other.slotine_li_torque(q, v, v, v), expected)
