"""The compiled engine (``bhgrasp._core``, src/engine.cpp) against the Python reference engine, in lockstep.

Every step of a reference run (the Python engine's) is repeated by the compiled engine from the same state: same
configuration, velocity, contact memory and actuation modes.  Both must agree on the next configuration and
velocity, the contacts (which pairs, points, forces, stick/slip), the contact memory and the delivered drive torques
to 1e-12 (round-off: the two differ in summation order and in the linear solver).  The scenes cover each branch of
the step: fingertip pads on a held box (cylinders and spheres against a box), free flight with gyroscopic spin,
multi-point box-on-plane and box-on-box patches, fast sliding, joint stops, the Barrett transmission with its
TorqueSwitch breaking away, spring-mounted objects with Hunt-Crossley and tanh laws, and the 16-DOF Allegro hand.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from scenes import G, far_hand, incline, off_centre_boxes

import bhgrasp as bh
from bhgrasp.errors import InputError
from bhgrasp.model.objects import Box
from bhgrasp.model.spring_mounted import SpringMounted
from bhgrasp.scenarios.allegro_grasp import allegro_box_grasp
from bhgrasp.scenarios.box_grasp import box_grasp
from bhgrasp.scenarios.hold import reference_hold
from bhgrasp.sim import INTEGRATORS, Simulator
from bhgrasp.sim.actuation import BarrettActuation, FullyActuated
from bhgrasp.sim.contact_law import SpringDamper
from bhgrasp.sim.scene import Scene

TOLERANCE = 1e-12


def twin(simulator: Simulator, engine: str) -> Simulator:
    """The same scene, law, actuation and options with another engine."""
    return Simulator(
        simulator.scene,
        dt=simulator.dt,
        contact=simulator.law,
        actuation=simulator.actuation,
        integrator=simulator.integrator,
        joint_limit_stiffness=simulator.limit_stiffness,
        joint_limit_damping=simulator.limit_damping,
        max_penetration=simulator.max_penetration,
        max_speed=simulator.max_speed,
        engine=engine,
        linear_solver=simulator.settings.linear_solver,
    )


def lockstep(simulator: Simulator, controller, steps: int, state=None) -> dict[str, float]:
    """Largest differences between the engines' steps along the Python engine's run; also counts contacts."""
    python, compiled = twin(simulator, "python"), twin(simulator, "compiled")
    state = python.initial_state() if state is None else state
    worst = {"q": 0.0, "v": 0.0, "force": 0.0, "point": 0.0, "drive": 0.0, "memory": 0.0, "contacts": 0}
    for _ in range(steps):
        u = controller(state.t, state)
        reference, info = python.step(state, u)
        other, other_info = compiled.step(state, u)
        assert other.t == reference.t
        np.testing.assert_array_equal(info.contacts.pair, other_info.contacts.pair)
        np.testing.assert_array_equal(info.contacts.sticking, other_info.contacts.sticking)
        np.testing.assert_array_equal(reference.actuation_modes, other.actuation_modes)
        memory, other_memory = reference.contact_memory, other.contact_memory
        np.testing.assert_array_equal(memory.pair, other_memory.pair)
        np.testing.assert_array_equal(memory.sliding, other_memory.sliding)
        for name, a, b in [
            ("q", reference.scene_q, other.scene_q),
            ("v", reference.scene_v, other.scene_v),
            ("force", info.contacts.force, other_info.contacts.force),
            ("point", info.contacts.point, other_info.contacts.point),
            ("drive", info.drive_torques, other_info.drive_torques),
            ("memory", memory.displacement, other_memory.displacement),
        ]:
            worst[name] = max(worst[name], float(np.abs(a - b).max(initial=0.0)))
        worst["contacts"] = max(worst["contacts"], len(info.contacts))
        state = reference
    return worst


def assert_agree(worst: dict[str, float], contacts: int) -> None:
    assert worst["contacts"] >= contacts, f"the scene should reach {contacts} contacts, got {worst['contacts']}"
    for name in ("q", "v", "force", "point", "drive", "memory"):
        assert worst[name] <= TOLERANCE, f"{name} differs by {worst[name]:.3g} (> {TOLERANCE})"


def zero(n: int):
    return lambda t, state: np.zeros(n)


# ---------------------------------------------------------------------- scenes
def test_reference_hold() -> None:
    """Three fingertip pads squeezing a box under gravity (the benchmark scene), 2000 steps."""
    hold = reference_hold()
    assert_agree(lockstep(hold.simulator, hold.controller, 2000, hold.state), 3)


@pytest.mark.parametrize("integrator", INTEGRATORS)
def test_free_flight_with_spin(integrator: str) -> None:
    """A box tumbling about its intermediate axis (the implicit-midpoint gyroscopic torque; RK4's dexp stages)."""
    box = Box(
        size=(0.08, 0.05, 0.03),
        mass=0.4,
        pose=pin.SE3(pin.rpy.rpyToMatrix(0.3, -0.2, 0.5), np.zeros(3)),
        velocity=[0.5, -0.2, 0.44, 0.4, 15.0, 0.6],
    )
    simulator = Simulator(Scene(far_hand(), [box]), integrator=integrator)
    assert_agree(lockstep(simulator, zero(8), 1000), 0)


@pytest.mark.parametrize("integrator", INTEGRATORS)
def test_off_centre_box_collision(integrator: str) -> None:
    """Two boxes meeting off centre: box-box patches, then they spin apart."""
    simulator = Simulator(Scene(far_hand(), off_centre_boxes()), integrator=integrator)
    assert_agree(lockstep(simulator, zero(8), 300), 2)


@pytest.mark.parametrize("integrator", ["implicit", "semi-implicit"])
def test_box_sliding_down_an_incline(integrator: str) -> None:
    """Four corners sliding at up to 2.8 m/s (multi-point patch depths, kinetic friction, slip memory)."""
    box, plane, law = incline()
    dt = 1e-3 if integrator == "implicit" else 2e-4  # the explicit step needs a smaller step for k = 1e4
    simulator = Simulator(Scene(far_hand((0.0, 0.0, -G)), [box], [plane]), dt=dt, contact=law, integrator=integrator)
    assert_agree(lockstep(simulator, zero(8), 1200), 4)


@pytest.mark.slow  # 18 s
def test_barrett_closing_on_a_box_breaks_away_and_reopens() -> None:
    """The 4-motor transmission in each TorqueSwitch mode: the fingers close on a box, the proximal links block and
    the switches break away (the distal links close alone: mode 1); opening, the tips return to their stops and the
    proximal links open alone (mode 2) until the switches re-arm (mode 0).  Joint damping and Coulomb joint friction
    are on."""
    setup = box_grasp(mass=0.3, actuation="barrett")
    actuation = BarrettActuation(setup.hand, damping=0.01, friction=0.002)
    simulator = Simulator(
        setup.simulator.scene, dt=setup.simulator.dt, contact=setup.simulator.law, actuation=actuation, engine="python"
    )
    state = simulator.initial_state(setup.q_start)
    close = lambda t, s: np.array([0.02, 0.11, 0.11, 0.11])  # noqa: E731
    opening = lambda t, s: np.array([0.0, -0.11, -0.11, -0.11])  # noqa: E731
    assert_agree(lockstep(simulator, close, 1500, state), 3)
    closed = simulator.run(close, 1.5, state=state, progress=False)
    assert (closed.modes[-1, :3] == 1).all()  # every TorqueSwitch broke away within the compared span
    for _ in range(1500):
        state, _ = simulator.step(state, close(state.t, state))
    assert_agree(lockstep(simulator, opening, 1200, state), 0)
    opened = simulator.run(opening, 1.2, state=state, progress=False)
    assert (opened.modes[:, :3] == 2).any() and (opened.modes[-1, :3] == 0).all()  # re-opened and re-armed


@pytest.mark.parametrize("linear_solver", ["dense", "sparse"])
def test_fingers_against_their_joint_stops_and_a_spring_mounted_object(linear_solver: str) -> None:
    """Joint stops (a finger driven past its limit), a spring-mounted object, Hunt-Crossley normal law; the velocity
    solve dense and by parts (a part of one velocity, bhgrasp.sim.part_system)."""
    hand = bh.BarrettHand()
    tip = hand.fingertip_positions(hand.configuration(F3_proximal=1.0))[hand.fingers.index("F3")]
    body = Box(size=(0.04, 0.04, 0.01), mass=0.1, pose=pin.SE3(np.eye(3), tip + np.array([0.0, 0.0, 0.006])))
    plate = SpringMounted(body=body, direction=np.array([0.0, 0.0, 1.0]), stiffness=200.0, damping=2.0)
    law = SpringDamper(stiffness=2e4, damping=50.0, normal_law="hunt-crossley", exponent=1.5)
    drive = FullyActuated(hand, damping=0.02)  # the finger starts 5.6 mm into the plate on purpose: no warning
    simulator = Simulator(
        Scene(hand, [plate]), contact=law, actuation=drive, start_check="off", linear_solver=linear_solver
    )
    torque = np.zeros(8)
    torque[hand.joint_index("F3_proximal")] = 0.3
    torque[hand.joint_index("F1_distal")] = 0.3  # against its upper stop
    state = simulator.initial_state(hand.configuration(F3_proximal=0.9))
    assert_agree(lockstep(simulator, lambda t, s: torque, 800, state), 1)


def test_tanh_friction_law() -> None:
    """The regularised friction law on the reference hold."""
    hold = reference_hold()
    law = SpringDamper(stiffness=1e4, damping=20.0, friction=0.8, friction_law="tanh", slip_velocity=1e-3)
    simulator = Simulator(hold.simulator.scene, dt=1e-3, contact=law, actuation=hold.simulator.actuation)
    assert_agree(lockstep(simulator, hold.controller, 500, hold.state), 3)


@pytest.mark.parametrize("linear_solver", ["dense", "sparse"])
def test_allegro_hand_closing_on_a_box(linear_solver: str) -> None:
    """The 16-DOF Allegro hand of example-robot-data (mesh-free primitives of its own URDF) closing on a box; the
    velocity solve dense and by parts (every joint driven: the identity transmission)."""
    setup = allegro_box_grasp()
    simulator, hand = setup.simulator.with_settings(linear_solver=linear_solver), setup.hand
    target = setup.q_close

    def close(t, state):
        return hand.gravity_torques(state.q) + 0.5 * (target - state.q) - 0.02 * state.v

    assert_agree(lockstep(simulator, close, 1500, setup.state), 2)


# ---------------------------------------------------------------------- the engine option
def test_engine_option_is_checked_and_compiled_is_the_default() -> None:
    hold = reference_hold()
    assert hold.simulator.engine_name == "compiled"
    with pytest.raises(InputError, match="`engine` must be one of"):
        Simulator(hold.simulator.scene, engine="fortran")


def test_a_missing_compiled_core_says_how_to_rebuild(monkeypatch: pytest.MonkeyPatch) -> None:
    import bhgrasp

    hold = reference_hold()
    monkeypatch.setitem(__import__("sys").modules, "bhgrasp._core", None)  # import of it now fails
    monkeypatch.delattr(bhgrasp, "_core", raising=False)
    with pytest.raises(bh.CompiledEngineUnavailable, match=r"pip install -e \.|engine='python'"):
        Simulator(hold.simulator.scene)
    assert Simulator(hold.simulator.scene, engine="python").engine_name == "python"  # the reference still runs


def test_changed_actuation_parameters_reach_the_compiled_step() -> None:
    """The compiled step caches the actuation's transmission and damping; a changed damping must not be missed."""
    hold = reference_hold()
    python, compiled = twin(hold.simulator, "python"), twin(hold.simulator, "compiled")
    u = hold.controller(hold.state.t, hold.state)
    compiled.step(hold.state, u)  # caches the drive
    hold.simulator.actuation.damping = hold.simulator.actuation.damping * 3.0
    reference, _ = python.step(hold.state, u)
    other, _ = compiled.step(hold.state, u)
    np.testing.assert_allclose(other.scene_v, reference.scene_v, rtol=0, atol=TOLERANCE)


def test_the_recorders_join_is_its_numpy_twin(monkeypatch: pytest.MonkeyPatch) -> None:
    """A compiled run's contacts, joined in C++ (src/recording.cpp) and by NumPy: the same arrays, bit for bit."""
    from bhgrasp import _native
    from bhgrasp.sim.recorder import Recorder

    hold = reference_hold()
    state, parts = hold.state, []
    for _ in range(300):
        state, info = hold.simulator.step(state, hold.controller(state.t, state))
        parts.append(info.contact_arrays)
    assert sum(len(part) for part in parts) >= 900  # three pads in contact throughout
    recorder = Recorder(hold.simulator.scene, hold.simulator.actuation)
    joined = recorder._contact_arrays(parts)
    monkeypatch.setattr(_native, "DEFAULT_ENGINE", "python")
    python = recorder._contact_arrays(parts)
    assert joined.keys() == python.keys()
    for name in joined:
        assert joined[name].dtype == python[name].dtype and np.array_equal(joined[name], python[name]), name
