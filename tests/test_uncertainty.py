"""Sensor noise and delay, joint friction, torque limits, a wrong mu (issue 17, item 5) against their definitions.

Noise: sample moments of many seeded reads against the Gaussian's sigma; delay: the reading is the true state of
exactly ``delay`` before; the limit: no delivered torque above it; a true mu: Coulomb's bound on every contact.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import bhgrasp as bh
from bhgrasp.model.objects import Box, table
from bhgrasp.scenarios.grasp_demo import check_demo_arguments, run_grasp_demo
from bhgrasp.sim import Simulator
from bhgrasp.sim.actuation import FullyActuated
from bhgrasp.sim.scene import Scene
from bhgrasp.sim.sensor_model import SensorModel, Sensors
from bhgrasp.thesis.robustness import run_scenarios, success_interval, summarise
from bhgrasp.thesis.robustness_scenarios import SCENARIOS, SLIDE

FAR = pin.SE3(np.eye(3), np.array([5.0, 0.0, 0.3]))


def box_on_table() -> tuple[Simulator, bh.Hand]:
    hand = bh.BarrettHand(base_placement=FAR)
    box = Box(size=(0.06, 0.05, 0.05), mass=0.2, pose=pin.SE3(np.eye(3), np.array([0.0, 0.0, 0.03])))
    return Simulator(Scene(hand, [box], [table()]), dt=1e-3), hand


def a_state() -> bh.State:
    """A state with an object pose, twist and two contact forces (the reads below perturb it)."""
    rotation = pin.rpy.rpyToMatrix(0.1, -0.2, 0.3)
    return bh.State(
        t=0.5,
        q=np.linspace(0.0, 0.7, 8),
        v=np.zeros(8),
        object_poses=(pin.SE3(rotation, np.array([0.1, 0.2, 0.3])),),
        object_twists=np.array([[0.01, 0.0, -0.02, 0.1, 0.2, 0.0]]),
        contact_points=np.zeros((2, 3)),
        contact_normals=np.tile([0.0, 0.0, 1.0], (2, 1)),
        contact_forces=np.array([[0.0, 0.0, 3.0], [1.0, 0.0, 2.0]]),
    )


def test_noise_has_the_model_sigmas_and_zero_mean() -> None:
    model = SensorModel(
        object_position=1e-3,
        object_rotation=2e-3,
        object_velocity=3e-3,
        object_angular_velocity=4e-2,
        contact_force=0.5,
        joint_position=1e-4,
    )
    sensors, truth = Sensors(model, seed=11), a_state()
    reads = [sensors.read(truth) for _ in range(4000)]
    position = np.array([r.object_poses[0].translation for r in reads]) - truth.object_poses[0].translation
    turn = np.array([pin.log3(r.object_poses[0].rotation @ truth.object_poses[0].rotation.T) for r in reads])
    twist = np.array([r.object_twists[0] for r in reads]) - truth.object_twists[0]
    force = np.array([r.contact_forces for r in reads]) - truth.contact_forces
    joints = np.array([r.q for r in reads]) - truth.q
    for sample, sigma in (
        (position, 1e-3),
        (turn, 2e-3),
        (twist[:, :3], 3e-3),
        (twist[:, 3:], 4e-2),
        (force.reshape(-1, 3), 0.5),
        (joints, 1e-4),
    ):
        # 4000 draws: the sample sigma's standard error is 1.1 %, the mean's 1.6 % of sigma
        np.testing.assert_allclose(sample.std(axis=0), sigma, rtol=0.05)
        assert np.all(np.abs(sample.mean(axis=0)) < 0.07 * sigma)
    np.testing.assert_array_equal(np.array([r.v for r in reads]), 0.0)  # no velocity noise asked: none drawn
    np.testing.assert_array_equal(reads[0].contact_points, truth.contact_points)  # points are not measured here


def test_exact_sensors_pass_the_true_state_itself() -> None:
    truth = a_state()
    assert Sensors(SensorModel(), seed=None).read(truth) is truth


def test_the_joint_noise_shorthand_is_the_same_model_bit_for_bit() -> None:
    simulator, hand = box_on_table()

    def run(**sensing) -> bh.Trajectory:
        return simulator.run(
            lambda t, s: hand.gravity_torques(s.q) - 0.01 * s.v, 0.1, seed=5, progress=False, **sensing
        )

    short, model = run(sensor_noise=(1e-3, 1e-2)), run(sensors=SensorModel(joint_position=1e-3, joint_velocity=1e-2))
    for name in ("q", "v", "u", "object_position"):
        np.testing.assert_array_equal(getattr(short, name), getattr(model, name))
    with pytest.raises(bh.InputError, match="not both"):
        run(sensor_noise=(1e-3, 1e-2), sensors=SensorModel())


def test_a_delayed_reading_is_the_true_state_of_delay_before() -> None:
    simulator, hand = box_on_table()
    seen: list[tuple[float, float, float]] = []

    def controller(t: float, state: bh.State) -> np.ndarray:
        seen.append((t, state.t, float(state.object_poses[0].translation[2])))
        return hand.gravity_torques(state.q)

    # the box starts 5 mm above the table and falls onto it: its height changes every step
    trajectory = simulator.run(controller, 0.05, progress=False, sensors=SensorModel(delay=0.005))
    times, heights = trajectory.t, trajectory.object_position[:, 0, 2]
    for t, t_seen, z_seen in seen:
        expected = max(0.0, round(t - 0.005, 9))
        assert t_seen == pytest.approx(expected, abs=1e-12)
        assert z_seen == heights[int(np.argmin(np.abs(times - expected)))]
    assert len({z for _, _, z in seen}) > 10  # the readings did change


def test_a_tracker_delivers_its_frames_late_and_holds_each_until_the_next() -> None:
    """30 frames/s taken at k/30 s (the control cycle at or before) and delivered 30 ms later: the object reading
    at t is the true state of the newest frame delivered (the start state's before the first), with its capture
    time, the same noisy frame repeated; the encoders stay current."""
    simulator, hand = box_on_table()
    seen: list[tuple[float, float | None, np.ndarray, np.ndarray]] = []

    def controller(t: float, state: bh.State) -> np.ndarray:
        seen.append((t, state.object_time, state.object_poses[0].translation.copy(), np.array(state.q)))
        return hand.gravity_torques(state.q)

    model = SensorModel(object_position=1e-4, tracker_rate=30.0, tracker_latency=0.03)
    trajectory = simulator.run(controller, 0.2, progress=False, sensors=model, seed=3)
    times, positions = trajectory.t, trajectory.object_position[:, 0]
    repeated = {}
    for t, frame, position, q in seen:
        capture = max(0.0, np.floor((t - 0.03 + 1e-9) * 30.0) / 30.0)
        k = int(np.searchsorted(times, capture + 1e-9)) - 1  # the last control cycle at or before the capture
        assert frame == pytest.approx(times[k], abs=1e-12) and 0.0 <= capture - times[k] < 1e-3
        assert np.linalg.norm(position - positions[k]) < 6e-4  # the frame's truth plus its 0.1 mm noise
        repeated.setdefault(frame, []).append(position)
        assert np.array_equal(q, trajectory.q[int(np.argmin(np.abs(times - t)))])
    assert len(repeated) == 6  # frames of 0, 1/30, ..., 5/30 s delivered by 0.2 s
    for positions_of_frame in repeated.values():
        assert all(np.array_equal(p, positions_of_frame[0]) for p in positions_of_frame)
    assert SensorModel(tracker_rate=30.0).tracked and not SensorModel(tracker_rate=30.0).exact


def test_sensor_model_refuses_bad_values() -> None:
    with pytest.raises(bh.InputError, match="object_position"):
        SensorModel(object_position=-1e-3)
    with pytest.raises(bh.InputError, match="delay"):
        SensorModel(delay=float("nan"))
    with pytest.raises(bh.InputError, match="tracker_rate"):
        SensorModel(tracker_rate=-30.0)
    with pytest.raises(bh.InputError, match="needs a `seed`"):
        Sensors(SensorModel(contact_force=0.1), seed=None)
    with pytest.raises(bh.InputError, match="SensorModel"):
        Sensors((0.1, 0.1), seed=1)


def test_the_torque_limit_clips_every_joint() -> None:
    hand = bh.BarrettHand()
    drive = FullyActuated(hand, limit=0.3)
    u = np.linspace(-1.0, 1.0, hand.nv)
    np.testing.assert_array_equal(drive.joint_torques(u), np.clip(u, -0.3, 0.3))
    np.testing.assert_array_equal(FullyActuated(hand).joint_torques(u), u)  # no limit by default
    with pytest.raises(bh.InputError, match="`limit` must be finite and >= 0"):
        FullyActuated(hand, limit=-1.0)


def test_the_demo_holds_its_torque_limit_and_the_true_mu() -> None:
    limited = run_grasp_demo(mass=0.4, duration=1.2, torque_limit=0.4)
    assert np.abs(limited.trajectory.tau).max() <= 0.4 + 1e-12
    assert np.abs(limited.trajectory.u).max() > 0.4  # the controller asked for more
    slippery = run_grasp_demo(mass=0.4, duration=1.2, friction=0.5)
    bodies = slippery.trajectory.pair_bodies[slippery.trajectory.contact_pair]
    on_box = np.array([b == slippery.trajectory.object_names[0] for _, b in bodies])
    force, normal = slippery.trajectory.contact_force[on_box], slippery.trajectory.contact_normal[on_box]
    normal_part = np.einsum("ij,ij->i", force, normal)
    tangential = np.linalg.norm(force - normal_part[:, None] * normal, axis=1)
    assert np.all(tangential <= 0.5 * normal_part + 1e-9)  # Coulomb with the true mu
    assert np.any(tangential > 0.45 * normal_part)  # and the cone is reached: 0.5, not the default 0.8


def test_true_and_sensed_errors() -> None:
    exact = run_grasp_demo(mass=0.4, duration=2.0)
    # without noise the true final error is the controller's own, one control step apart
    assert abs(exact.true_position_error - exact.position_error) < 1e-6
    assert abs(exact.true_rotation_error - exact.rotation_error) < 1e-5
    noisy = run_grasp_demo(mass=0.4, duration=2.0, pose_noise=(5e-4, 5e-3), seed=3)
    assert abs(noisy.true_position_error - noisy.position_error) > 1e-5  # the controller saw a noisy pose


def test_demo_uncertainty_arguments_are_checked() -> None:
    with pytest.raises(bh.InputError, match="no parameter 'pose_nois'"):
        check_demo_arguments(pose_nois=(0.1, 0.1))
    with pytest.raises(bh.InputError, match=r"`pose_noise` must have shape \(2,\)"):
        check_demo_arguments(pose_noise=0.1)
    with pytest.raises(bh.InputError, match="`friction` must be a positive"):
        check_demo_arguments(friction=0.0)
    with pytest.raises(bh.InputError, match="apply to the Barrett scene"):
        check_demo_arguments(hand="allegro", delay=0.002)


def test_the_monte_carlo_is_seeded_and_counts_success() -> None:
    chosen = {key: SCENARIOS[key] for key in ("exact", "pose_noise")}
    first = run_scenarios(1.5, "serial", chosen, samples=2)
    again = run_scenarios(1.5, "serial", chosen, samples=2)
    for key in chosen:
        columns = ["mass", "true_position_error", "slip_events", "force_error"]
        np.testing.assert_array_equal(first[key][columns].to_numpy(), again[key][columns].to_numpy())
    np.testing.assert_array_equal(first["exact"]["mass"], first["pose_noise"]["mass"])  # the same boxes
    frame = first["exact"].copy()
    frame.loc[:, "true_position_error"] = [1e-4, 1e-3]  # one run 1 mm off: half succeed
    frame.loc[:, "true_rotation_error"] = 1e-3
    frame.loc[:, "slip_events"] = 0.0
    figures = summarise(frame)
    assert figures["success_pct"] == 50.0 and figures["max_error_mm"] == pytest.approx(1.0)
    assert figures["lightest_failure_kg"] == frame["mass"].iloc[1]  # the run 1 mm off
    # both within the pose bounds, both with samples at the Coulomb limit; one slid 20 um, the other 0.2 mm
    frame.loc[:, "true_position_error"] = 1e-4
    frame.loc[:, "slip_events"] = 3.0
    frame.loc[:, "slide"] = [0.2 * SLIDE, 2.0 * SLIDE]
    figures = summarise(frame)
    assert figures["success_pct"] == 50.0 and figures["strict_success_pct"] == 0.0
    assert figures["max_slide_mm"] == pytest.approx(2e3 * SLIDE)


def test_a_scenario_whose_runs_all_failed_reports_them() -> None:
    import pandas as pd

    frame = pd.DataFrame({"case": [0, 1], "status": ["failed", "failed"], "error": ["InputError: ...", "..."]})
    figures = summarise(frame)
    assert figures["success_pct"] == 0.0 and figures["failed_runs"] == 2.0 and np.isnan(figures["mean_error_mm"])


@pytest.mark.parametrize(("successes", "runs"), [(0, 30), (15, 30), (27, 30), (30, 30), (3, 12)])
def test_the_success_interval_is_wilsons_score_interval(successes: int, runs: int) -> None:
    """Wilson's interval is every p whose normal test does not reject the observed share: |s/n - p| <= z
    sqrt(p (1 - p) / n).  Its bounds, found here by bisection on that inequality, are the closed form's."""
    from scipy.stats import norm

    z, share = norm.ppf(0.975), successes / runs

    def inside(p: float) -> bool:
        return abs(share - p) <= z * np.sqrt(p * (1 - p) / runs)

    def edge(outside: float, within: float) -> float:
        for _ in range(200):
            middle = 0.5 * (outside + within)
            outside, within = (outside, middle) if inside(middle) else (middle, within)
        return within

    low, high = success_interval(successes, runs)
    assert low == pytest.approx(0.0 if successes == 0 else edge(0.0, share), abs=1e-12)
    assert high == pytest.approx(1.0 if successes == runs else edge(1.0, share), abs=1e-12)
    assert low <= share <= high
