"""The compiled finger kernels (src/workspace.cpp: FingerDynamics) against their Python twins.

Truths: the twins in bhgrasp.controllers._workspace_terms: _finger_terms_python (the hand's methods, Pinocchio's
Python API; equal to the bit), _workspace_dynamics and _fingertip_torque (NumPy's SVD, inverse and products: equal to
round-off, 1e-12 relative, on configurations with cond(J_t) < 100), so that the controllers built on them give the
same torques, to round-off, with and without the compiled core; and the identities the workspace dynamics must
satisfy: M_x = (J_t M_f^-1 J_t^T)^-1 for the square task Jacobian, B orthonormal with J_f = B J_t
(tests/test_controllers.py checks the RNEA identity).
"""

from __future__ import annotations

import copy
import pickle

import numpy as np
import pinocchio as pin
import pytest

import bhgrasp as bh
from bhgrasp._native import core_loads
from bhgrasp.controllers import WorkspaceComputedTorque, workspace_dynamics
from bhgrasp.controllers._workspace_terms import (
    _finger_terms,
    _finger_terms_python,
    _fingertip_torque,
    _kernel,
    _workspace_dynamics,
    workspace_terms,
)
from bhgrasp.controllers.impedance import ForceImpedance
from bhgrasp.controllers.impedance_controller import ImpedanceController
from bhgrasp.errors import InputError
from bhgrasp.model.planar import thesis_impedance_finger, thesis_one_link_finger
from bhgrasp.motion.trajectories import Constant
from bhgrasp.scenarios import finger_press, press_fitness

RELATIVE = 1e-12
MAX_CONDITION = 100.0
FIELDS = ("basis", "jacobian", "mass", "coriolis", "gravity")

pytestmark = pytest.mark.skipif(not core_loads(), reason="bhgrasp._core is not built")


def hands():
    yield bh.BarrettHand()
    yield bh.BarrettHand().perturbed(0.7, payload=("F1_tip", 0.05))
    tilted = bh.BarrettHand()
    tilted.base_placement = pin.SE3(pin.exp3(np.array([0.4, -1.2, 0.3])), np.array([0.1, 0.0, 0.2]))
    yield tilted  # model frame turned and moved: positions, Jacobians, bias accelerations and gravity change frame
    yield thesis_impedance_finger()  # two joints: the tip moves in a plane
    yield thesis_one_link_finger()  # one joint: along a line


HANDS = list(hands())
IDS = ["barrett", "perturbed", "tilted", "planar", "one-link"]


def no_kernel(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr("bhgrasp.controllers._workspace_terms._kernel", lambda hand: None)


@pytest.mark.parametrize("hand", HANDS, ids=IDS)
def test_finger_terms_are_the_python_twin_to_the_bit(hand: bh.Hand) -> None:
    rng = np.random.default_rng(0)
    for _ in range(200):
        q, v = hand.random_configuration(rng), rng.normal(size=hand.nv)
        for number, finger in enumerate(hand.fingers):
            compiled = _finger_terms(hand, q, v, finger, number)
            python = _finger_terms_python(hand, q, v, finger, number)
            for got, expected in zip(compiled, python, strict=True):
                assert got.shape == expected.shape
                np.testing.assert_array_equal(got, expected)


def well_conditioned(hand: bh.Hand, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray, str]:
    while True:
        q = hand.random_configuration(rng)
        finger = hand.fingers[rng.integers(len(hand.fingers))]
        singular = np.linalg.svd(hand.fingertip_jacobian(q, finger)[:, hand.finger_indices(finger)], compute_uv=False)
        if singular[-1] > singular[0] / MAX_CONDITION:
            return q, rng.normal(size=hand.nv), finger


def assert_close(got: np.ndarray, expected: np.ndarray, what: str) -> None:
    scale = max(1.0, float(np.abs(expected).max(initial=0.0)))
    np.testing.assert_allclose(got, expected, rtol=0, atol=RELATIVE * scale, err_msg=what)


@pytest.mark.parametrize("hand", HANDS, ids=IDS)
def test_the_workspace_mass_is_the_inverse_of_the_projected_inverse_mass(hand: bh.Hand) -> None:
    """M_x = J_t^-T M_f J_t^-1 = (J_t M_f^-1 J_t^T)^-1 (square J_t); B is orthonormal and J_f = B J_t."""
    rng = np.random.default_rng(1)
    for _ in range(50):
        q, v, finger = well_conditioned(hand, rng)
        index = hand.finger_indices(finger)
        dyn = workspace_dynamics(hand, q, v, finger)
        mass_f = hand.mass_matrix(q)[np.ix_(index, index)]
        assert_close(dyn.mass, np.linalg.inv(dyn.jacobian @ np.linalg.solve(mass_f, dyn.jacobian.T)), "M_x")
        assert_close(dyn.basis.T @ dyn.basis, np.eye(len(index)), "B^T B")
        assert_close(dyn.basis @ dyn.jacobian, hand.fingertip_jacobian(q, finger)[:, index], "B J_t")


@pytest.mark.parametrize("hand", HANDS, ids=IDS)
def test_the_workspace_terms_are_the_python_twin_to_round_off(hand: bh.Hand) -> None:
    """FingerDynamics.workspace (Eigen's SVD, inverse and products) is _workspace_dynamics (NumPy's), field by field."""
    rng = np.random.default_rng(2)
    names = ("position", "jacobian", "basis", "task_jacobian", "mass", "coriolis", "gravity")
    for _ in range(100):
        q, v, finger = well_conditioned(hand, rng)
        index, number = hand.finger_indices(finger), hand.fingers.index(finger)
        compiled = workspace_terms(hand, q, v, finger, index, number)
        python = _workspace_dynamics(hand, q, v, finger, index, number)
        assert not compiled.singular and not python.singular
        for name in names:
            got, expected = getattr(compiled, name), getattr(python, name)
            assert got.shape == expected.shape, name
            assert_close(got, expected, name)


@pytest.mark.parametrize("hand", HANDS, ids=IDS)
def test_the_fingertip_torque_is_the_python_twin_to_round_off(hand: bh.Hand) -> None:
    """WorkspaceTerms.torque (src: fingertip_torque) is _fingertip_torque for random references and SPD gains."""
    rng = np.random.default_rng(3)
    for _ in range(100):
        q, v, finger = well_conditioned(hand, rng)
        index, number = hand.finger_indices(finger), hand.fingers.index(finger)
        compiled = workspace_terms(hand, q, v, finger, index, number)
        python = _workspace_dynamics(hand, q, v, finger, index, number)
        root = rng.normal(size=(2, 3, 3))
        kp, kv = (r @ r.T + np.eye(3) for r in root)
        x_d, xd_d, xdd_d = python.position + 0.01 * rng.normal(size=3), rng.normal(size=3), rng.normal(size=3)
        args = (v[index], x_d, xd_d, xdd_d, kp, kv)
        assert_close(compiled.torque(*args), _fingertip_torque(python, *args), "tau_f")
        np.testing.assert_array_equal(python.torque(*args), _fingertip_torque(python, *args))


def test_the_kernel_checks_the_torque_sizes() -> None:
    hand = bh.BarrettHand()
    q, v = hand.configuration(F3_proximal=0.6, F3_distal=0.4), np.zeros(hand.nv)
    terms = workspace_terms(hand, q, v, "F3", hand.finger_indices("F3"), 2)
    reference, gains = (np.zeros(3),) * 3, (np.eye(3),) * 2
    for wrong in (np.zeros(3), np.zeros(1)):  # joint velocities of another size than the finger's 2
        with pytest.raises(ValueError, match="fingertip_torque: terms of a regular configuration, velocity of size"):
            terms.torque(wrong, *reference, *gains)


@pytest.mark.parametrize("hand", HANDS, ids=IDS)
def test_workspace_dynamics_with_and_without_the_kernel_agree_to_round_off(
    hand: bh.Hand, monkeypatch: pytest.MonkeyPatch
) -> None:
    rng = np.random.default_rng(2)
    cases = [well_conditioned(hand, rng) for _ in range(50)]
    compiled = [workspace_dynamics(hand, *case) for case in cases]
    no_kernel(monkeypatch)
    for case, got in zip(cases, compiled, strict=True):
        expected = workspace_dynamics(hand, *case)
        for name in FIELDS:
            assert_close(getattr(got, name), getattr(expected, name), name)


def test_the_controller_gives_the_same_torques_without_the_kernel(monkeypatch: pytest.MonkeyPatch) -> None:
    hand = bh.BarrettHand()
    q = hand.configuration(F1_proximal=0.6, F1_distal=0.5, F3_proximal=0.4, F3_distal=0.8)
    tips = hand.fingertip_positions(q)
    controller = WorkspaceComputedTorque(hand, {"F1": Constant(tips[0] + 0.01), "F3": Constant(tips[2])})
    states = [bh.State(0.01 * k, q + 0.02 * k, np.linspace(-0.5, 0.5, hand.nv) * k) for k in range(5)]
    controller.reset(states[0])
    compiled = [(controller(s.t, s), dict(controller.log)) for s in states]
    no_kernel(monkeypatch)
    controller.reset(states[0])
    for state, (tau, log) in zip(states, compiled, strict=True):
        assert_close(controller(state.t, state), tau, "tau")
        for key, value in controller.log.items():
            assert_close(log[key], value, key)


def test_the_impedance_controller_gives_the_same_torques_without_the_kernel(monkeypatch: pytest.MonkeyPatch) -> None:
    """In lockstep: the Python twin, fed the states of the compiled controller's run, gives its torques and logs."""
    setup = press_fitness.cached_f3_setup(press_fitness.TUNING_SPRING)

    def controller() -> ImpedanceController:
        law = ForceImpedance(
            Constant(setup.tip0),
            setup.normal,
            6.0,
            setup.surface_point(),
            setup.k_e,
            mass=0.01,
            stiffness=100.0,
            period=finger_press.DT,
        )
        return ImpedanceController(setup.hand, {"F3": law}, *finger_press.F3_GAINS)

    compiled, steps = controller(), []

    def recording(t: float, state: bh.State) -> np.ndarray:
        tau = compiled(t, state)
        steps.append((t, state, tau, {key: np.array(value) for key, value in compiled.log.items()}))
        return tau

    recording.reset = compiled.reset  # type: ignore[attr-defined]
    traj = finger_press.run(setup, recording, 0.5)  # contact at ~0.36 s
    assert traj.contact_count().max() > 0
    no_kernel(monkeypatch)
    python = controller()
    python.reset(steps[0][1])
    for t, state, tau, log in steps:
        assert_close(python(t, state), tau, f"tau at t = {t}")
        for key, value in python.log.items():
            assert_close(np.asarray(value, dtype=float), log[key], f"{key} at t = {t}")


@pytest.mark.parametrize("with_kernel", [True, False])
def test_a_stretched_finger_is_refused(with_kernel: bool, monkeypatch: pytest.MonkeyPatch) -> None:
    hand = thesis_impedance_finger()
    if not with_kernel:
        no_kernel(monkeypatch)
    q = np.array([0.3, 0.0])  # the two links in line: J_f of rank 1
    with pytest.raises(InputError, match=r"finger 'tip' is at a singular configuration q = \[0\.3 0\. \] \(J has rank"):
        workspace_dynamics(hand, q, np.zeros(hand.nv), "tip")
    controller = WorkspaceComputedTorque(hand, {"tip": Constant(hand.fingertip_positions(q)[0])})
    with pytest.raises(InputError, match="singular configuration"):
        controller(0.0, bh.State(0.0, q, np.zeros(hand.nv)))


def test_base_placement_and_gravity_changes_reach_the_kernel() -> None:
    hand = bh.BarrettHand()
    rng = np.random.default_rng(3)
    q, v, finger = well_conditioned(hand, rng)
    number = hand.fingers.index(finger)
    before = _finger_terms(hand, q, v, finger, number)  # builds the kernel
    hand.base_placement = pin.SE3(pin.exp3(np.array([0.0, 0.7, 0.0])), np.array([0.0, 0.3, 0.0]))
    hand.gravity = (0.0, 9.81, 0.0)
    after = _finger_terms(hand, q, v, finger, number)
    for got, expected in zip(after, _finger_terms_python(hand, q, v, finger, number), strict=True):
        np.testing.assert_array_equal(got, expected)
    assert not np.array_equal(after[0], before[0]) and not np.array_equal(after[3], before[3])
    index = hand.finger_indices(finger)
    compiled, python = (
        workspace_terms(hand, q, v, finger, index, number),
        _workspace_dynamics(hand, q, v, finger, index, number),
    )
    for name in ("position", "jacobian", "basis", "gravity"):
        assert_close(getattr(compiled, name), getattr(python, name), name)


def test_copies_and_pickles_of_a_hand_get_their_own_kernel() -> None:
    hand = bh.BarrettHand()
    q, v = hand.configuration(F2_proximal=0.5, F2_distal=0.7), np.full(hand.nv, 0.3)
    expected = workspace_dynamics(hand, q, v, "F2")
    for other in (copy.deepcopy(hand), pickle.loads(pickle.dumps(hand))):
        got = workspace_dynamics(other, q, v, "F2")
        assert _kernel(other) is not _kernel(hand)
        for name in FIELDS:
            np.testing.assert_array_equal(getattr(got, name), getattr(expected, name))


def test_the_kernel_checks_sizes() -> None:
    hand = bh.BarrettHand()
    kernel = _kernel(hand)
    gravity, q = hand.model.gravity.linear, hand.neutral()
    for finger, q_, v in ((3, q, q), (-1, q, q), (0, q[:5], q), (0, q, q[:5])):
        with pytest.raises(ValueError, match="a finger number 0 .. fingers - 1, q of size nq, v of size nv"):
            kernel.compute(finger, gravity, q_, v)
