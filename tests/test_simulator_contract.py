"""The Simulator's contract: frozen settings, states checked against the scene, an immutable contact memory, steps
safe from several threads, pickling, and divergences that name the value they saw.

Each test here failed on the Simulator before the contract (an independent review's adversarial cases): the
reference hold (a box squeezed by the Barrett hand) against the same scene with other objects.
"""

from __future__ import annotations

import copy
import dataclasses
import pickle
import threading

import numpy as np
import pinocchio as pin
import pytest

from bhgrasp.data import ContactMemory, State
from bhgrasp.errors import BhgraspError, FrozenSettingError, InputError, SimulationDiverged
from bhgrasp.model.objects import Sphere
from bhgrasp.scenarios.hold import reference_hold
from bhgrasp.sim import ENGINES, Simulator, SimulatorSettings
from bhgrasp.sim.batch import BatchSimulator
from bhgrasp.sim.scene import Scene
from bhgrasp.sim.state_check import divergence_text


def hold_on(engine: str):
    """The reference hold on ``engine``, settled 50 steps (so that it carries a contact memory)."""
    hold = reference_hold()
    simulator = hold.simulator.with_settings(engine=engine)
    state = hold.state
    for _ in range(50):
        state, _ = simulator.step(state, hold.controller(state.t, state))
    assert len(state.contact_memory) >= 3
    return simulator, hold.controller, state


def run_steps(simulator: Simulator, controller, state, steps: int):
    for _ in range(steps):
        state, _ = simulator.step(state, controller(state.t, state))
    return state


# ---------------------------------------------------------------------- frozen settings
@pytest.mark.parametrize("name", ["dt", "integrator", "max_speed", "engine", "scene", "actuation"])
def test_settings_cannot_change_after_construction(name: str) -> None:
    """``sim.dt = 2e-3`` used to be taken by the Python engine and ignored by the compiled one (which still
    advanced the clock by the new dt)."""
    simulator = reference_hold().simulator
    cure = rf"with_settings\({name}=" if name in SimulatorSettings.__dataclass_fields__ else r"Simulator\(scene, "
    with pytest.raises(FrozenSettingError, match=rf"Simulator\.{name} cannot change .*{cure}"):
        setattr(simulator, name, 2e-3)
    assert isinstance(FrozenSettingError("x"), AttributeError | BhgraspError)
    assert simulator.dt == 1e-3


@pytest.mark.parametrize("engine", ENGINES)
def test_with_settings_builds_a_new_simulator_equal_to_a_fresh_one(engine: str) -> None:
    hold = reference_hold()
    coarse = hold.simulator.with_settings(dt=2e-3, engine=engine)
    original = hold.simulator
    fresh = Simulator(original.scene, dt=2e-3, contact=original.law, actuation=original.actuation, engine=engine)
    assert coarse.dt == coarse.settings.dt == 2e-3 and hold.simulator.dt == 1e-3
    u = hold.controller(0.0, hold.state)
    stepped, _ = coarse.step(hold.state, u)
    reference, _ = fresh.step(hold.state, u)
    assert stepped.t == 2e-3
    np.testing.assert_array_equal(stepped.scene_q, reference.scene_q)
    np.testing.assert_array_equal(stepped.scene_v, reference.scene_v)
    with pytest.raises(InputError, match=r"unknown settings \['timestep'\]"):
        hold.simulator.with_settings(timestep=1e-3)
    with pytest.raises(InputError, match="`dt` must be a positive finite number"):
        SimulatorSettings(dt=-1.0)


# ---------------------------------------------------------------------- a state is checked against its scene
def sphere_scene_simulator(engine: str) -> Simulator:
    """The reference hold's hand with a ball where its box was: the same sizes (nq, nv), another scene."""
    hold = reference_hold()
    box = hold.simulator.scene.objects[0]
    ball = Sphere(radius=0.02, mass=0.2, pose=box.pose)
    return Simulator(Scene(hold.simulator.scene.hand, [ball]), engine=engine)


@pytest.mark.parametrize("engine", ENGINES)
def test_a_state_of_another_scene_is_refused(engine: str) -> None:
    """The box's state stepped by the ball's simulator used to be accepted: the box jumped to the ball's place."""
    hold = reference_hold()
    other = sphere_scene_simulator(engine)
    assert other.scene.nq == hold.simulator.scene.nq and other.scene.nv == hold.simulator.scene.nv
    u = np.zeros(other.actuation.n_inputs)
    with pytest.raises(InputError, match="`state` is a state of another scene"):
        other.step(hold.state, u)
    copied = dataclasses.replace(hold.state, t=0.0)  # the signature travels with a copy
    with pytest.raises(InputError, match="another scene"):
        other.step(copied, u)
    with pytest.raises(InputError, match="another scene"):
        other.run(lambda t, s: u, 0.01, state=hold.state, progress=False)


def malformed(state: State, scene: Scene) -> list[tuple[State, str]]:
    box = scene.object_q_slice(0)
    zero_quaternion = np.array(state.scene_q)
    zero_quaternion[box.start + 3 : box.stop] = 0.0
    far = np.array(state.scene_q)
    far[box.start] = 1e155
    nan_v = np.array(state.scene_v)
    nan_v[3] = np.nan
    return [
        (State(t=0.0, q=state.q, v=state.v), r"`state\.scene_q` is missing"),
        (dataclasses.replace(state, scene_q=state.scene_q[:-1]), r"`state\.scene_q` must have shape \(15,\)"),
        (
            dataclasses.replace(state, scene_q=zero_quaternion),
            rf"`state\.scene_q\[{box.start + 3}:{box.stop}\]` must be the unit quaternion .* \(norm 0\)",
        ),
        (dataclasses.replace(state, scene_q=far), r"`state\.scene_q\[8\]` = 1e\+155 is beyond max_coordinate = 10000"),
        (dataclasses.replace(state, scene_v=nan_v), r"`state\.scene_v` must be finite, got nan at index 3"),
        (dataclasses.replace(state, scene_q=["a"] * 15), r"`state\.scene_q` must be 15 numbers"),
        (dataclasses.replace(state, t=float("nan")), r"`state\.t` must be a finite time"),
        (dataclasses.replace(state, contact_memory={"pair": []}), r"`state\.contact_memory` must be a ContactMemory"),
        ("not a state", r"`state` must be a bhgrasp State, got str"),
    ]


@pytest.mark.parametrize("engine", ENGINES)
def test_a_malformed_state_is_refused_naming_its_field(engine: str) -> None:
    """These gave a nanobind TypeError, Pinocchio's kinematics.hxx text, a zero quaternion that stayed zero, or (a
    coordinate of 1e155 m on the Python engine) a segfault inside coal."""
    hold = reference_hold()
    simulator = hold.simulator.with_settings(engine=engine)
    u = np.zeros(simulator.actuation.n_inputs)
    for state, message in malformed(hold.state, simulator.scene):
        with pytest.raises(InputError, match=message):
            simulator.step(state, u)
    with pytest.raises(InputError, match=r"`u` must be 8 numbers \(the inputs\), got 'abc'"):
        simulator.step(hold.state, "abc")
    with pytest.raises(InputError, match=r"`states\[1\]`: `state\.scene_v` must be finite"):
        BatchSimulator(hold.simulator, [hold.state, malformed(hold.state, simulator.scene)[4][0]])


def test_a_state_made_by_the_step_is_read_only_and_trusted() -> None:
    hold = reference_hold()
    state, _ = hold.simulator.step(hold.state, hold.controller(0.0, hold.state))
    for array in (state.scene_q, state.scene_v, state.q, state.v):
        with pytest.raises(ValueError, match="read-only"):
            array[0] = 1.0
    assert state.scene_signature == hold.state.scene_signature is not None


# ---------------------------------------------------------------------- the contact memory is a value
@pytest.mark.parametrize("engine", ENGINES)
def test_an_edited_contact_memory_is_what_the_step_reads(engine: str) -> None:
    """``dataclasses.replace(memory, displacement=...)`` used to keep the compiled engine's hidden native copy, so
    the compiled step ignored the edit (v differed by 0.149 m/s after one step)."""
    simulator, controller, state = hold_on(engine)
    python = simulator.with_settings(engine="python")
    memory = state.contact_memory
    with pytest.raises(ValueError, match="read-only"):
        memory.displacement[0, 0] = 1.0
    stretched = dataclasses.replace(memory, displacement=memory.displacement + 1e-4)
    assert stretched.native is None
    edited = dataclasses.replace(state, contact_memory=stretched)
    u = controller(state.t, state)
    after, _ = simulator.step(edited, u)
    reference, _ = python.step(edited, u)
    unedited, _ = simulator.step(state, u)
    np.testing.assert_allclose(after.scene_v, reference.scene_v, rtol=0, atol=1e-12)
    assert np.abs(after.scene_v - unedited.scene_v).max() > 1e-3  # the edit matters, and is read
    with pytest.raises(InputError, match=r"`ContactMemory\.local_b` must have shape \(3, 3\)"):
        ContactMemory(memory.pair, memory.local_b[:2], memory.displacement, memory.sliding)


# ---------------------------------------------------------------------- threads
def run_together(jobs: list) -> list:
    """Each job (a no-argument callable) on its own thread, started at one barrier; their results in order."""
    results: list = [None] * len(jobs)
    barrier = threading.Barrier(len(jobs))

    def work(i: int) -> None:
        barrier.wait()
        results[i] = jobs[i]()

    threads = [threading.Thread(target=work, args=(i,)) for i in range(len(jobs))]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    return results


@pytest.mark.parametrize("engine", ENGINES)
def test_steps_from_two_threads_give_each_thread_its_serial_result(engine: str) -> None:
    """The compiled step releases the GIL and wrote shared work arrays; the Python engine shared the scene's
    Pinocchio data: two threads stepping one Simulator got wrong results (up to 0.35 m), or a false divergence."""
    simulator, controller, state = hold_on(engine)
    steps = 150 if engine == "compiled" else 40
    starts = [state, dataclasses.replace(state, scene_v=state.scene_v + 0.05)]
    serial = [run_steps(simulator, controller, start, steps) for start in starts]
    together = run_together([lambda start=start: run_steps(simulator, controller, start, steps) for start in starts])
    for alone, with_other in zip(serial, together):
        np.testing.assert_array_equal(with_other.scene_q, alone.scene_q)
        np.testing.assert_array_equal(with_other.scene_v, alone.scene_v)
    # two Simulators of one scene share no work space either
    simulators = (simulator, simulator.with_settings())
    apart = run_together([lambda i=i: run_steps(simulators[i], controller, starts[i], steps) for i in range(2)])
    for alone, with_other in zip(serial, apart):
        np.testing.assert_array_equal(with_other.scene_q, alone.scene_q)


# ---------------------------------------------------------------------- pickling
@pytest.mark.parametrize("engine", ENGINES)
def test_a_simulator_pickles_and_copies_and_steps_the_same_bits(engine: str) -> None:
    """It raised Boost's 'Pickling of "pinocchio.Data" is not enabled', which kept it off Dask workers."""
    simulator, controller, state = hold_on(engine)
    reference = run_steps(simulator, controller, state, 20)
    for other in (pickle.loads(pickle.dumps(simulator)), copy.deepcopy(simulator), copy.copy(simulator)):
        assert other is not simulator and other.settings == simulator.settings
        continued = run_steps(other, controller, pickle.loads(pickle.dumps(state)), 20)
        np.testing.assert_array_equal(continued.scene_q, reference.scene_q)
        np.testing.assert_array_equal(continued.scene_v, reference.scene_v)


# ---------------------------------------------------------------------- divergences name what they saw
@pytest.mark.parametrize("engine", ENGINES)
def test_a_non_finite_result_names_its_coordinate_and_value(engine: str) -> None:
    """A step from velocities of 1e200 overflows; the batch used to report 'joint/object position = 0'."""
    hold = reference_hold()
    simulator = hold.simulator.with_settings(engine=engine)
    wild = dataclasses.replace(hold.state, scene_v=np.full(simulator.scene.nv, 1e200))
    pattern = r"joint/object (position|velocity) \(coordinate \d+, (joint|object) \w+\) = (nan|-?inf)"
    with pytest.raises(SimulationDiverged, match=pattern), np.errstate(over="ignore", invalid="ignore"):
        simulator.step(wild, np.zeros(8))  # (the Python engine's arithmetic overflows on its way)
    batch = BatchSimulator(hold.simulator, [hold.state, wild])
    batch.step(np.zeros((2, 8)))
    assert batch.diverged.tolist() == [False, True]
    assert "coordinate" in batch.divergence(1) and batch.divergence(1).split(" = ")[1] in ("nan", "inf", "-inf")


@pytest.mark.parametrize("engine", ENGINES)
def test_a_step_beyond_max_coordinate_diverges_with_its_coordinate(engine: str) -> None:
    hold = reference_hold()
    simulator = hold.simulator.with_settings(engine=engine, max_coordinate=3.0)
    box = simulator.scene.object_q_slice(0)
    q = np.array(hold.state.scene_q)
    q[box.start] = 2.99
    v = np.zeros(simulator.scene.nv)
    v[simulator.scene.object_v_slice(0).start] = 20.0  # [m/s] along x: 2 cm in a step
    start = dataclasses.replace(hold.state, scene_q=q, scene_v=v, contact_memory=None)
    pattern = rf"coordinate {box.start}, object object0 = 3\.01; beyond max_coordinate = 3"
    with pytest.raises(SimulationDiverged, match=pattern):
        simulator.step(start, np.zeros(8))


def test_divergence_records_read_in_words() -> None:
    record = type("Record", (), {"kind": 1, "index": 12, "value": float("nan")})
    assert divergence_text(record) == "joint/object position (coordinate 12) = nan"
    record.kind, record.index, record.value = 4, -1, 0.0312
    assert divergence_text(record) == "contact depth = 0.0312 m"


# ---------------------------------------------------------------------- one run, both engines
def test_a_whole_run_agrees_across_engines() -> None:
    """The run loop (controller, recorder, trajectory) on both engines: the same samples to round-off."""
    hold = reference_hold()
    runs = [
        hold.simulator.with_settings(engine=engine).run(hold.controller, 0.2, state=hold.state, progress=False)
        for engine in ENGINES
    ]
    compiled, python = runs
    assert len(compiled) == len(python) == 201
    np.testing.assert_array_equal(compiled.t, python.t)
    np.testing.assert_array_equal(compiled.contact_offsets, python.contact_offsets)
    np.testing.assert_array_equal(compiled.contact_pair, python.contact_pair)
    for name in ("q", "v", "u", "tau", "object_position", "object_quaternion", "contact_force", "contact_point"):
        np.testing.assert_allclose(getattr(compiled, name), getattr(python, name), rtol=0, atol=1e-10, err_msg=name)


def test_a_pinned_pose_keeps_working() -> None:
    """A user may place the box elsewhere with dataclasses.replace: a checked, unit quaternion is accepted."""
    hold = reference_hold()
    box = hold.simulator.scene.object_q_slice(0)
    q = np.array(hold.state.scene_q)
    q[box] = pin.SE3ToXYZQUAT(pin.SE3(pin.rpy.rpyToMatrix(0.0, 0.0, 0.3), q[box.start : box.start + 3]))
    moved = dataclasses.replace(hold.state, scene_q=q, contact_memory=None)
    state, _ = hold.simulator.step(moved, np.zeros(8))
    np.testing.assert_allclose(np.linalg.norm(state.scene_q[box.start + 3 : box.stop]), 1.0, rtol=0, atol=1e-12)
