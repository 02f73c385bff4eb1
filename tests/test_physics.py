"""Trust in the physics (issue 14): free bodies, sliding contacts and re-runs against independent truths.

- Torque-free flight: linear velocity kept exactly, kinetic energy never gained, angular momentum (world frame)
  kept to O(dt) without growth (Euler's equations conserve it; the integrators' errors must not pump it).
- Off-centre collisions of two boxes: total linear momentum conserved to round-off (Newton's third law).
- A box sliding fast down an incline keeps all four corners loaded, with the closed-form load split of a sliding
  block (the friction moment shifts load to the leading edge), at every stable step.
- A run depends only on its inputs: the start state carries the contact memory and the actuation modes.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pinocchio as pin
import pytest
from scenes import G, far_hand, incline, off_centre_boxes

import bhgrasp as bh
from bhgrasp.data import ContactMemory
from bhgrasp.model.objects import Box, Sphere
from bhgrasp.scenarios.hold import reference_hold
from bhgrasp.sim import INTEGRATORS, Simulator
from bhgrasp.sim.actuation import BarrettActuation
from bhgrasp.sim.scene import Scene

Z = np.array([0.0, 0.0, 1.0])


def _fly(body, integrator: str, dt: float, duration: float):
    """States of a lone body in zero gravity, one per step."""
    sim = Simulator(Scene(far_hand(), [body]), dt=dt, integrator=integrator)
    state = sim.initial_state()
    states = [state]
    for _ in range(round(duration / dt)):
        state, _ = sim.step(state, np.zeros(8))
        states.append(state)
    return states


# ---------------------------------------------------------------------- torque-free flight
@pytest.mark.parametrize("integrator", INTEGRATORS)
def test_spinning_sphere_keeps_its_velocity(integrator: str) -> None:
    """The issue's case: 1 m/s and 20 rad/s; before the fix the implicit steps reached 1.22 m/s in 1 s."""
    sphere = Sphere(radius=0.04, mass=0.3, pose=pin.SE3.Identity(), velocity=[1.0, 0.0, 0.0, 0.0, 3.0, 20.0])
    states = _fly(sphere, integrator, 1e-3, 1.0)
    twists = np.array([s.object_twists[0] for s in states])
    np.testing.assert_allclose(twists[:, :3], [[1.0, 0.0, 0.0]] * len(twists), rtol=0, atol=1e-15)
    np.testing.assert_allclose(twists[:, 3:], [[0.0, 3.0, 20.0]] * len(twists), rtol=0, atol=1e-12)
    np.testing.assert_allclose(states[-1].object_poses[0].translation, [1.0, 0.0, 0.0], atol=1e-12)


def _tumbling_box(dt: float, integrator: str, duration: float):
    """A box spinning near its intermediate axis (unstable: it tumbles), moving at 0.7 m/s."""
    box = Box(
        size=(0.08, 0.05, 0.03),
        mass=0.4,
        pose=pin.SE3(pin.rpy.rpyToMatrix(0.3, -0.2, 0.5), np.zeros(3)),
        velocity=[0.5, -0.2, 0.44, 0.4, 15.0, 0.6],
    )
    inertia = box.spatial_inertia().inertia
    states = _fly(box, integrator, dt, duration)
    rotations = [s.object_poses[0].rotation for s in states]
    omega_body = np.array([r.T @ s.object_twists[0, 3:] for r, s in zip(rotations, states)])
    energy = 0.5 * np.einsum("ti,ij,tj->t", omega_body, inertia, omega_body)
    momentum = np.array([r @ inertia @ w for r, w in zip(rotations, omega_body)])  # world angular momentum
    linear = np.array([s.object_twists[0, :3] for s in states])
    return energy, momentum, linear, omega_body


@pytest.mark.parametrize("integrator", ["implicit", "semi-implicit"])
def test_tumbling_box_never_gains_energy_and_keeps_angular_momentum(integrator: str) -> None:
    """Implicit-midpoint gyroscopic torque: energy and |I w| exact at every step; the world angular momentum's
    error is O(dt) (halves with dt) and does not grow with time (the same after 1 s as after 4 s)."""
    errors = {}
    for dt in (2e-3, 1e-3):
        energy, momentum, linear, omega = _tumbling_box(dt, integrator, 4.0)
        assert np.ptp(omega[:, 1]) > 10.0  # it really tumbles (the spin axis flips)
        assert np.diff(energy).max() <= 1e-13 * energy[0]  # no step gains energy
        assert abs(energy[-1] / energy[0] - 1.0) < 1e-12
        assert np.abs(linear - linear[0]).max() < 1e-15  # no force: kept to round-off, no drift
        error = np.linalg.norm(momentum - momentum[0], axis=1) / np.linalg.norm(momentum[0])
        first_second = error[: round(1.0 / dt) + 1].max()
        assert error.max() < 1.25 * first_second  # bounded, no drift growth
        errors[dt] = error.max()
    assert errors[1e-3] < 0.02
    assert 0.4 < errors[1e-3] / errors[2e-3] < 0.6  # first order in dt


def test_tumbling_box_rk4_is_fourth_order() -> None:
    """RK4 (Munthe-Kaas on the bodies' rotations): energy and world angular momentum errors O(dt^4).

    Adding the stages' body rates on SO(3) instead was second order: 1.3e-5 of |L| in 2 s at 1 ms.
    """
    errors = []
    for dt in (1e-3, 5e-4):
        energy, momentum, linear, _ = _tumbling_box(dt, "rk4", 2.0)
        assert np.abs(energy / energy[0] - 1.0).max() < 1e-10
        assert np.abs(linear - linear[0]).max() < 1e-15
        errors.append(np.linalg.norm(momentum - momentum[0], axis=1).max() / np.linalg.norm(momentum[0]))
    assert errors[0] < 1e-9
    assert 1 / 24 < errors[1] / errors[0] < 1 / 10


# ---------------------------------------------------------------------- collisions
@pytest.mark.parametrize("integrator", INTEGRATORS)
def test_off_centre_box_collision_conserves_linear_momentum(integrator: str) -> None:
    """The issue's case (before: 8e-3 of sum m |v| with the default integrators, 3e-4 with RK4)."""
    sim = Simulator(Scene(far_hand(), off_centre_boxes()), dt=1e-3, integrator=integrator)
    trajectory = sim.run(lambda t, s: np.zeros(8), 0.3, progress=False)
    assert trajectory.contact_count().max() >= 2
    assert np.abs(trajectory.object_twist[-1, :, 3:]).max() > 1.0  # off centre: they spin
    momentum = np.einsum("o,toi->ti", np.array([0.3, 0.5]), trajectory.object_twist[:, :, :3])
    assert np.abs(momentum - momentum[0]).max() < 1e-14 * (0.3 * 0.5 + 0.5 * 0.5)


# ---------------------------------------------------------------------- fast sliding
def _fast_slide(dt: float, duration: float = 1.2, mu: float = 0.3, theta: float = np.radians(30.0)):
    """A 0.2 kg box released on a 30 deg incline with mu = 0.3: it accelerates past 2.8 m/s in 1.2 s."""
    box, plane, law = incline(mu, theta)
    sim = Simulator(Scene(far_hand((0.0, 0.0, -G)), [box], [plane]), dt=dt, contact=law)
    return sim.run(lambda t, s: np.zeros(8), duration, progress=False)


@pytest.mark.parametrize("dt", [2e-3, 1e-3, 5e-4])
def test_fast_sliding_box_keeps_four_corners_loaded(dt: float) -> None:
    """Before the fix, at 1 ms the trailing corners unloaded to 0 N past ~1.7 m/s and the box rocked.

    Independent truths: the sliding block's acceleration g (sin - mu cos), and its corner loads: the friction
    mu N acting h/2 below the centre of mass is balanced by shifting mu N h / L of the normal load N to the
    leading edge, so each trailing corner carries (N - mu N h / L) / 4.
    """
    mu, theta, h, length = 0.3, np.radians(30.0), 0.05, 0.06
    trajectory = _fast_slide(dt)
    sliding = trajectory.between(0.2, 1.2)
    speed = np.linalg.norm(sliding.object_twist[:, 0, :3], axis=1)
    assert speed[-1] > 2.5
    assert np.abs(sliding.object_twist[:, 0, 3:]).max() < 1e-3  # no rocking [rad/s]
    assert (sliding.contact_count() == 4).all()
    normal_load = 0.2 * G * np.cos(theta)
    trailing = (normal_load - mu * normal_load * h / length) / 4
    leading = (normal_load + mu * normal_load * h / length) / 4
    for k in range(0, len(sliding), 50):
        contacts = sliding.contacts_at(k)
        f_n = np.sort(np.einsum("ij,ij->i", contacts["force"], contacts["normal"]))
        np.testing.assert_allclose(f_n, [trailing] * 2 + [leading] * 2, rtol=2e-3)
        assert not contacts["sticking"].any()
    acceleration = 2 * np.polyfit(sliding.t, sliding.object_position[:, 0, 0], 2)[0] / np.cos(theta)
    assert acceleration == pytest.approx(G * (np.sin(theta) - mu * np.cos(theta)), rel=2e-3)


def test_sliding_box_stops_and_sticks_on_a_flat_table() -> None:
    """A sliding contact may stick again: a box launched at 1 m/s on a table (mu = 0.5) stops after v^2/(2 mu g)."""
    rest = np.array([0.0, 0.0, 0.025 - 0.2 * G / 1e4])
    box = Box(
        size=(0.06, 0.05, 0.05), mass=0.2, friction=0.5, pose=pin.SE3(np.eye(3), rest), velocity=[1, 0, 0, 0, 0, 0]
    )
    sim = Simulator(Scene(far_hand((0.0, 0.0, -G)), [box], [bh.table(friction=0.5)]), dt=1e-3)
    trajectory = sim.run(lambda t, s: np.zeros(8), 0.5, progress=False)
    stop = 1.0**2 / (2 * 0.5 * G)
    assert trajectory.object_position[-1, 0, 0] == pytest.approx(stop, abs=2e-3)
    late = trajectory.between(0.4, 0.5)
    assert late.contact_sticking.all()
    assert np.abs(late.object_twist[:, 0, :3]).max() < 1e-4  # the anchored tangential springs ring down


# ---------------------------------------------------------------------- re-runs
def test_rerun_from_the_same_state_is_bit_identical() -> None:
    """Before the fix, a second run from the same State started from the first run's contact memory (82 um and
    0.55 N apart).  Now the state carries the memory: same state, same bits."""
    hold = reference_hold(dt=1e-3)
    sim, state = hold.simulator, hold.state
    for _ in range(200):  # a state in the middle of a hold, with anchored tangential springs
        state, _ = sim.step(state, hold.controller(state.t, state))
    assert len(state.contact_memory) >= 3 and np.abs(state.contact_memory.displacement).max() > 0
    first = sim.run(hold.controller, 0.3, state=state, progress=False)
    sim.run(hold.controller, 0.2, state=hold.state, progress=False)  # anything in between
    second = sim.run(hold.controller, 0.3, state=state, progress=False)
    for name in ("q", "v", "u", "object_position", "contact_force", "contact_sticking"):
        np.testing.assert_array_equal(getattr(first, name), getattr(second, name))
    cleared = sim.run(hold.controller, 0.3, state=dataclasses.replace(state, contact_memory=None), progress=False)
    assert not np.array_equal(cleared.contact_force, first.contact_force)  # the memory matters, and it is the state's


def test_rerun_keeps_the_torque_switch_modes_of_its_state() -> None:
    """A Barrett finger closing on the palm breaks away; a run from a state after breakaway continues broken."""
    hand = bh.BarrettHand()
    sim = Simulator(Scene(hand), dt=1e-3, actuation=BarrettActuation(hand))
    state = sim.initial_state(hand.configuration(F3_proximal=hand.upper[hand.joint_index("F3_proximal")] - 0.05))
    for _ in range(300):
        state, _ = sim.step(state, np.array([0.0, 0.0, 0.0, 0.05]))
    assert state.actuation_modes[2] == 1  # F3 broke away
    runs = [sim.run(lambda t, s: np.array([0.0, 0.0, 0.0, 0.05]), 0.1, state=state, progress=False) for _ in "ab"]
    sim.run(lambda t, s: np.zeros(4), 0.1, progress=False)  # a fresh run re-arms the simulator's actuation
    third = sim.run(lambda t, s: np.array([0.0, 0.0, 0.0, 0.05]), 0.1, state=state, progress=False)
    for run in [*runs[1:], third]:
        np.testing.assert_array_equal(run.q, runs[0].q)
        np.testing.assert_array_equal(run.modes, runs[0].modes)
    assert (runs[0].modes[:, 2] == 1).all()


def test_grasp_rerun_with_the_same_controller_repeats_to_round_off() -> None:
    """The supervisor, the SMC-adaptive law (estimates, integrals, QP warm starts) and their logs restart with the
    run: before, the second run's log carried the first run's grasp values into its approach phase.

    Not bit for bit: within one process the second run's arrays sit at other addresses, and NumPy's SIMD
    reductions sum in an order that depends on alignment (a replay of the controller with other allocations in
    between moved its torque by 1e-16 relative at a single step); the runs then agree to ~1e-13.
    """
    from bhgrasp.controllers.adaptive_grasp import SMCAdaptiveGrasp
    from bhgrasp.controllers.grasp_options import GraspOptions
    from bhgrasp.controllers.supervisor import GraspSupervisor
    from bhgrasp.scenarios.box_grasp import box_grasp

    setup = box_grasp(mass=0.6)
    grasp = SMCAdaptiveGrasp(
        setup.hand, bh.Box(size=setup.box.size, mass=0.3), options=GraspOptions(mu=0.6, squeeze=5.0)
    )
    supervisor = GraspSupervisor(setup.hand, setup.q_contact, grasp, offset=(0, 0, 0.01, 0.1, 0, 0))
    first = setup.simulator.run(supervisor, 1.0, state=setup.state, progress=False)
    second = setup.simulator.run(supervisor, 1.0, state=setup.state, progress=False)
    assert np.nanmax(first.log["phase"]) == 2  # it grasped and began the motion
    for name, tolerance in (("q", 1e-12), ("v", 1e-10), ("u", 1e-10), ("object_position", 1e-12)):
        np.testing.assert_allclose(getattr(first, name), getattr(second, name), rtol=0, atol=tolerance, err_msg=name)
    np.testing.assert_array_equal(first.contact_offsets, second.contact_offsets)
    np.testing.assert_allclose(first.contact_force, second.contact_force, rtol=0, atol=1e-9)
    assert first.log.keys() == second.log.keys()
    for name in first.log:  # NaN where a controller did not log yet: the same samples in both runs
        np.testing.assert_allclose(first.log[name], second.log[name], rtol=1e-9, atol=1e-9, err_msg=name)


@pytest.mark.parametrize("engine_name", ["compiled", "python"])
def test_contact_detection_does_not_depend_on_what_was_detected_before(engine_name: str) -> None:
    """A box flush on its pedestal gave a 4-corner patch, or a 1-point patch after another configuration had been
    queried (coal's GJK guesses, stored in Pinocchio's collision requests, carried from call to call)."""
    from bhgrasp.scenarios.box_grasp import box_grasp

    setup = box_grasp(mass=0.6)
    simulator = setup.simulator.with_settings(engine=engine_name)
    engine, scene = simulator.engine, simulator.scene
    box = scene.object_q_slice(0)

    def placed(q, tilt: float, lift: float) -> np.ndarray:
        pose = pin.XYZQUATToSE3(q[box])
        q = q.copy()
        q[box] = pin.SE3ToXYZQUAT(pin.SE3(pin.rpy.rpyToMatrix(tilt, 0, 0) @ pose.rotation, pose.translation + lift * Z))
        return q

    def detect(q):
        contacts = engine.detect(q, ContactMemory.empty())
        return np.concatenate((contacts.pair, contacts.point.ravel(), contacts.normal.ravel(), contacts.depth))

    resting = placed(setup.state.scene_q, 0.0, -2e-5)  # 20 um into the pedestal
    fresh = detect(resting)
    assert len(fresh) == 4 * 8  # one patch: the 4 corners of the box's bottom face
    for tilt, lift in ((0.05, 1e-3), (0.1, 0.0), (0.0, 1e-4), (0.3, 5e-3), (0.01, -1e-4)):
        other = placed(setup.state.scene_q, tilt, lift)  # any other configuration in between
        engine.detect(other, ContactMemory.empty())
        np.testing.assert_array_equal(detect(resting), fresh)


@pytest.mark.parametrize("engine_name", ["compiled", "python"])
def test_flush_box_contact_normal_is_the_face_normal(engine_name: str) -> None:
    """Coal's default GJK/EPA tolerance (1e-6) tilted the normal of a box flush on its pedestal by up to 0.027;
    the narrow phase now runs to 1e-10: over random sub-micrometre offsets the normal is +z to 1e-8."""
    from bhgrasp.scenarios.box_grasp import box_grasp

    setup = box_grasp(mass=0.6)
    simulator = setup.simulator.with_settings(engine=engine_name)
    engine, scene = simulator.engine, simulator.scene
    box = scene.object_q_slice(0)
    rng = np.random.default_rng(3)
    errors = []
    for _ in range(100):
        q = setup.state.scene_q.copy()
        pose = pin.XYZQUATToSE3(q[box])
        tilt = pin.rpy.rpyToMatrix(*(1e-9 * rng.standard_normal(3)))
        shift = np.append(1e-4 * rng.standard_normal(2), -2e-5)  # sideways, and 20 um into the pedestal
        q[box] = pin.SE3ToXYZQUAT(pin.SE3(tilt @ pose.rotation, pose.translation + shift))
        contacts = engine.detect(q, ContactMemory.empty())
        assert len(contacts) == 4
        errors.append(np.abs(contacts.normal - Z).max())
    assert max(errors) < 1e-8
