"""The hand on a wrist mount (issue 16, item 1) against independent truths: the same hand placed at the mount's pose,
rigid-body totals, finite differences of the mount's angles, a tray lifted on the palm (m (g + a) on the contacts)."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import bhgrasp as bh
from bhgrasp.barrett.transmission import MAX_MOTOR_TORQUE, BarrettTransmission
from bhgrasp.controllers.mount import MountServo
from bhgrasp.errors import InputError, ModelError
from bhgrasp.grasp.sensing import ContactSensing
from bhgrasp.model.mount import (
    MOUNT_JOINTS,
    angular_map,
    angular_map_rate,
    mount_coordinates,
    mount_pose,
    mounted,
)
from bhgrasp.model.objects import Box
from bhgrasp.motion.pose_references import PoseMotion, PosePath
from bhgrasp.motion.trajectories import Quintic
from bhgrasp.motion.wrist import MountReference
from bhgrasp.sim import Simulator
from bhgrasp.sim.actuation import BarrettActuation
from bhgrasp.sim.batch import BatchSimulator
from bhgrasp.sim.scene import Scene

ORIGIN = pin.SE3(pin.exp3(np.array([0.2, -0.1, 0.3])), np.array([0.1, 0.2, 0.5]))
COORDINATES = np.array([0.05, -0.02, 0.1, 0.3, -0.4, 0.7])


@pytest.fixture(scope="module")
def tilted():
    return bh.BarrettHand(base_placement=ORIGIN)


def test_a_mounted_hand_is_the_hand_placed_at_the_mounts_pose(tilted) -> None:
    hand = mounted(tilted)
    assert hand.joint_names[:6] == MOUNT_JOINTS and hand.nq == tilted.nq + 6
    assert hand.total_mass == pytest.approx(tilted.total_mass, rel=1e-15)  # the palm rides on the mount
    placed = bh.BarrettHand(base_placement=ORIGIN * mount_pose(COORDINATES))
    q_hand = tilted.random_configuration(np.random.default_rng(0))
    q = np.concatenate((COORDINATES, q_hand))
    for frame in ("palm_surface", "F1_tip", "F2_distal_link", "F3_tip"):
        np.testing.assert_allclose(
            hand.frame_placement(q, frame).homogeneous, placed.frame_placement(q_hand, frame).homogeneous, atol=1e-14
        )
    # the fingers' dynamics with the mount at rest are the placed hand's (same gravity in the world)
    v_hand, a_hand = np.random.default_rng(1).normal(size=(2, 8))
    mounted_torques = pin.rnea(hand.model, hand.data, q, np.r_[np.zeros(6), v_hand], np.r_[np.zeros(6), a_hand])
    placed_torques = pin.rnea(placed.model, placed.data, q_hand, v_hand, a_hand)
    np.testing.assert_allclose(mounted_torques[6:], placed_torques, rtol=1e-12, atol=1e-13)
    # the mount's translation carries the whole hand: mass block m I, and its weight on the mount's axes
    mass = hand.mass_matrix(q)[:3, :3]
    np.testing.assert_allclose(mass, tilted.total_mass * np.eye(3), atol=1e-13)
    weight = -tilted.total_mass * ORIGIN.rotation.T @ tilted.gravity
    np.testing.assert_allclose(hand.gravity_torques(q)[:3], weight, rtol=1e-13)
    with pytest.raises(ModelError, match="is already mounted"):
        mounted(hand)
    # the mount belongs to no finger: finger joints, sensing and IK see the hand's own
    assert hand.base_joints == MOUNT_JOINTS
    for finger in hand.fingers:
        assert hand.finger_joints(finger) == tilted.finger_joints(finger)
        np.testing.assert_array_equal(hand.finger_indices(finger), tilted.finger_indices(finger) + 6)
    sensing = ContactSensing(hand)
    assert sensing.finger_of("palm") is None and sensing.finger_of("F3_distal_link") == "F3"
    assert hand.perturbed(0.7).base_joints == MOUNT_JOINTS


def angular_velocity(c: np.ndarray, rates: np.ndarray, accelerations: np.ndarray, s: float) -> np.ndarray:
    """omega (central differences of R) along the path c + s rates + s^2/2 accelerations, at s."""
    step = 1e-6
    c_s, rate_s = c + s * rates + 0.5 * s * s * accelerations, rates + s * accelerations
    rotation_rate = (mount_pose(c_s + step * rate_s).rotation - mount_pose(c_s - step * rate_s).rotation) / (2 * step)
    return pin.unSkew(rotation_rate @ mount_pose(c_s).rotation.T)


def test_mount_coordinates_and_their_angular_maps_against_finite_differences() -> None:
    rng = np.random.default_rng(2)
    for c in rng.uniform([-0.5] * 3 + [-3.0, -1.4, -3.0], [0.5] * 3 + [3.0, 1.4, 3.0], size=(20, 6)):
        np.testing.assert_allclose(mount_coordinates(mount_pose(c)), c, atol=1e-12)
        rates, accelerations = rng.normal(size=(2, 6))
        omega = angular_velocity(c, rates, accelerations, 0.0)
        np.testing.assert_allclose(omega, angular_map(c) @ rates[3:], atol=1e-8)
        ahead, behind = (angular_velocity(c, rates, accelerations, s) for s in (1e-4, -1e-4))
        omega_dot = (ahead - behind) / 2e-4
        expected = angular_map(c) @ accelerations[3:] + angular_map_rate(c, rates) @ rates[3:]
        np.testing.assert_allclose(omega_dot, expected, atol=1e-5 * (1 + np.abs(expected).max()))


def test_mount_reference_follows_a_world_pose_motion(tilted) -> None:
    """origin * M(c(t)) is the pose reference; c's rates and accelerations are its derivatives (central differences)."""
    start = ORIGIN * mount_pose(COORDINATES)
    motion = PoseMotion(start, [0.02, -0.05, 0.1, 0.2, -0.3, 0.4], 1.0, delay=0.2)
    reference = MountReference(motion, ORIGIN)
    for t in (0.1, 0.35, 0.7, 0.95, 1.5):
        c, rates, accelerations = reference(t)
        pose = motion(t)[0]
        np.testing.assert_allclose(
            (ORIGIN * mount_pose(c)).homogeneous, pin.SE3(pin.exp3(pose[3:]), pose[:3]).homogeneous, atol=1e-13
        )
        (c_plus, rates_plus, _), (c_minus, rates_minus, _) = reference(t + 1e-6), reference(t - 1e-6)
        np.testing.assert_allclose((c_plus - c_minus) / 2e-6, rates, atol=1e-7)
        np.testing.assert_allclose((rates_plus - rates_minus) / 2e-6, accelerations, atol=1e-6)
    with pytest.raises(InputError, match="`pose` must be a Reference of size 6"):
        MountReference(Quintic(0.0, 1.0, 1.0), ORIGIN)


def test_a_repeated_wrist_sample_is_the_computed_one_in_fresh_arrays() -> None:
    """Before, after and between moves the pose and mount samples repeat the last call's: the same bits as a new
    reference computes them (-0.0 kept apart from 0.0), and arrays the caller may change without changing the next."""
    start = ORIGIN * mount_pose(COORDINATES)
    moves = [([0.0, 0.0, -0.05, 0.0, 0.0, 0.3], 0.5), (np.zeros(6), 0.5), ([0.02, 0.0, 0.1, 0.0, 0.2, 0.0], 0.5)]
    path = MountReference(PosePath(start, moves, delay=0.1), ORIGIN)
    times = (0.0, 0.05, 0.3, 0.6, 0.7, 0.9, 0.9, 1.3, 1.7, 2.0, 0.05, 0.3)  # back in time too
    for t in times:
        kept = path(t)
        fresh = MountReference(PosePath(start, moves, delay=0.1), ORIGIN)(t)
        for a, b in zip(kept, fresh):
            assert a.tobytes() == b.tobytes()
            a[:] = np.nan  # the caller's copy
    motion = PoseMotion(start, [0.1, 0.0, 0.0, 0.0, 0.0, 0.0], 1.0, delay=0.0)
    minus, plus = motion(-0.0)[1], PoseMotion(start, [0.1, 0.0, 0.0, 0.0, 0.0, 0.0], 1.0)(0.0)[1]
    assert minus.tobytes() == PoseMotion(start, [0.1, 0.0, 0.0, 0.0, 0.0, 0.0], 1.0)(-0.0)[1].tobytes()
    assert motion(0.0)[1].tobytes() == plus.tobytes()


@pytest.fixture(scope="module")
def tray_lift():
    """A 0.2 kg tray resting on the knuckles of a palm-up hand, lifted 10 cm in 0.5 s by the mount servo."""
    hand = mounted(bh.BarrettHand())
    tray = Box(size=(0.12, 0.12, 0.01), mass=0.2, friction=0.8, pose=pin.SE3(np.eye(3), np.array([0, 0, 0.09605])))
    simulator = Simulator(Scene(hand, [tray]), dt=1e-3)
    lift = MountReference(PoseMotion(pin.SE3.Identity(), [0, 0, 0.1, 0, 0, 0], 0.5, delay=0.3), hand.base_placement)
    trajectory = simulator.run(
        MountServo(hand, lift), 1.0, state=simulator.initial_state(hand.neutral()), progress=False
    )
    return hand, lift, trajectory


def test_a_tray_on_the_palm_rises_with_the_mount_and_weighs_m_g_plus_a(tray_lift) -> None:
    _, lift, trajectory = tray_lift
    lifted = trajectory.object_position[:, 0, 2] - trajectory.q[:, 2]  # tray height above the mount
    assert trajectory.q[-1, 2] == pytest.approx(0.1, abs=1e-5)  # the servo arrived
    assert np.ptp(lifted[250:]) < 3e-4  # it rides on the palm: only the contact springs give (~0.2 mm)
    rows = slice(trajectory.contact_offsets[250], None)
    normal = np.einsum("ij,ij->i", trajectory.contact_force[rows], trajectory.contact_normal[rows])
    assert trajectory.contact_sticking[rows][normal > 0.01 * 0.2 * 9.81].all()  # no loaded contact slides ...
    assert np.abs(trajectory.object_position[-1, 0, :2]).max() < 1e-5  # ... the stuck contacts' springs give µm
    for t in (0.25, 0.406, 0.55, 0.694, 0.95):  # at rest, peak up-acceleration, mid-lift, peak braking, at rest
        k = round(t / 1e-3)
        rows = slice(trajectory.contact_offsets[k], trajectory.contact_offsets[k + 1])
        acceleration = lift(t)[2][2]
        supported = trajectory.contact_force[rows, 2].sum()
        assert supported == pytest.approx(0.2 * (9.81 + acceleration), rel=0.03), t  # the tray's m (g + a)


def test_the_servo_feels_the_load_through_the_contact_torques(tray_lift) -> None:
    """The contacts' joint torques on mount z are minus the force the hand exerts on the tray (the state's forces)."""
    hand, _, trajectory = tray_lift
    sensing = ContactSensing(hand)
    for k in (250, 450, 900):
        contacts = trajectory.contacts_at(k)
        state = bh.State(
            trajectory.t[k],
            trajectory.q[k],
            trajectory.v[k],
            contact_points=contacts["point"],
            contact_normals=contacts["normal"],
            contact_forces=contacts["force"],
            contact_bodies=tuple(map(tuple, contacts["bodies"])),
        )
        reaction = sensing.reaction_torques(state)  # the mount's x, y, z slide along the world axes here
        np.testing.assert_allclose(reaction[:3], -contacts["force"].sum(axis=0), rtol=1e-12, atol=1e-15)
    assert np.abs(trajectory.log["mount_error"][:, :3]).max() < 5e-4  # the servo holds the path within 0.5 mm


def test_without_load_feedforward_the_servo_pd_carries_the_tray_at_m_g_over_kp() -> None:
    """compensate_load=False (grasps from a support): at rest the PD alone holds the tray's weight, so the mount
    sags by m g / kp_z (closed form), where the feedforward version holds the reference."""
    hand = mounted(bh.BarrettHand())
    tray = Box(size=(0.12, 0.12, 0.01), mass=0.2, friction=0.8, pose=pin.SE3(np.eye(3), np.array([0, 0, 0.09605])))
    simulator = Simulator(Scene(hand, [tray]), dt=1e-3)
    hold = MountReference(PoseMotion(pin.SE3.Identity(), np.zeros(6), 1.0), hand.base_placement)
    start = simulator.initial_state(hand.neutral())
    for compensate, expected in ((False, -0.2 * 9.81 / 2e4), (True, 0.0)):
        servo = MountServo(hand, hold, compensate_load=compensate)
        trajectory = simulator.run(servo, 0.6, state=start, progress=False)
        assert trajectory.log["mount_error"][-1, 2] == pytest.approx(expected, abs=2e-6), compensate  # 98 um / 0


def test_the_barrett_drive_runs_a_mounted_hand_with_direct_mount_inputs() -> None:
    hand = mounted(bh.BarrettHand())
    drive = BarrettTransmission(hand)
    assert drive.n_inputs == 10 and drive.direct == list(range(6))
    u = np.r_[0.01, 0.02, 0.03, 0.04, np.arange(1.0, 7.0)]
    for modes in ([0, 0, 0], [1, 2, 0]):
        transmission, gears = drive.matrix(modes), drive.gears(modes)
        np.testing.assert_array_equal(transmission[:6, 4:], np.eye(6))
        np.testing.assert_array_equal(drive.joint_torques(u, modes)[:6], u[4:])
        unmounted = BarrettTransmission(bh.BarrettHand())
        np.testing.assert_array_equal(gears[6:, :4], unmounted.gears(modes))
    actuation = BarrettActuation(hand, saturate=True)
    np.testing.assert_array_equal(
        actuation.joint_torques(np.r_[1.0, 0, 0, 0, 100.0, 0, 0, 0, 0, 0])[[6, 0]], [17.5 * MAX_MOTOR_TORQUE, 100.0]
    )  # pucks saturate, the mount does not
    simulator = Simulator(Scene(hand), actuation=actuation)
    with pytest.raises(InputError, match="BatchSimulator runs the Barrett hand's four motors alone, got 10 inputs"):
        BatchSimulator(simulator, [simulator.initial_state()])


def test_mount_servo_refuses_a_hand_without_a_mount() -> None:
    with pytest.raises(InputError, match="`nominal` must be a mounted hand"):
        MountServo(bh.BarrettHand(), Quintic(np.zeros(6), np.ones(6), 1.0))
    with pytest.raises(InputError, match="`reference` must be a Reference of size 6"):
        MountServo(mounted(bh.BarrettHand()), Quintic(0.0, 1.0, 1.0))
