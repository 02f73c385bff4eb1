"""Batched rollouts (bhgrasp.sim.batch, src/batch.cpp): N environments stepped together equal N separate runs.

The independent truth is the single-environment compiled step (itself held to the Python reference engine by
tests/test_compiled.py): a batch must reproduce each environment's separate run bit for bit, whatever the number
of threads, keep each environment's contact memory to itself, and freeze only the environments that diverge.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from scenes import PythonBarrettRules

from bhgrasp.errors import InputError
from bhgrasp.model.transmission import Transmission
from bhgrasp.scenarios.box_grasp import box_grasp
from bhgrasp.scenarios.hold import POSTURE_GAIN, SQUEEZE, reference_hold
from bhgrasp.sim import Simulator
from bhgrasp.sim.actuation import Actuation, BarrettActuation
from bhgrasp.sim.batch import BatchSimulator


def start_states(hold, n: int):
    """n different states of the reference hold, each with its own contact memory (squeezed differently)."""
    states = []
    for i in range(n):
        state = hold.state
        for _ in range(20 * i):
            state, _ = hold.simulator.step(state, hold.controller(state.t, state) * (1.0 + 0.05 * i))
        states.append(state)
    t = max(state.t for state in states)
    return [dataclasses.replace(state, t=t) for state in states]


def inputs(hold, states):
    return np.array([hold.controller(s.t, s) * (1.0 + 0.1 * i) for i, s in enumerate(states)])


@pytest.mark.parametrize("threads", [1, 2])
def test_a_batch_reproduces_separate_runs_bit_for_bit(threads: int) -> None:
    hold = reference_hold()
    states = start_states(hold, 4)
    u = inputs(hold, states)
    batch = BatchSimulator(hold.simulator, states, threads=threads)
    for _ in range(300):
        batch.step(u)
    for i, state in enumerate(states):
        for _ in range(300):
            state, info = hold.simulator.step(state, u[i])
        np.testing.assert_array_equal(batch.scene_q[i], state.scene_q)
        np.testing.assert_array_equal(batch.scene_v[i], state.scene_v)
        np.testing.assert_array_equal(batch.contacts(i).force, info.contacts.force)
        np.testing.assert_array_equal(batch.state(i).contact_memory.displacement, state.contact_memory.displacement)
        assert batch.state(i).t == pytest.approx(state.t, abs=1e-12)
    assert len(batch.contacts(0)) == 3 and not batch.diverged.any()


def test_kernels_match_the_hand_model() -> None:
    hold = reference_hold()
    states = start_states(hold, 3)
    batch = BatchSimulator(hold.simulator, states)
    gravity, jacobians = batch.gravity_torques(), batch.fingertip_jacobians(["F3", "F1"])
    assert jacobians.shape == (3, 2, 3, 8)
    for i, state in enumerate(states):
        np.testing.assert_allclose(gravity[i], hold.hand.gravity_torques(state.q), rtol=0, atol=1e-12)
        for k, finger in enumerate(["F3", "F1"]):
            np.testing.assert_allclose(jacobians[i, k], hold.hand.fingertip_jacobian(state.q, finger), atol=1e-12)


def test_a_vectorised_hold_controller_holds_the_box() -> None:
    """The reference hold's law written for the batch (gravity, posture spring, J^T squeeze) tracks the serial run."""
    hold = reference_hold()
    states = start_states(hold, 2)
    q0 = hold.state.q
    forces = np.array(list(SQUEEZE.values()))

    def controller(t, batch):
        tips = batch.fingertip_jacobians(list(SQUEEZE))
        return batch.gravity_torques() + POSTURE_GAIN * (q0 - batch.q) + np.einsum("nkij,ki->nj", tips, forces)

    batch = BatchSimulator(hold.simulator, states).run(controller, 0.5)
    for i, state in enumerate(states):
        serial = hold.simulator.run(hold.controller, 0.5, state=state, progress=False)
        np.testing.assert_allclose(batch.scene_q[i, :8], serial.q[-1], rtol=0, atol=1e-9)
        assert abs(batch.object_positions()[i, 2] - hold.box_height) < 1e-3  # held


def test_a_diverging_environment_is_frozen_and_the_others_go_on() -> None:
    hold = reference_hold()
    states = start_states(hold, 3)
    u = inputs(hold, states)
    u[1] = 1e4  # [N m] far beyond the hand: it flies apart
    batch = BatchSimulator(hold.simulator, states, threads=2)
    for _ in range(50):
        batch.step(u)
    assert batch.diverged.tolist() == [False, True, False]
    assert "speed" in batch.divergence(1) or "depth" in batch.divergence(1)
    state = states[2]
    for _ in range(50):
        state, _ = hold.simulator.step(state, u[2])
    np.testing.assert_array_equal(batch.scene_q[2], state.scene_q)


def test_batch_errors_name_the_argument() -> None:
    hold = reference_hold()
    with pytest.raises(InputError, match="`threads` must be a positive integer"):
        BatchSimulator(hold.simulator, [hold.state], threads=0)
    with pytest.raises(InputError, match="at least one start state"):
        BatchSimulator(hold.simulator, [])
    batch = BatchSimulator(hold.simulator, [hold.state, hold.state])
    with pytest.raises(InputError, match=r"`u` must have shape \(2, 8\)"):
        batch.step(np.zeros(8))
    u = np.zeros((2, 8))
    u[1, 3] = np.nan
    with pytest.raises(InputError, match=r"NaN/inf in environments \[1\]"):
        batch.step(u)
    with pytest.raises(InputError, match="unknown fingers"):
        batch.fingertip_jacobians(["F4"])
    with pytest.raises(InputError, match="`env` must be an environment index"):
        batch.state(2)

    class OneMotor(Transmission):  # one motor closing every joint: a transmission the batch does not know
        n_inputs = 1

        def matrix(self, modes=None):
            return np.ones((self.hand.nv, 1))

        def gears(self, modes=None):
            return np.ones((self.hand.nv, 1))

        def joint_damping(self, modes=None):
            return self.passive_damping.copy()

    class Gripper(Actuation):
        def joint_torques(self, u):
            return np.full(self.hand.nv, u[0])

    gripper = Simulator(hold.simulator.scene, actuation=Gripper(OneMotor(hold.hand)))
    with pytest.raises(InputError, match="runs FullyActuated and BarrettActuation hands, got Gripper"):
        BatchSimulator(gripper, [gripper.initial_state()])


@pytest.mark.parametrize(("threads", "saturate"), [(1, False), (2, True)])
def test_a_batch_of_barrett_hands_switches_like_separate_runs(threads: int, saturate: bool) -> None:
    """Four motors per environment, TorqueSwitches breaking away while closing on a box, re-opening and re-arming
    on the way back: every environment's modes, configuration and velocity equal its separate run's under the Python
    rules (the compiled Simulator runs the same C++ drive as the batch), bit for bit."""
    setup = box_grasp(mass=0.3, actuation="barrett")
    actuation = BarrettActuation(setup.hand, damping=0.01, friction=0.002, saturate=saturate)
    simulator = Simulator(
        setup.simulator.scene, dt=setup.simulator.dt, contact=setup.simulator.law, actuation=actuation
    )
    start = simulator.initial_state(setup.q_start)
    scales = np.array([1.0, 0.8, 1.3])  # 1.3: above the puck limit, clipped when saturating
    close, opening = np.array([0.02, 0.11, 0.11, 0.11]), np.array([0.0, -0.11, -0.11, -0.11])
    phases = [(close, 1500), (opening, 1200)]
    batch = BatchSimulator(simulator, [start] * len(scales), threads=threads)
    seen = set()
    for u, steps in phases:
        for _ in range(steps):
            batch.step(scales[:, None] * u)
            seen.update((k, mode) for k, mode in enumerate(batch.modes.max(axis=0)))
            seen.update((k, mode) for k, mode in enumerate(batch.modes.min(axis=0)))
    assert {mode for k, mode in seen if k < 3} == {0.0, 1.0, 2.0}  # every TorqueSwitch mode was visited ...
    assert {mode for k, mode in seen if k >= 3} == {0.0, 1.0}  # ... and the worms locked and unlocked
    rules = PythonBarrettRules(setup.hand, damping=0.01, friction=0.002, saturate=saturate)
    separate = Simulator.from_settings(simulator.scene, simulator.settings, simulator.law, rules)
    for i, scale in enumerate(scales):
        state = start
        for u, steps in phases:
            for _ in range(steps):
                state, _ = separate.step(state, scale * u)
        np.testing.assert_array_equal(batch.scene_q[i], state.scene_q)
        np.testing.assert_array_equal(batch.scene_v[i], state.scene_v)
        np.testing.assert_array_equal(batch.modes[i], state.actuation_modes)
        np.testing.assert_array_equal(batch.state(i).actuation_modes, state.actuation_modes)
