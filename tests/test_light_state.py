"""The light State and the recorder: a stepped state builds its derived fields only when read, and they (and a
run's Trajectory, assembled at the end of the run) hold what the scene and the step say.

Independent truths: :class:`~bhgrasp.sim.scene.Scene`'s own pose and twist functions of (q, v), the step's
:class:`~bhgrasp.sim.simulator.StepInfo` contacts, and a run continued from a copy, a pickle or a replaced state
against the original run (bit for bit).
"""

from __future__ import annotations

import copy
import dataclasses
import pickle

import numpy as np
import pinocchio as pin
import pytest

import bhgrasp as bh
from bhgrasp.data import DERIVED_FIELDS, ContactMemory, SimulatedState
from bhgrasp.model.objects import Box
from bhgrasp.model.spring_mounted import SpringMounted
from bhgrasp.scenarios.hold import reference_hold
from bhgrasp.sim import Simulator
from bhgrasp.sim.actuation import FullyActuated
from bhgrasp.sim.scene import Scene

ENGINES = ("compiled", "python")


def engine_twin(simulator: Simulator, engine: str) -> Simulator:
    return Simulator(
        simulator.scene, dt=simulator.dt, contact=simulator.law, actuation=simulator.actuation, engine=engine
    )


def spring_scene(engine: str) -> tuple[Simulator, object, np.ndarray]:
    """A finger pressing a spring-mounted plate (the other object kind) next to a free box lying on it."""
    hand = bh.BarrettHand()
    tip = hand.fingertip_positions(hand.configuration(F3_proximal=1.0))[hand.fingers.index("F3")]
    body = Box(size=(0.04, 0.04, 0.01), mass=0.1, pose=pin.SE3(np.eye(3), tip + np.array([0.0, 0.0, 0.006])))
    plate = SpringMounted(body=body, direction=np.array([0.0, 0.0, 1.0]), stiffness=200.0, damping=2.0)
    box = Box(
        size=(0.03, 0.02, 0.02),
        mass=0.05,
        pose=pin.SE3(pin.rpy.rpyToMatrix(0.1, 0.2, 0.3), np.r_[3.0, 0, 0]),
        velocity=[0.1, 0.0, 0.0, 1.0, 4.0, -2.0],
        name="tumbling",
    )
    # The finger starts 5.6 mm into the plate on purpose (a press from the first step): no start warning
    drive = FullyActuated(hand, damping=0.02)
    simulator = Simulator(Scene(hand, [plate, box]), actuation=drive, engine=engine, start_check="off")
    torque = np.zeros(8)
    torque[hand.joint_index("F3_proximal")] = 0.3
    return simulator, lambda t, s: torque, hand.configuration(F3_proximal=0.9)


def scenes(engine: str):
    hold = reference_hold()
    yield engine_twin(hold.simulator, engine), hold.controller, hold.state
    simulator, controller, q = spring_scene(engine)
    yield simulator, controller, simulator.initial_state(q)


def assert_state_matches_scene(simulator: Simulator, state, info) -> None:
    """Every derived field against the scene's functions of (q, v) and the step's contacts."""
    scene = simulator.scene
    q, v = state.scene_q, state.scene_v
    np.testing.assert_array_equal(state.q, q[: scene.nq_hand])
    np.testing.assert_array_equal(state.v, v[: scene.nv_hand])
    for i, pose in enumerate(state.object_poses):
        assert pose.isApprox(scene.object_pose(q, i), 0.0)
        np.testing.assert_array_equal(state.object_twists[i], scene.object_twist(q, v, i))
    contacts = info.contacts
    np.testing.assert_array_equal(state.contact_points, contacts.point)
    np.testing.assert_array_equal(state.contact_normals, contacts.normal)
    np.testing.assert_array_equal(state.contact_forces, contacts.force)
    assert state.contact_bodies == tuple((scene.pairs[k].body_a, scene.pairs[k].body_b) for k in contacts.pair)
    memory = state.contact_memory
    assert isinstance(memory, ContactMemory) and len(memory) == len(contacts)
    np.testing.assert_array_equal(memory.pair, contacts.pair)


@pytest.mark.parametrize("engine", ENGINES)
def test_a_stepped_state_reads_as_the_scene_and_the_step_say(engine: str) -> None:
    for simulator, controller, state in scenes(engine):
        touched = 0
        for _ in range(200):
            state, info = simulator.step(state, controller(state.t, state))
            assert_state_matches_scene(simulator, state, info)
            touched += len(info.contacts) > 0
        assert touched > 100  # the comparisons covered contacts


@pytest.mark.parametrize("engine", ENGINES)
def test_unread_fields_are_not_built(engine: str) -> None:
    hold = reference_hold()
    simulator = engine_twin(hold.simulator, engine)
    state, _ = simulator.step(hold.state, hold.controller(hold.state.t, hold.state))
    assert isinstance(state, SimulatedState)
    for name in DERIVED_FIELDS - {"q", "v"}:
        with pytest.raises(AttributeError):
            object.__getattribute__(state, name)  # the slot is empty until the field is read
    for hand, scene in ((state.q, state.scene_q), (state.v, state.scene_v)):  # the hand's: views of the scene's
        assert np.shares_memory(hand, scene) and np.array_equal(hand, scene[: len(hand)])
        with pytest.raises(ValueError, match="read-only"):
            hand[0] = 1.0  # the next step starts from scene_q: nobody may change it
    poses = state.object_poses
    assert object.__getattribute__(state, "object_poses") is poses  # built once, then kept
    assert object.__getattribute__(state, "object_twists") is state.object_twists  # built with the poses
    with pytest.raises(AttributeError, match="contact_pionts"):
        state.contact_pionts  # noqa: B018  (a misspelt field is still an AttributeError)


@pytest.mark.parametrize("engine", ENGINES)
def test_copies_pickles_and_replaced_states_continue_the_run_bit_for_bit(engine: str) -> None:
    hold = reference_hold()
    simulator = engine_twin(hold.simulator, engine)
    state = hold.state
    for _ in range(50):
        state, _ = simulator.step(state, hold.controller(state.t, state))

    def run(start):
        for _ in range(50):
            start, _ = simulator.step(start, hold.controller(start.t, start))
        return start

    reference = run(state)
    for other in (
        copy.copy(state),
        copy.deepcopy(state),
        pickle.loads(pickle.dumps(state)),
        dataclasses.replace(state, t=state.t),
    ):
        continued = run(other)
        np.testing.assert_array_equal(continued.scene_q, reference.scene_q)
        np.testing.assert_array_equal(continued.scene_v, reference.scene_v)
        np.testing.assert_array_equal(continued.contact_forces, reference.contact_forces)
    cleared = dataclasses.replace(state, contact_memory=None)
    assert cleared.contact_memory is None and len(cleared.contact_points) == len(state.contact_points)


def test_a_compiled_run_continues_on_the_python_engine() -> None:
    """A state carries the compiled engine's native contact memory; the Python engine takes it over."""
    hold = reference_hold()
    python = engine_twin(hold.simulator, "python")
    state = hold.state
    for _ in range(100):
        state, _ = hold.simulator.step(state, hold.controller(state.t, state))
    u = hold.controller(state.t, state)
    from_native, _ = python.step(state, u)
    from_arrays, _ = python.step(dataclasses.replace(state, t=state.t), u)  # every field built: ContactMemory
    np.testing.assert_array_equal(from_native.scene_v, from_arrays.scene_v)
    compiled_next, _ = hold.simulator.step(state, u)
    np.testing.assert_allclose(from_native.scene_v, compiled_next.scene_v, rtol=0, atol=1e-12)


@pytest.mark.parametrize("engine", ENGINES)
def test_a_trajectory_records_what_each_state_holds(engine: str) -> None:
    """The recorder assembles its arrays at the end of the run; each sample must equal its state's fields."""
    for simulator, controller, start in scenes(engine):
        states = []

        def watching(t, state, controller=controller, states=states):
            states.append(state)
            return controller(t, state)

        trajectory = simulator.run(watching, 0.3, state=start, progress=False)
        assert len(states) == len(trajectory) - 1 == 300  # the last sample has no controller call
        for k, state in enumerate(states):
            assert trajectory.t[k] == state.t
            np.testing.assert_array_equal(trajectory.q[k], state.q)
            np.testing.assert_array_equal(trajectory.v[k], state.v)
            for i, pose in enumerate(state.object_poses):
                np.testing.assert_array_equal(trajectory.object_position[k, i], pose.translation)
                rotation = pin.Quaternion(*np.roll(trajectory.object_quaternion[k, i], 1)).toRotationMatrix()
                np.testing.assert_allclose(rotation, pose.rotation, rtol=0, atol=4e-16)
                np.testing.assert_allclose(
                    trajectory.object_twist[k, i],
                    state.object_twists[i],
                    rtol=0,
                    atol=1e-15 * max(1.0, np.abs(state.object_twists[i]).max()),
                )
            if k == 0:
                continue  # a run's first sample records no step, so no contact forces
            contacts = trajectory.contacts_at(k)
            np.testing.assert_array_equal(contacts["point"], state.contact_points)
            np.testing.assert_array_equal(contacts["normal"], state.contact_normals)
            np.testing.assert_array_equal(contacts["force"], state.contact_forces)
            assert [tuple(b) for b in contacts["bodies"]] == list(state.contact_bodies)
        assert trajectory.contact_count().sum() > 0


def test_contact_body_names_come_from_a_bounded_cache_that_answers_as_the_pairs_say() -> None:
    """SceneLayout.body_names keeps the tuple of each contact list it met (a run meets a handful), up to a bound."""
    simulator = reference_hold().simulator
    layout = simulator.layout
    rng = np.random.default_rng(5)
    lists = [rng.integers(0, len(layout.pair_bodies), size=rng.integers(0, 9)) for _ in range(3000)]
    for pairs in lists + lists[:50]:
        names = layout.body_names(pairs)
        assert names == tuple((simulator.scene.pairs[k].body_a, simulator.scene.pairs[k].body_b) for k in pairs)
        assert len(layout._names) <= 1024
    again = np.array(lists[-1])  # another array with the same indices: the kept tuple itself
    assert layout.body_names(again) is layout.body_names(lists[-1])
