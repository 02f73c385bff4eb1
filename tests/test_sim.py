"""The simulator against independent truths: kinematics of free fall, statics, conservation laws, friction.

Scenes keep the hand out of the way (base 5 m away, gravity-compensated) unless the hand is what is tested.
"""

from __future__ import annotations

import warnings

import numpy as np
import pinocchio as pin
import pytest
import scenes
from scenes import G

import bhgrasp as bh
from bhgrasp.data import Trajectory
from bhgrasp.errors import SimulationDiverged
from bhgrasp.model.objects import Box, Sphere, table
from bhgrasp.model.planar import planar_finger
from bhgrasp.scenarios.hold import reference_hold
from bhgrasp.sim import Simulator
from bhgrasp.sim.contact_law import SpringDamper
from bhgrasp.sim.scene import Scene
from bhgrasp.sim.start_check import StartWarning


def far_hand(gravity=(0.0, 0.0, -G)) -> bh.Hand:
    """The hand of :func:`scenes.far_hand`, under gravity by default here."""
    return scenes.far_hand(gravity)


def hold_hand(hand: bh.Hand):
    return lambda t, state: hand.gravity_torques(state.q)


def at(pose_z: float, **kwargs) -> pin.SE3:
    return pin.SE3(np.eye(3), np.array([0.0, 0.0, pose_z]))


# ---------------------------------------------------------------------- free fall
@pytest.mark.parametrize("integrator", ["implicit", "semi-implicit", "rk4"])
def test_free_fall(integrator: str) -> None:
    """RK4 is exact for constant acceleration; the Euler schemes follow their own discrete law exactly."""
    hand = far_hand()
    ball = Sphere(radius=0.02, mass=0.1, pose=at(1.0))
    dt = 1e-3
    sim = Simulator(Scene(hand, [ball]), dt=dt, integrator=integrator)
    trajectory = sim.run(hold_hand(hand), 0.5, progress=False)
    k = np.arange(len(trajectory.t))
    if integrator == "rk4":
        expected = 1.0 - G * trajectory.t**2 / 2
    else:  # v_k = -g k dt, z_k = z_0 - g dt^2 k (k + 1) / 2
        expected = 1.0 - G * dt**2 * k * (k + 1) / 2
    np.testing.assert_allclose(trajectory.object_position[:, 0, 2], expected, atol=1e-12)
    assert len(trajectory.contact_pair) == 0


# ---------------------------------------------------------------------- resting contact
@pytest.mark.parametrize(
    ("law", "expected_depth"),
    [
        (SpringDamper(stiffness=1e4, damping=20.0), 0.1 * G / 1e4),
        (SpringDamper(stiffness=5e4, damping=20.0), 0.1 * G / 5e4),
        (SpringDamper(stiffness=1e6, damping=50.0, normal_law="hunt-crossley"), (0.1 * G / 1e6) ** (1 / 1.5)),
    ],
)
def test_sphere_rests_at_the_static_depth(law: SpringDamper, expected_depth: float) -> None:
    hand = far_hand()
    ball = Sphere(radius=0.02, mass=0.1, pose=at(0.02))
    sim = Simulator(Scene(hand, [ball], [table()]), dt=1e-3, contact=law)
    trajectory = sim.run(hold_hand(hand), 1.0, progress=False)
    depth = 0.02 - trajectory.object_position[-1, 0, 2]
    assert depth == pytest.approx(expected_depth, rel=1e-6)
    contact = trajectory.contacts_at(len(trajectory) - 1)
    np.testing.assert_allclose(contact["force"].sum(axis=0), [0.0, 0.0, 0.1 * G], rtol=1e-6, atol=1e-9)


def test_box_face_contact_stiffness_is_per_patch() -> None:
    """Coal reports 4 corner points for a box face; together they are one spring of stiffness k."""
    hand = far_hand()
    box = Box(size=(0.06, 0.05, 0.05), mass=0.2, pose=at(0.025))
    sim = Simulator(Scene(hand, [box], [table()]), dt=1e-3, contact=SpringDamper(stiffness=1e4))
    trajectory = sim.run(hold_hand(hand), 1.0, progress=False)
    assert trajectory.contact_count()[-1] == 4
    assert 0.025 - trajectory.object_position[-1, 0, 2] == pytest.approx(0.2 * G / 1e4, rel=1e-6)


def test_implicit_contact_is_stable_where_explicit_is_not() -> None:
    """k = 5e4 N/m on a 10 g sphere dropped 0.1 mm, dt = 1 ms (omega dt = 2.2 > 2): symplectic Euler pumps energy
    into the contact and throws the ball ~15 cm up; the linearly-implicit step rests at m g / k."""
    hand = far_hand()
    ball = Sphere(radius=0.01, mass=0.01, pose=at(0.0101))
    law = SpringDamper(stiffness=5e4, damping=1.0)
    implicit = Simulator(Scene(hand, [ball], [table()]), dt=1e-3, contact=law).run(hold_hand(hand), 0.5, progress=False)
    assert 0.01 - implicit.object_position[-1, 0, 2] == pytest.approx(0.01 * G / 5e4, rel=1e-5)
    assert implicit.object_position[:, 0, 2].max() <= 0.0101 + 1e-12  # never above its release height
    explicit = Simulator(Scene(hand, [ball], [table()]), dt=1e-3, contact=law, integrator="semi-implicit")
    with pytest.warns(StartWarning, match="too fast for the semi-implicit step at dt = 0.001 s: dt < 0.000894"):
        bounced = explicit.run(hold_hand(hand), 0.5, progress=False)  # the start check foresees it: 2 sqrt(m / k)
    assert bounced.object_position[:, 0, 2].max() > 0.05  # energy from nowhere: the explicit step is unstable
    halved = Simulator(Scene(hand, [ball], [table()]), dt=5e-4, contact=law, integrator="semi-implicit")
    with warnings.catch_warnings():
        warnings.simplefilter("error", StartWarning)  # within the bound: nothing to say
        settled = halved.run(hold_hand(hand), 0.5, progress=False)
    assert 0.01 - settled.object_position[-1, 0, 2] == pytest.approx(0.01 * G / 5e4, rel=1e-3)


# ---------------------------------------------------------------------- conservation laws
def _energy_run(integrator: str, dt: float) -> tuple[np.ndarray, float]:
    finger = planar_finger((0.1, 0.08), (0.1, 0.05))  # a double pendulum: gravity along -y, in its plane
    box = Box(
        size=(0.06, 0.04, 0.02),
        mass=0.2,
        pose=pin.SE3(np.eye(3), np.array([1.0, 0.0, 0.0])),
        velocity=np.array([0.1, 0.5, 0.0, 0.2, 8.0, 0.3]),  # tumbling about the intermediate axis
    )
    scene = Scene(finger, [box])
    sim = Simulator(scene, dt=dt, integrator=integrator)
    state = sim.initial_state(np.array([-np.pi / 2 + 0.6, 0.4]))
    energies, kinetic = [], []
    for _ in range(round(2.0 / dt)):
        state, _ = sim.step(state, np.zeros(2))
        energies.append(scene.energy(state.scene_q, state.scene_v))
        kinetic.append(pin.computeKineticEnergy(scene.model, scene.data, state.scene_q, state.scene_v))
    return np.array(energies), float(np.max(kinetic))


def test_energy_is_conserved_by_rk4() -> None:
    energies, kinetic_scale = _energy_run("rk4", 1e-3)
    assert np.abs(energies - energies[0]).max() < 1e-4 * kinetic_scale


def test_semi_implicit_energy_error_is_bounded_and_first_order() -> None:
    """Symplectic Euler: energy error stays small and halves with the step (first order), it does not blow up."""
    coarse, kinetic_scale = _energy_run("semi-implicit", 1e-3)
    fine, _ = _energy_run("semi-implicit", 5e-4)
    coarse_drift, fine_drift = np.abs(coarse - coarse[0]).max(), np.abs(fine - fine[0]).max()
    assert coarse_drift < 1e-2 * kinetic_scale
    assert 0.4 < fine_drift / coarse_drift < 0.6


def _collision_momentum(integrator: str, friction: float, dt: float) -> tuple[np.ndarray, Trajectory]:
    """Two spheres collide off-centre in zero gravity; returns each sample's total linear momentum."""
    hand = far_hand(gravity=(0.0, 0.0, 0.0))
    first = Sphere(radius=0.02, mass=0.3, friction=friction, pose=at(0.0), velocity=np.array([0.5, 0, 0, 0, 0, 0]))
    second = Sphere(
        radius=0.03,
        mass=0.1,
        friction=friction,
        pose=pin.SE3(np.eye(3), np.array([0.1, 0.02, 0.0])),
        velocity=np.array([-0.2, 0.0, 0.1, 0.0, 0.0, 0.0]),
    )
    sim = Simulator(
        Scene(hand, [first, second]),
        dt=dt,
        integrator=integrator,
        contact=SpringDamper(stiffness=1e4, damping=5.0, friction=friction),
    )
    trajectory = sim.run(hold_hand(hand), 0.3, progress=False)
    assert trajectory.contact_count().max() >= 1  # they did collide
    return np.einsum("o,toi->ti", np.array([0.3, 0.1]), trajectory.object_twist[:, :, :3]), trajectory


@pytest.mark.parametrize("friction", [0.0, 0.8])
@pytest.mark.parametrize("integrator", ["implicit", "semi-implicit", "rk4"])
def test_collision_conserves_momentum(integrator: str, friction: float) -> None:
    """Newton's third law: equal and opposite contact forces, friction included, leave the total linear momentum
    unchanged to round-off (translations are integrated world-aligned: no body-frame Coriolis term)."""
    momentum, trajectory = _collision_momentum(integrator, friction, 1e-4)
    scale = 0.3 * 0.5 + 0.1 * np.hypot(0.2, 0.1)  # sum m |v| [kg m/s]
    assert np.abs(momentum - momentum[0]).max() < 1e-13 * scale
    assert not np.allclose(trajectory.object_twist[-1, 0, :3], trajectory.object_twist[0, 0, :3])  # it changed
    if friction:
        assert np.abs(trajectory.object_twist[-1, :, 3:]).max() > 1.0  # friction spun them up [rad/s]


# ---------------------------------------------------------------------- friction
def _incline(theta_degrees: float, integrator: str = "implicit", dt: float = 1e-3, duration: float = 2.0) -> Trajectory:
    theta = np.radians(theta_degrees)
    hand = far_hand(gravity=(G * np.sin(theta), 0.0, -G * np.cos(theta)))  # tilting gravity = tilting the plane
    box = Box(size=(0.06, 0.05, 0.05), mass=0.2, friction=0.5, pose=at(0.025 - 0.2 * G * np.cos(theta) / 1e4))
    scene = Scene(hand, [box], [table(friction=0.5)])
    sim = Simulator(scene, dt=dt, integrator=integrator, contact=SpringDamper(stiffness=1e4, damping=20.0))
    return sim.run(hold_hand(hand), duration, progress=False)


@pytest.mark.parametrize("integrator", ["implicit", "semi-implicit"])
def test_box_sticks_on_a_plane_flatter_than_its_friction_angle(integrator: str) -> None:
    """tan(20 deg) = 0.36 < mu = 0.5: after settling the box creeps < 1 micrometre per second."""
    dt = 1e-3 if integrator == "implicit" else 2e-4
    trajectory = _incline(20.0, integrator, dt, duration=1.5)
    late = trajectory.between(0.5, 1.5)
    creep = np.linalg.norm(late.object_position[-1, 0] - late.object_position[0, 0]) / 1.0
    assert creep < 1e-6
    assert late.contact_sticking.all()


@pytest.mark.parametrize("integrator", ["implicit", "semi-implicit"])
def test_box_slides_with_coulomb_deceleration(integrator: str) -> None:
    """tan(35 deg) = 0.70 > mu = 0.5: a = g (sin(theta) - mu cos(theta)) = 1.609 m/s^2."""
    dt = 1e-3 if integrator == "implicit" else 2e-4
    trajectory = _incline(35.0, integrator, dt, duration=1.0).between(0.3, 1.0)
    acceleration = 2 * np.polyfit(trajectory.t, trajectory.object_position[:, 0, 0], 2)[0]
    theta = np.radians(35.0)
    assert acceleration == pytest.approx(G * (np.sin(theta) - 0.5 * np.cos(theta)), rel=1e-3)
    assert not trajectory.contact_sticking.any()


def test_regularised_friction_creeps_where_stick_slip_holds() -> None:
    """The tanh law needs slip velocity to make friction: on the 20 deg incline it creeps (the reason for stick)."""
    theta = np.radians(20.0)
    hand = far_hand(gravity=(G * np.sin(theta), 0.0, -G * np.cos(theta)))
    box = Box(size=(0.06, 0.05, 0.05), mass=0.2, friction=0.5, pose=at(0.025 - 0.2 * G * np.cos(theta) / 1e4))
    law = SpringDamper(stiffness=1e4, damping=20.0, friction_law="tanh", slip_velocity=1e-3)
    sim = Simulator(Scene(hand, [box], [table(friction=0.5)]), dt=2e-4, contact=law, integrator="semi-implicit")
    late = sim.run(hold_hand(hand), 1.0, progress=False).between(0.5, 1.0)
    creep = np.linalg.norm(late.object_position[-1, 0] - late.object_position[0, 0]) / 0.5
    assert creep > 1e-5  # tens of micrometres per second or more


def test_three_finger_hold_does_not_creep() -> None:
    """Barrett F1 + F2 against F3 squeeze a 0.2 kg box (friction margin > 3): creep < 1 micrometre/s over 2 s."""
    hold = reference_hold(dt=1e-3)
    trajectory = hold.simulator.run(hold.controller, 2.5, state=hold.state, progress=False)
    held = trajectory.between(0.5, 2.5)
    creep = np.linalg.norm(held.object_position[-1, 0] - held.object_position[0, 0]) / 2.0
    assert creep < 1e-6
    last = held.contacts_at(len(held) - 1)
    assert sorted(last["bodies"][:, 0]) == ["F1_distal_link", "F2_distal_link", "F3_distal_link"]
    normal_forces = np.einsum("ij,ij->i", last["force"], last["normal"])
    assert 0.8 * normal_forces.sum() > 3 * 0.2 * G  # the friction margin the test claims
    np.testing.assert_allclose(last["force"].sum(axis=0), [0.0, 0.0, 0.2 * G], atol=1e-6)  # statics of the box
    assert last["sticking"].all()


# ---------------------------------------------------------------------- determinism and divergence
def test_same_seed_same_trajectory_bit_for_bit() -> None:
    hand = far_hand()
    scene = Scene(hand, [Box(size=(0.06, 0.05, 0.05), mass=0.2, pose=at(0.03))], [table()])

    def run(seed: int) -> Trajectory:
        sim = Simulator(scene, dt=1e-3)
        return sim.run(
            lambda t, s: hand.gravity_torques(s.q) - 0.01 * s.v,
            0.3,
            sensor_noise=(1e-3, 1e-2),
            seed=seed,
            progress=False,
        )

    first, second, other = run(3), run(3), run(4)
    for name in ("q", "v", "u", "object_position", "contact_force"):
        np.testing.assert_array_equal(getattr(first, name), getattr(second, name))
    assert not np.array_equal(first.u, other.u)


def test_absurd_controller_raises_instead_of_nan() -> None:
    hand = far_hand()
    sim = Simulator(Scene(hand, [Sphere(radius=0.02, mass=0.1, pose=at(0.5))]), dt=1e-3)
    with pytest.raises(SimulationDiverged, match=r"speed of velocity \(coordinate") as caught:
        sim.run(lambda t, s: np.full(8, 1e6), 1.0, progress=False)
    assert caught.value.time < 0.01 and caught.value.quantity.startswith("speed")
    with pytest.raises(SimulationDiverged, match="control input u"):
        sim.run(lambda t, s: np.full(8, np.nan), 1.0, progress=False)


def test_bad_simulator_arguments() -> None:
    hand = far_hand()
    scene = Scene(hand)
    with pytest.raises(bh.InputError, match="`integrator` must be one of"):
        Simulator(scene, integrator="euler")
    with pytest.raises(bh.InputError, match="`dt` must be a positive finite number"):
        Simulator(scene, dt=0.0)
    sim = Simulator(scene, dt=1e-3)
    with pytest.raises(bh.InputError, match=r"`u` must have shape \(8,\), got shape \(3,\)"):
        sim.run(lambda t, s: np.zeros(3), 0.01, progress=False)
    with pytest.raises(bh.InputError, match="`control_dt` must be a positive multiple of dt"):
        sim.run(lambda t, s: np.zeros(8), 0.01, control_dt=1.5e-3, progress=False)
    with pytest.raises(bh.InputError, match="`sensor_noise` needs a `seed`"):
        sim.run(lambda t, s: np.zeros(8), 0.01, sensor_noise=(0.01, 0.01), progress=False)


def test_zero_order_hold_at_the_control_period() -> None:
    hand = far_hand()
    sim = Simulator(Scene(hand), dt=1e-3)
    calls = []

    def controller(t: float, state) -> np.ndarray:
        calls.append(t)
        return hand.gravity_torques(state.q)

    trajectory = sim.run(controller, 0.1, control_dt=1e-2, progress=False)
    np.testing.assert_allclose(calls, np.arange(10) * 1e-2, atol=1e-12)
    assert len(trajectory) == 101


def test_bad_run_arguments_name_the_argument(tmp_path) -> None:
    """record_every=0 was a ZeroDivisionError, a wrong-shaped disturbance a numpy broadcast error."""
    hand = far_hand()
    sim = Simulator(Scene(hand), dt=1e-3)
    hold = hold_hand(hand)
    for bad in (0, -2, 1.5, True):
        with pytest.raises(bh.InputError, match="`record_every` must be a positive integer"):
            sim.run(hold, 0.01, record_every=bad, progress=False)
    with pytest.raises(bh.InputError, match=r"`disturbance` must be 8 joint torques \[N m\].*got shape \(3,\)"):
        sim.run(hold, 0.01, disturbance=np.zeros(3), progress=False)
    with pytest.raises(bh.InputError, match=r"`disturbance\(t\)` must be 8 joint torques.*got shape \(2, 8\)"):
        sim.run(hold, 0.01, disturbance=lambda t: np.zeros((2, 8)), progress=False)
    with pytest.raises(bh.InputError, match="`disturbance` must be finite"):
        sim.run(hold, 0.01, disturbance=np.full(8, np.nan), progress=False)
    with pytest.raises(bh.InputError, match="`state` is a state of another scene"):
        sim.run(hold, 0.01, state=Simulator(Scene(hand, [Sphere(radius=0.02, mass=0.1)])).initial_state())


def test_trajectory_load_refuses_what_is_not_a_trajectory(tmp_path) -> None:
    import pickle

    hand = far_hand()
    trajectory = Simulator(Scene(hand), dt=1e-3).run(hold_hand(hand), 0.005, progress=False)
    good = trajectory.save(tmp_path / "run.npz")
    np.testing.assert_array_equal(Trajectory.load(good).q, trajectory.q)
    with pytest.raises(bh.InputError, match="no trajectory file at .*missing.npz"):
        Trajectory.load(tmp_path / "missing.npz")
    with np.load(good) as data:
        arrays = dict(data)
    arrays["q"] = np.array([{"payload": 1}], dtype=object)
    np.savez(tmp_path / "pickled.npz", **arrays)  # every array present, one of them a pickled object array
    with pytest.raises(bh.InputError, match="holds pickled objects, which are never loaded"):
        Trajectory.load(tmp_path / "pickled.npz")
    (tmp_path / "raw.pkl").write_bytes(pickle.dumps({"q": [1, 2]}))
    with pytest.raises(bh.InputError, match="is not a bhgrasp trajectory"):
        Trajectory.load(tmp_path / "raw.pkl")
    np.save(tmp_path / "single.npy", np.zeros(3))
    with pytest.raises(bh.InputError, match="a single .npy array, expected an .npz archive"):
        Trajectory.load(tmp_path / "single.npy")


# ---------------------------------------------------------------------- recorded controller logs
def test_recorded_log_copies_each_sample_and_marks_absent_keys_nan() -> None:
    """Keys that appear late, vanish or come back are NaN where absent; a log array changed in place later is not."""
    hand = far_hand()
    simulator = Simulator(Scene(hand))

    class Logging:
        def __init__(self) -> None:
            self.log: dict = {}
            self.buffer = np.zeros(2)

        def __call__(self, t: float, state) -> np.ndarray:
            k = round(t / simulator.dt)
            self.buffer[:] = k  # one array, changed in place every call
            self.log["always"] = self.buffer
            if k >= 2:
                self.log["late"] = np.array(float(k))
            if k == 4:
                self.log.pop("late")
            return hand.gravity_torques(state.q)

    log = simulator.run(Logging(), 6 * simulator.dt, progress=False).log
    np.testing.assert_array_equal(log["always"], np.repeat(np.arange(7.0), 2).reshape(7, 2).clip(max=5.0))
    np.testing.assert_array_equal(log["late"], [np.nan, np.nan, 2.0, 3.0, np.nan, 5.0, 5.0])


def reference_log(samples: list) -> dict:
    """What a log's arrays are, sample by sample: each entry as np.array(value, float), NaN where it is absent (a
    sample that logged nothing, None, counts as absent for every entry), up to the last sample that logged."""
    names: dict = {}
    for log in samples:
        for name, value in (log or {}).items():
            names.setdefault(name, np.shape(np.array(value, dtype=float)))
    last = max((k for k, log in enumerate(samples) if log is not None), default=-1)
    return {
        name: np.array(
            [
                np.array(log[name], dtype=float) if log is not None and name in log else np.full(shape, np.nan)
                for log in samples[: last + 1]
            ]
        )
        for name, shape in names.items()
    }


def test_the_log_columns_record_what_sample_by_sample_arrays_would() -> None:
    """Columns grown from 2 rows to 300 samples: entries appearing late and vanishing, samples without a log,
    booleans, integers, Python floats and 0-d, 1-d and 2-d arrays; the same values, NaN and entry order."""
    from bhgrasp.sim.recorder import LogColumns

    rng = np.random.default_rng(5)
    samples = []
    for k in range(300):
        if k % 37 == 5:
            samples.append(None)  # a sample without a log (the controller had none then)
            continue
        log = {"matrix": rng.normal(size=(3, 2)), "count": np.array(k)}
        if k >= 40:
            log["late"] = rng.normal(size=4)
        if k % 7 == 0:
            log["sometimes"] = bool(k % 2)
        if 100 <= k < 150:
            log["scalar"] = float(k) / 3
        samples.append(log)
    samples.extend([None, None])  # trailing samples without a log are not rows
    columns = LogColumns(2)
    for k, log in enumerate(samples):
        if log is not None:
            columns.add(log, k)
    recorded, expected = columns.arrays(), reference_log(samples)
    assert list(recorded) == list(expected) == ["matrix", "count", "sometimes", "late", "scalar"]
    for name, array in expected.items():
        assert recorded[name].dtype == np.float64 and recorded[name].shape == array.shape == (300, *array.shape[1:])
        assert recorded[name].tobytes() == array.tobytes(), name


def test_log_rows_added_a_run_at_a_time_record_what_sample_by_sample_arrays_would() -> None:
    """Runs of samples with the same entries added at once (``add_rows``, as a compiled loop's), between samples added
    one by one, gaps without a log, entries absent from a run: the same values, NaN and entry order."""
    from bhgrasp.sim.recorder import LogColumns

    rng = np.random.default_rng(8)
    samples = []
    for k in range(400):
        log = None if k % 53 == 9 else {"force": rng.normal(size=(3, 2)), "count": np.array(float(k))}
        if log is not None and 60 <= k < 200:
            log["late"] = rng.normal(size=4)
        samples.append(log)
    columns, k = LogColumns(3), 0
    while k < len(samples):
        n = int(rng.integers(1, 25))
        run = samples[k : k + n]
        if all(log is not None and log.keys() == run[0].keys() for log in run):
            columns.add_rows({name: np.array([log[name] for log in run]) for name in run[0]}, k)
            k += len(run)
        else:
            if samples[k] is not None:
                columns.add(samples[k], k)
            k += 1
    recorded, expected = columns.arrays(), reference_log(samples)
    assert list(recorded) == list(expected) == ["force", "count", "late"]
    for name, array in expected.items():
        assert recorded[name].shape == array.shape and recorded[name].tobytes() == array.tobytes(), name
    with pytest.raises(bh.InputError, match=r"'force' has rows of shape \(2,\) from sample 400, \(3, 2\) before"):
        columns.add_rows({"force": np.zeros((2, 2))}, 400)
    with pytest.raises(bh.InputError, match="as many for every entry"):
        columns.add_rows({"force": np.zeros((2, 3, 2)), "count": np.zeros(3)}, 400)
    with pytest.raises(bh.InputError, match="sample 10 after sample 399"):
        columns.add_rows({"force": np.zeros((1, 3, 2))}, 10)
    assert columns.arrays()["force"].shape == (400, 3, 2)  # nothing of the refused runs kept


def test_a_log_entry_that_changes_shape_or_is_not_numbers_is_refused_and_nothing_of_its_sample_kept() -> None:
    from bhgrasp.sim.recorder import LogColumns

    columns = LogColumns(4)
    columns.add({"force": np.zeros(3), "gain": 2.5}, 0)  # a Python float is an entry like any other
    with pytest.raises(bh.InputError, match=r"'force' has shape \(2,\) at sample 1, \(3,\) before"):
        columns.add({"force": np.zeros(2), "gain": 2.5}, 1)
    with pytest.raises(bh.InputError, match="'name' at sample 1 must be numbers"):
        columns.add({"force": np.ones(3), "new": np.ones(2), "name": "F1"}, 1)
    with pytest.raises(bh.InputError, match="'huge' at sample 1 must be numbers"):
        columns.add({"force": np.ones(3), "huge": 10**400}, 1)
    columns.add({"force": np.full(3, 7.0), "gain": True}, 1)
    with pytest.raises(bh.InputError, match="sample 0 after sample 1"):
        columns.add({"force": np.zeros(3), "gain": 1.0}, 0)
    arrays = columns.arrays()
    assert list(arrays) == ["force", "gain"]  # the refused samples left no entry behind
    np.testing.assert_array_equal(arrays["force"], [[0.0, 0.0, 0.0], [7.0, 7.0, 7.0]])
    np.testing.assert_array_equal(arrays["gain"], [2.5, 1.0])
