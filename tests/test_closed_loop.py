"""The compiled closed loop (``src/closed_loop.cpp``) against the Python run loop it stands in for, bit for bit.

:meth:`Simulator.run <bhgrasp.sim.simulator.Simulator.run>` hands a controller's cycles to one C++ call while the
controller offers a compiled loop controller (a :class:`GraspSupervisor`'s approach, and its grasp phases over a
compiled :class:`SMCAdaptiveGrasp`; a bare compiled law once it grasps toward a pose path) and the run is plain: exact
sensors, one control cycle and one sample a step, nothing else acting on the scene.  Each run here is made twice,
the second with the offer withdrawn (every step through Python's loop, the law's compiled cycle called from
Python), and every recorded array, log entry and error, and the controllers as the runs leave them, must be the same
to the bit.  The runs cover the approach (handed back when the fingers arrive, when its reference table is used up,
at a timeout, with other gains and damping, with a torque that is not finite), the squeeze's end (the loop stops for
the supervisor's switch and plan), clipped torques, a friction margin, fingers letting go (the loop hands the cycle
back), a diverged step, a failed cycle, runs cut into chunks and a second run after a reset.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from bhgrasp.controllers import supervisor as supervisor_module
from bhgrasp.controllers.adaptive_grasp import SMCAdaptiveGrasp
from bhgrasp.controllers.grasp_options import GraspOptions
from bhgrasp.controllers.supervisor import GraspSupervisor
from bhgrasp.controllers.supervisor_options import DEFAULT_APPROACH, Approach
from bhgrasp.errors import InputError, SimulationDiverged
from bhgrasp.model.objects import Box
from bhgrasp.motion.pose_references import PoseMotion
from bhgrasp.scenarios.box_grasp import box_grasp
from bhgrasp.scenarios.demo_result import MU_ASSUMED
from bhgrasp.scenarios.grasp_controllers import SQUEEZE
from bhgrasp.scenarios.grasp_demo import OFFSET, run_grasp_demo
from bhgrasp.sim import run_loop
from bhgrasp.sim.actuation import FullyActuated
from bhgrasp.sim.simulator import Simulator

pytest.importorskip("bhgrasp._core")


@pytest.fixture
def compiled_steps(monkeypatch):
    """The steps each compiled loop took (stop and status too), as a list filled by the runs."""
    taken: list[tuple[int, int, int]] = []
    run_compiled = Simulator.run_compiled

    def counted(self, *arguments):
        done = run_compiled(self, *arguments)
        if done is not None:
            taken.append((int(done[0].steps), int(done[0].stop), int(done[0].status)))
        return done

    monkeypatch.setattr(Simulator, "run_compiled", counted)
    return taken


def python_loop(monkeypatch) -> None:
    """Withdraw the controllers' offers: every step through the Python loop."""
    for kind in (GraspSupervisor, SMCAdaptiveGrasp):
        monkeypatch.setattr(kind, "compiled_control", lambda self, t, state: None)


def assert_same_run(compiled, python) -> None:
    """Every array of the two trajectories and every log entry, in the same order, equal to the bit."""
    for field in dataclasses.fields(python):
        a, b = getattr(compiled, field.name), getattr(python, field.name)
        if isinstance(b, np.ndarray):
            assert a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes(), field.name
    assert list(compiled.log) == list(python.log)
    for key, value in python.log.items():
        assert compiled.log[key].shape == value.shape and compiled.log[key].tobytes() == value.tobytes(), key


@pytest.mark.parametrize(
    "case",
    [{}, {"friction_margin": 0.3, "duration": 2.0}, {"torque_limit": 0.5, "mass": 1.5, "duration": 2.0}],
    ids=["demo", "friction-margin", "clipped-torques"],
)
def test_the_demo_runs_in_the_compiled_loop_with_the_python_loops_bits(case, compiled_steps, monkeypatch):
    compiled = run_grasp_demo(**case)
    steps = round(case.get("duration", 3.0) * 1000)
    taken = sum(count for count, _, _ in compiled_steps)
    # the approach until the fingers arrive (handed back), the squeeze to its end, the motion to the run's end
    assert [(stop, status) for _, stop, status in compiled_steps] == [(1, -1), (0, 0), (0, 0)]
    assert taken == steps - 3  # in Python: the approach's first cycle, the grasp's first (the switch), the motion's
    if "torque_limit" in case:
        u = compiled.trajectory.u
        assert np.abs(u).max() > case["torque_limit"]  # the drive clipped some commands
        tau = compiled.trajectory.tau  # sample k: the torques of the step that made it
        delivered = np.clip(u[:-1], -0.5, 0.5)  # (no joint friction, no damping; the drive's round-off)
        np.testing.assert_allclose(tau[1:], delivered, rtol=0.0, atol=1e-12)
    python_loop(monkeypatch)
    python = run_grasp_demo(**case)
    assert_same_run(compiled.trajectory, python.trajectory)
    assert compiled.position_error == python.position_error


def test_fingers_that_let_go_hand_the_cycle_back_to_python(compiled_steps, monkeypatch):
    """True friction 0.22 (the law assumes 0.6): the box slides out and F1, F2 let go at ~2.1 s."""
    compiled = run_grasp_demo(friction=0.22, duration=2.25)
    assert (1, -1) in {(stop, status) for _, stop, status in compiled_steps}
    contacts = compiled.trajectory.log["contacts"]
    assert np.nanmax(contacts[-100:]) < 2  # the approach branch, in Python, after the loop handed it back
    python_loop(monkeypatch)
    assert_same_run(compiled.trajectory, run_grasp_demo(friction=0.22, duration=2.25).trajectory)


@pytest.fixture
def controllers(monkeypatch):
    """The controller of every ``Simulator.run`` call, as a list filled by the runs."""
    given = []
    run = Simulator.run

    def kept(self, controller, *arguments, **options):
        given.append(controller)
        return run(self, controller, *arguments, **options)

    monkeypatch.setattr(Simulator, "run", kept)
    return given


def assert_same_logs(compiled: dict, python: dict) -> None:
    """Two controllers' logs: the same entries in the same order, equal to the bit."""
    assert list(compiled) == list(python)
    for key, value in python.items():
        a, b = np.asarray(compiled[key], dtype=float), np.asarray(value, dtype=float)
        assert a.shape == b.shape and a.tobytes() == b.tobytes(), key


def assert_same_controllers(compiled: GraspSupervisor, python: GraspSupervisor) -> None:
    """Two supervisors over SMC-adaptive laws as their runs left them: clocks, logs, estimates, arrived fingers."""
    assert compiled.grasp._time == python.grasp._time and compiled.phase == python.phase
    assert compiled.switch_time == python.switch_time
    assert compiled._arrived.tobytes() == python._arrived.tobytes()
    assert compiled._approach_law._time == python._approach_law._time
    assert_same_logs(compiled._approach_law.log, python._approach_law.log)
    assert_same_logs(compiled.log, python.log)
    assert_same_logs(compiled.grasp.log, python.grasp.log)
    assert compiled.grasp.object_estimate.tobytes() == python.grasp.object_estimate.tobytes()


def supervised(approach: Approach = DEFAULT_APPROACH, runs: int = 1, duration: float = 1.2, scene=None, **law):
    """The box scene (``scene``: box_grasp's options) and a supervisor over a bare law (the demo's motion from its
    squeeze's end) run ``runs`` times (each run resets it): the last trajectory and the supervisor."""
    setup = box_grasp(mass=0.6, **(scene or {}))
    supervisor = GraspSupervisor(setup.hand, setup.q_contact, bare_law(setup, **law), offset=OFFSET, approach=approach)
    for _ in range(runs):
        trajectory = setup.simulator.run(supervisor, duration, state=setup.state, progress=False)
    return trajectory, supervisor


@pytest.mark.parametrize("rows", [1, 97, 625])
def test_an_approach_handed_back_at_any_cycle_leaves_the_python_loops_bits(rows, compiled_steps, monkeypatch):
    """Reference tables of ``rows`` samples: the loop hands back when one is used up (at 625: on the cycle the fingers
    arrive, before it took a step)."""
    monkeypatch.setattr(supervisor_module, "APPROACH_ROWS", rows)
    compiled = supervised()
    assert (1, -1) in {(stop, status) for _, stop, status in compiled_steps}
    python_loop(monkeypatch)
    python = supervised()
    assert_same_run(compiled[0], python[0])
    assert_same_controllers(compiled[1], python[1])


@pytest.mark.parametrize(
    "approach",
    [Approach(timeout=0.3), Approach(damping=0.05, kp=900.0, kv=60.0, time=0.1)],
    ids=["timeout", "damping-and-gains"],
)
def test_an_approach_with_other_settings_and_a_second_run_leave_the_python_loops_bits(
    approach, compiled_steps, monkeypatch
):
    """A timeout before the fingers arrive (the grasp starts anyway), other gains and damping; the supervisor run
    twice (the second after its reset)."""
    compiled = supervised(approach, runs=2)
    assert sum(count for count, _, _ in compiled_steps) > 0.8 * 2400  # of 2 x 1,200 (a timeout: some law closing)
    python_loop(monkeypatch)
    python = supervised(approach, runs=2)
    assert_same_run(compiled[0], python[0])
    assert_same_controllers(compiled[1], python[1])
    if approach.timeout == 0.3:
        assert compiled[1].switch_time == pytest.approx(0.3) and not compiled[1]._arrived.all()


def test_the_controllers_are_left_as_the_python_loop_leaves_them(controllers, monkeypatch):
    run_grasp_demo(duration=2.0)
    python_loop(monkeypatch)
    run_grasp_demo(duration=2.0)
    assert_same_controllers(*controllers)


def test_a_step_that_diverges_in_the_loop_raises_what_the_python_loop_raises(compiled_steps, controllers, monkeypatch):
    """The diverged step's cycle ran: the controllers are left as after it, on either loop."""
    with pytest.raises(SimulationDiverged) as in_cpp:
        run_grasp_demo(friction=0.25)
    assert [stop for _, stop, _ in compiled_steps] == [1, 0, 2]  # the approach, the squeeze; the motion diverged
    python_loop(monkeypatch)
    with pytest.raises(SimulationDiverged) as in_python:
        run_grasp_demo(friction=0.25)
    assert str(in_cpp.value) == str(in_python.value)
    assert "t = 2.204 s" in str(in_python.value)
    assert_same_controllers(*controllers)


def test_runs_of_at_most_a_chunk_of_steps_a_call_take_the_same_steps(compiled_steps, monkeypatch):
    """The loop resumes each chunk from the controller as the last one left it: the same bits as one call."""
    whole = run_grasp_demo(duration=2.0).trajectory
    calls = len(compiled_steps)
    monkeypatch.setattr(run_loop, "CHUNK", 97)
    chunked = run_grasp_demo(duration=2.0).trajectory
    assert len(compiled_steps) - calls > 12 and max(count for count, _, _ in compiled_steps[calls:]) == 97
    assert_same_run(chunked, whole)


def test_a_simulator_without_the_compiled_loop_runs_every_step_in_python(compiled_steps):
    """The Python engine, a subclass of FullyActuated (its hooks are Python's) or a Barrett drive: no offer taken."""
    setup = box_grasp(mass=0.6)

    class Limited(FullyActuated):
        """A subclass, which may change what the inputs do."""

    hand = setup.simulator.scene.hand
    simulators = [
        setup.simulator.with_settings(engine="python"),
        Simulator(setup.simulator.scene, dt=setup.simulator.dt, contact=setup.simulator.law, actuation=Limited(hand)),
        box_grasp(mass=0.6, actuation="barrett").simulator,
    ]
    assert setup.simulator.closes_loops_in_cpp()
    for simulator in simulators:
        assert not simulator.closes_loops_in_cpp()
    law = bare_law(setup)
    setup.simulator.run(law, 1.2, state=setup.state, progress=False)
    assert compiled_steps
    compiled_steps.clear()
    simulators[1].run(bare_law(setup), 1.2, state=simulators[1].initial_state(setup.state.q), progress=False)
    assert compiled_steps == []


def bare_law(setup, **options):
    """A bare compiled law (no supervisor; told 0.3 kg) that follows the demo's motion from 0.8 s on."""
    box = Box(size=setup.box.size, mass=0.3)
    grasp = GraspOptions(mu=MU_ASSUMED, squeeze=SQUEEZE)
    law = SMCAdaptiveGrasp(setup.hand, box, options=grasp, engine="compiled", **options)
    law.reference = PoseMotion(setup.state.object_poses[0], OFFSET, 1.0, 0.8)  # (a reset keeps it)
    return law


def test_a_bare_law_runs_its_grasp_cycles_in_cpp_with_the_python_loops_bits(compiled_steps, monkeypatch):
    """The law closes the fingers itself (its approach branch, in Python), then grasps and moves the box."""
    setup = box_grasp(mass=0.6)
    compiled = setup.simulator.run(bare_law(setup), 1.5, state=setup.state, progress=False)
    assert sum(count for count, _, _ in compiled_steps) > 1000
    python_loop(monkeypatch)
    assert_same_run(compiled, setup.simulator.run(bare_law(setup), 1.5, state=setup.state, progress=False))


def test_a_cycle_that_fails_in_the_loop_raises_what_the_python_cycle_raises(compiled_steps, monkeypatch):
    """An adaptation rate that overflows the object estimate once the grasp adapts: the same error either way, and
    the controllers left alike (the failed cycle's clock, the last good cycle's logs)."""
    errors, supervisors = [], []
    for python in (False, True):
        if python:
            python_loop(monkeypatch)
        setup = box_grasp(mass=0.6)
        supervisor = GraspSupervisor(
            setup.hand, setup.q_contact, bare_law(setup, object_adaptation=np.full(7, 1e308)), offset=OFFSET
        )
        with pytest.raises(InputError) as error:
            setup.simulator.run(supervisor, 1.5, state=setup.state, progress=False)
        errors.append(str(error.value))
        supervisors.append(supervisor)
    assert errors[0] == errors[1]
    assert [(stop, status) for _, stop, status in compiled_steps][-1] == (1, 3)  # the wrench not finite
    assert_same_controllers(*supervisors)


def test_an_approach_torque_that_is_not_finite_raises_what_the_python_loop_raises(
    controllers, compiled_steps, monkeypatch
):
    """Gains that overflow the computed torque (the drive clips what it applies, 0.5 N m): the loop hands the cycle
    back, and Python raises as it would."""
    approach = Approach(kp=1.7e308, time=1e-3, closing=3.0)
    errors = []
    for python in (False, True):
        if python:
            python_loop(monkeypatch)
        with pytest.raises(InputError) as error, np.errstate(over="ignore", invalid="ignore"):
            supervised(approach, duration=0.3, scene={"torque_limit": 0.5, "opening": 1.5})
        errors.append(str(error.value))
    assert errors[0] == errors[1] and "non-finite torques" in errors[0]
    assert compiled_steps == [(0, 1, -1)]  # the loop's first cycle overflows: handed back
    assert_same_logs(controllers[0].log, controllers[1].log)
    assert controllers[0]._approach_law._time == controllers[1]._approach_law._time
