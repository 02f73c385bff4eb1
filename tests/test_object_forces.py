"""External forces on objects (a shake test's push) against Newton's second law, in both engines."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import bhgrasp as bh
from bhgrasp.model.objects import Box, Sphere
from bhgrasp.model.spring_mounted import SpringMounted
from bhgrasp.sim import Simulator
from bhgrasp.sim.scene import Scene


@pytest.mark.parametrize("engine", ["python", "compiled"])
def test_a_pushed_free_body_accelerates_by_f_over_m_and_a_mounted_one_along_its_slide(engine: str) -> None:
    """Implicit Euler from rest under a constant acceleration a: x_k = a dt^2 k (k + 1) / 2, exactly; a force at the
    centre of mass does not turn the body. A spring-mounted body takes F . direction against its spring."""
    hand = bh.BarrettHand()
    box = Box(size=(0.06, 0.05, 0.04), mass=0.3, pose=pin.SE3(pin.exp3(np.array([0.3, -0.5, 0.9])), np.r_[0, 0, 1.0]))
    ball = Sphere(radius=0.02, mass=0.2, pose=pin.SE3(np.eye(3), np.r_[0.5, 0.0, 1.0]))
    mounted = SpringMounted(ball, direction=[0.0, 1.0, 0.0], stiffness=50.0)
    simulator = Simulator(Scene(hand, [box, mounted]), dt=1e-3, engine=engine)
    force = np.array([[1.0, -2.0, 3.0], [0.0, 2.0, 5.0]])
    steps = 200
    trajectory = simulator.run(lambda t, s: np.zeros(8), steps * 1e-3, object_forces=lambda t: force, progress=False)
    acceleration = force[0] / 0.3 + simulator.scene.hand.gravity  # the box is free: gravity too
    expected = acceleration * 1e-6 * steps * (steps + 1) / 2
    np.testing.assert_allclose(trajectory.object_position[-1, 0] - [0, 0, 1.0], expected, rtol=1e-9)
    final = pin.Quaternion(*np.roll(trajectory.object_quaternion[-1, 0], 1)).toRotationMatrix()  # (x, y, z, w)
    np.testing.assert_allclose(final, box.pose.rotation, atol=1e-12)
    slide = trajectory.object_position[:, 1, 1]  # x = F/K (1 - cos w t) from rest, w = 15.8 rad/s: 2 F/K at 0.2 s
    exact = 2.0 / 50.0 * (1.0 - np.cos(np.sqrt(50.0 / 0.2) * trajectory.t))
    assert np.abs(slide - exact).max() < 0.03 * 2 * 2.0 / 50.0  # implicit Euler's damping: 1.2 % here
    with pytest.raises(bh.InputError, match="`object_forces` must"):
        simulator.step(simulator.initial_state(), np.zeros(8), object_forces=np.zeros((1, 3)))


def test_a_run_stops_at_the_first_state_until_accepts() -> None:
    """A falling box: the run ends at the first step below the line, the trajectory with it (x = g t^2 / 2)."""
    hand = bh.BarrettHand()
    box = Box(size=(0.05, 0.05, 0.05), mass=0.3, pose=pin.SE3(np.eye(3), np.r_[0.3, 0.0, 1.0]))
    simulator = Simulator(Scene(hand, [box]), dt=1e-3)
    trajectory = simulator.run(
        lambda t, s: np.zeros(8), 1.0, progress=False, until=lambda s: s.object_poses[0].translation[2] < 0.95
    )
    z = trajectory.object_position[:, 0, 2]
    assert z[-1] < 0.95 <= z[-2]
    assert trajectory.t[-1] == pytest.approx(np.sqrt(2 * 0.05 / 9.81), abs=2e-3)  # 0.101 s, not the 1 s asked
