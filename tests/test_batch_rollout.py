"""Open-loop rollouts of a batch (``BatchSimulator.rollout``, src/batch.cpp) and the batch's kept worker threads.

The independent truth is the batch's own step, called once per step from Python (itself held to separate
``Simulator`` runs by tests/test_batch.py): a rollout through the same inputs must give the same states after every
step, bit for bit, whatever the thread count, with held or per-step inputs, Barrett modes switching, and
environments diverging on the way.
"""

from __future__ import annotations

import os
import select
import signal
import threading
import time

import numpy as np
import pytest
from test_batch import inputs, start_states

from bhgrasp.errors import InputError
from bhgrasp.scenarios.box_grasp import box_grasp
from bhgrasp.scenarios.hold import reference_hold
from bhgrasp.sim import Simulator
from bhgrasp.sim.actuation import BarrettActuation, FullyActuated
from bhgrasp.sim.batch import BatchRollout, BatchSimulator


def stepped(simulator, states, u, threads):
    """The batch stepped once per step from Python: (N, steps, nq) and (N, steps, nv) states, and the batch."""
    batch = BatchSimulator(simulator, states, threads=threads)
    q, v = [], []
    for k in range(u.shape[1]):
        batch.step(u[:, k])
        q.append(batch.scene_q.copy())
        v.append(batch.scene_v.copy())
    return np.stack(q, axis=1), np.stack(v, axis=1), batch


@pytest.mark.parametrize("threads", [1, 2, 3])
def test_a_rollout_gives_the_bits_of_stepping_one_step_at_a_time(threads: int) -> None:
    hold = reference_hold()
    states = start_states(hold, 4)
    wobble = 1.0 + 0.2 * np.sin(np.arange(240) / 17.0)  # inputs that change every step
    u = inputs(hold, states)[:, None, :] * wobble[None, :, None]
    q, v, reference = stepped(hold.simulator, states, u, threads)
    batch = BatchSimulator(hold.simulator, states, threads=threads)
    result = batch.rollout(u)
    assert isinstance(result, BatchRollout) and result.scene_q.shape == (4, 240, q.shape[2])
    np.testing.assert_array_equal(result.scene_q, q)
    np.testing.assert_array_equal(result.scene_v, v)
    np.testing.assert_array_equal(result.q, q[:, :, :8])
    np.testing.assert_array_equal(batch.scene_q, reference.scene_q)
    for i in range(4):
        np.testing.assert_array_equal(batch.contacts(i).force, reference.contacts(i).force)
        np.testing.assert_array_equal(
            batch.state(i).contact_memory.displacement, reference.state(i).contact_memory.displacement
        )
    assert batch.t == reference.t and result.t[-1] == batch.t and len(result.t) == 240
    np.testing.assert_allclose(np.diff(result.t), hold.simulator.dt, rtol=1e-9)


def test_held_inputs_and_rollouts_in_pieces_equal_one_rollout() -> None:
    hold = reference_hold()
    states = start_states(hold, 3)
    u = inputs(hold, states)
    whole = BatchSimulator(hold.simulator, states, threads=2).rollout(u, steps=150)
    pieces = BatchSimulator(hold.simulator, states, threads=2)
    first = pieces.rollout(np.repeat(u[:, None, :], 100, axis=1))  # the same inputs, one row per step
    assert pieces.rollout(u, steps=50, record=False).scene_q.shape == (3, 0, 0)
    np.testing.assert_array_equal(first.scene_q, whole.scene_q[:, :100])
    np.testing.assert_array_equal(pieces.scene_q, whole.scene_q[:, -1])
    np.testing.assert_array_equal(pieces.scene_v, whole.scene_v[:, -1])


def test_a_rollout_of_barrett_hands_switches_their_modes_as_steps_do() -> None:
    setup = box_grasp(mass=0.3, actuation="barrett")
    actuation = BarrettActuation(setup.hand, damping=0.01, friction=0.002, saturate=True)
    simulator = Simulator(
        setup.simulator.scene, dt=setup.simulator.dt, contact=setup.simulator.law, actuation=actuation
    )
    start = [simulator.initial_state(setup.q_start)] * 3
    scales = np.array([1.0, 0.8, 1.3])[:, None, None]  # 1.3: above the puck limit, clipped
    close, opening = np.array([0.02, 0.11, 0.11, 0.11]), np.array([0.0, -0.11, -0.11, -0.11])
    reference = BatchSimulator(simulator, start, threads=2)
    batch = BatchSimulator(simulator, start, threads=2)
    for motors, steps, switches in [(close, 1500, "broken away"), (opening, 1200, "re-armed")]:
        u = scales * np.tile(motors, (1, steps, 1))
        q = []
        for k in range(steps):
            reference.step(u[:, k])
            q.append(reference.scene_q.copy())
        result = batch.rollout(u)
        np.testing.assert_array_equal(result.scene_q, np.stack(q, axis=1))
        np.testing.assert_array_equal(batch.scene_v, reference.scene_v)
        np.testing.assert_array_equal(batch.modes, reference.modes)
        assert (batch.modes[:, :3].max() > 0) == (switches == "broken away")  # TorqueSwitches broke, then re-armed


def test_a_diverging_environment_repeats_its_last_good_state_and_the_others_go_on() -> None:
    hold = reference_hold()
    states = start_states(hold, 3)
    u = np.repeat(inputs(hold, states)[:, None, :], 50, axis=1)
    u[1, 10:] = 1e4  # [N m] from step 10 on, far beyond the hand: it flies apart
    q, _, reference = stepped(hold.simulator, states, u, threads=2)
    batch = BatchSimulator(hold.simulator, states, threads=2)
    result = batch.rollout(u)
    assert batch.diverged.tolist() == reference.diverged.tolist() == [False, True, False]
    np.testing.assert_array_equal(result.scene_q, q)
    last = np.flatnonzero(np.abs(np.diff(q[1], axis=0)).max(axis=1) > 0)[-1] + 1  # the last step that moved it
    assert last < 49 and (result.scene_q[1, last:] == result.scene_q[1, last]).all()


def test_rollout_errors_name_the_argument() -> None:
    hold = reference_hold()
    batch = BatchSimulator(hold.simulator, [hold.state, hold.state])
    q = batch.scene_q.copy()
    with pytest.raises(InputError, match=r"`u` must have shape \(2, steps, 8\).*got \(2, 8\) and steps=None"):
        batch.rollout(np.zeros((2, 8)))
    with pytest.raises(InputError, match=r"got \(3, 5, 8\)"):
        batch.rollout(np.zeros((3, 5, 8)))
    with pytest.raises(InputError, match="`steps` is 4 but `u` holds 5 steps"):
        batch.rollout(np.zeros((2, 5, 8)), steps=4)
    for steps in (0, True, 2.5):
        with pytest.raises(InputError, match="`steps` must be a positive integer"):
            batch.rollout(np.zeros((2, 8)), steps=steps)
    with pytest.raises(InputError, match="at least one step"):
        batch.rollout(np.zeros((2, 0, 8)))
    u = np.zeros((2, 5, 8))
    u[1, 3, 2] = np.inf
    with pytest.raises(InputError, match=r"NaN/inf in environments \[1\]"):
        batch.rollout(u)
    np.testing.assert_array_equal(batch.scene_q, q)  # nothing stepped
    assert batch.t == hold.state.t


def test_the_kept_threads_survive_a_failing_step_and_a_change_of_count() -> None:
    """A step that throws in the workers' blocks reports the error and leaves the threads serving the next call."""
    hold = reference_hold()
    states = start_states(hold, 4)
    u = inputs(hold, states)
    batch = BatchSimulator(hold.simulator, states, threads=2)
    batch.step(u)
    native = batch._batch
    limits = (hold.simulator.max_speed, hold.simulator.max_penetration)
    with pytest.raises(ValueError, match="wrong size"):  # every environment's engine refuses the drive
        native.rollout(u, 3, False, type(batch._drive)(), *limits, 2, True)
    expected = BatchSimulator(hold.simulator, states, threads=1)
    expected.step(u)
    for threads in (2, 4, 1, 2):
        batch.threads = threads
        batch.step(u)
        expected.step(u)
        np.testing.assert_array_equal(batch.scene_q, expected.scene_q)


def test_a_saturating_hand_clips_at_its_own_limit_in_steps_and_rollouts() -> None:
    """A fully actuated hand with its own torque limit: batch steps and rollouts clip where separate runs clip."""
    hold = reference_hold()
    actuation = FullyActuated(hold.hand, damping=0.02, limit=0.1)  # [N m], below the hold's torques
    simulator = Simulator.from_settings(hold.simulator.scene, hold.simulator.settings, hold.simulator.law, actuation)
    states = start_states(hold, 2)
    u = np.repeat(inputs(hold, states)[:, None, :], 40, axis=1)
    assert np.abs(u).max() > 0.1
    batch = BatchSimulator(simulator, states, threads=2)
    result = batch.rollout(u)
    for i, state in enumerate(states):
        for k in range(40):
            state, _ = simulator.step(state, u[i, k])
            np.testing.assert_array_equal(result.scene_q[i, k], state.scene_q)
    stepped = BatchSimulator(simulator, states, threads=2)
    for k in range(40):
        stepped.step(u[:, k])
    np.testing.assert_array_equal(stepped.scene_v, batch.scene_v)


def test_a_forked_child_steps_a_batch_its_parent_threaded() -> None:
    """The kept threads are not in a fork()ed child: its copy of the batch makes its own, and ends without waiting."""
    hold = reference_hold()
    states = start_states(hold, 4)
    u = inputs(hold, states)
    batch = BatchSimulator(hold.simulator, states, threads=2)
    batch.step(u)  # the parent's threads are made
    read, write = os.pipe()
    child = os.fork()
    if child == 0:  # the child: step on its copy, report, drop the batch, leave
        try:
            batch.step(u)
            os.write(write, batch.scene_q.tobytes())
            del batch
        finally:
            os._exit(0)
    os.close(write)
    data, deadline, status = b"", time.monotonic() + 60.0, None
    try:
        while status is None and time.monotonic() < deadline:  # read until the child has ended, for at most 60 s
            if select.select([read], [], [], 0.05)[0]:
                data += os.read(read, 1 << 16)
            finished, code = os.waitpid(child, os.WNOHANG)
            status = code if finished else None
        data += os.read(read, 1 << 16) if status is not None else b""
    finally:
        os.close(read)
        if status is None:
            os.kill(child, signal.SIGKILL)
            os.waitpid(child, 0)
    assert status is not None, "the forked child did not step and end within 60 s"
    assert os.WIFEXITED(status) and os.WEXITSTATUS(status) == 0
    batch.step(u)
    np.testing.assert_array_equal(np.frombuffer(data).reshape(batch.scene_q.shape), batch.scene_q)


def test_two_python_threads_calling_one_batch_take_turns() -> None:
    """Calls from two Python threads (the GIL released in C++), each with its own thread count, run one at a time."""
    hold = reference_hold()
    states = start_states(hold, 4)
    batch = BatchSimulator(hold.simulator, states)
    expected = batch.gravity_torques()
    native, results, errors = batch._batch, [], []

    def call(threads: int) -> None:
        try:
            for _ in range(200):
                results.append(native.gravity(threads))
        except Exception as error:  # reported below
            errors.append(error)

    workers = [threading.Thread(target=call, args=(count,)) for count in (2, 3)]
    for worker in workers:
        worker.start()
    for worker in workers:
        worker.join(timeout=60.0)
    assert not any(worker.is_alive() for worker in workers), "the calls did not finish within 60 s"
    assert not errors and len(results) == 400
    assert all(np.array_equal(result, expected) for result in results)
