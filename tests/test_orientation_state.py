"""Z-Y-Z Euler conversion (against SciPy) and the Trajectory record (save/load without pickle, slicing)."""

from __future__ import annotations

import dataclasses
import itertools
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from scipy.spatial.transform import Rotation

import bhgrasp as bh
from bhgrasp.data import Trajectory
from bhgrasp.model.objects import Box, table
from bhgrasp.model.orientation import rotation_from_zyz, zyz_from_rotation
from bhgrasp.sim import Simulator
from bhgrasp.sim.scene import Scene


def test_zyz_matches_scipy_intrinsic_zyz() -> None:
    rng = np.random.default_rng(0)
    for _ in range(200):
        rotation = Rotation.random(random_state=rng)
        angles = zyz_from_rotation(rotation.as_matrix())
        np.testing.assert_allclose(rotation_from_zyz(angles), rotation.as_matrix(), atol=1e-12)
        np.testing.assert_allclose(Rotation.from_euler("ZYZ", angles).as_matrix(), rotation.as_matrix(), atol=1e-12)
        assert 0.0 <= angles[1] <= np.pi


@pytest.mark.parametrize("theta", [0.0, np.pi])
def test_zyz_at_the_gimbal_singularity(theta: float) -> None:
    rotation = rotation_from_zyz([0.7, theta, 0.2])
    angles = zyz_from_rotation(rotation)
    assert angles[1] == pytest.approx(theta) and angles[2] == 0.0
    np.testing.assert_allclose(rotation_from_zyz(angles), rotation, atol=1e-12)


@pytest.fixture(scope="module")
def trajectory() -> Trajectory:
    hand = bh.BarrettHand(base_placement=pin.SE3(np.eye(3), np.array([5.0, 0.0, 0.3])))
    box = Box(
        size=(0.06, 0.05, 0.05), mass=0.2, pose=pin.SE3(pin.rpy.rpyToMatrix(0.1, 0.0, 0.3), np.array([0, 0, 0.05]))
    )
    sim = Simulator(Scene(hand, [box], [table()]), dt=1e-3)

    def controller(t: float, state) -> np.ndarray:
        controller.log = {"time_squared": t**2, "vector": np.array([t, -t])}
        return hand.gravity_torques(state.q)

    controller.log = {}
    return sim.run(controller, 0.2, progress=False)


def test_trajectory_records_everything(trajectory: Trajectory) -> None:
    n = len(trajectory)
    assert n == 201 and trajectory.q.shape == (n, 8) and trajectory.object_quaternion.shape == (n, 1, 4)
    assert trajectory.contact_offsets[-1] == len(trajectory.contact_pair) > 0  # the box landed
    logged = trajectory.log["time_squared"]
    np.testing.assert_allclose(logged[:-1], trajectory.t[:-1] ** 2)  # logged at each controller call ...
    assert logged[-1] == logged[-2]  # ... and held, like u, at the final sample (no call there)
    assert trajectory.log["vector"].shape == (n, 2)
    euler = trajectory.object_euler_zyz()
    rotation = pin.Quaternion(*np.roll(trajectory.object_quaternion[0, 0], 1)).toRotationMatrix()
    np.testing.assert_allclose(rotation_from_zyz(euler[0, 0]), rotation, atol=1e-12)


def test_trajectory_round_trips_through_npz(trajectory: Trajectory, tmp_path: Path) -> None:
    path = trajectory.save(tmp_path / "run.npz")
    loaded = Trajectory.load(path)
    for name in ("t", "q", "v", "u", "tau", "object_position", "contact_offsets", "contact_force", "contact_sticking"):
        np.testing.assert_array_equal(getattr(loaded, name), getattr(trajectory, name))
    np.testing.assert_array_equal(loaded.log["vector"], trajectory.log["vector"])
    assert loaded.joint_names == trajectory.joint_names and loaded.object_names == trajectory.object_names
    with np.load(path, allow_pickle=False) as data:  # plain arrays only: loadable without pickle
        assert all(data[name].dtype != object for name in data.files)


def test_trajectory_slices_by_time(trajectory: Trajectory) -> None:
    part = trajectory.between(0.05, 0.1)
    assert part.t[0] == pytest.approx(0.05) and part.t[-1] == pytest.approx(0.1) and len(part) == 51
    k = 60
    np.testing.assert_array_equal(part.contacts_at(k - 50)["force"], trajectory.contacts_at(k)["force"])
    with pytest.raises(bh.InputError, match="no samples between t = 5 and 6 s"):
        trajectory.between(5, 6)


def test_joined_parts_are_the_whole_record(trajectory: Trajectory) -> None:
    """Cut in three at any samples and joined again, a record is the same arrays, contacts and log."""
    cuts = (0, 37, 90, len(trajectory))
    assert len(trajectory.contact_depth) > 0  # the box rests on the table: contacts to keep in step with the samples
    joined = Trajectory.joined([trajectory[a:b] for a, b in itertools.pairwise(cuts)])
    for name in ("t", "q", "u", "tau", "object_position", "contact_offsets", "contact_force", "contact_pair"):
        np.testing.assert_array_equal(getattr(joined, name), getattr(trajectory, name), err_msg=name)
    assert joined.log.keys() == trajectory.log.keys()
    for name, values in trajectory.log.items():
        np.testing.assert_array_equal(joined.log[name], values)
    np.testing.assert_array_equal(joined.contacts_at(60)["force"], trajectory.contacts_at(60)["force"])


def test_joined_parts_fill_a_log_one_lacks_with_nan_and_skip_empty_ones(trajectory: Trajectory) -> None:
    head, tail = trajectory[0:50], dataclasses.replace(trajectory[50 : len(trajectory)], log={})
    joined = Trajectory.joined([head, trajectory[0:0], tail])
    np.testing.assert_array_equal(joined.log["vector"][:50], trajectory.log["vector"][:50])
    assert np.isnan(joined.log["vector"][50:]).all() and joined.log["vector"].shape == trajectory.log["vector"].shape
    np.testing.assert_array_equal(joined.contact_force, trajectory.contact_force)


def test_joining_refuses_no_samples_other_scenes_and_times_that_go_back(trajectory: Trajectory) -> None:
    with pytest.raises(bh.InputError, match="at least one sample"):
        Trajectory.joined([trajectory[0:0]])
    other = dataclasses.replace(trajectory.between(0.15, 0.2), object_names=("another",))
    with pytest.raises(bh.InputError, match="must record one scene"):
        Trajectory.joined([trajectory.between(0.0, 0.1), other])
    with pytest.raises(bh.InputError, match="must increase: a part ends at t = 0.1 s and the next starts at 0.05"):
        Trajectory.joined([trajectory.between(0.0, 0.1), trajectory.between(0.05, 0.2)])


def test_loading_something_else_fails_clearly(tmp_path: Path) -> None:
    path = tmp_path / "other.npz"
    np.savez(path, x=np.zeros(3))
    with pytest.raises(bh.InputError, match="is not a bhgrasp trajectory: missing arrays"):
        Trajectory.load(path)
