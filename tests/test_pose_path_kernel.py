"""The compiled pose path (``bhgrasp._core.PosePath``, ``src/pose_path.cpp``) against PoseMotion and PosePath.

Its blend, position, twist and the twist's derivative are PoseMotion's operations in the same order: the same bits.
Its rotation exp(b dtheta) R_0 is summed by Eigen, NumPy's by BLAS: the same to round-off, and a turn about the
fixed world axis of dtheta (independent of either): R(t) R_0^T = exp(b dtheta), and finite differences of the pose
give the twist.  (``tests/test_smc_law_twin.py`` holds the compiled SMC law on it to the law on the Python sample.)
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from bhgrasp.controllers._pose_path import compiled_path, path_arguments
from bhgrasp.motion.pose_references import PoseMotion, PosePath
from bhgrasp.sim.compiled import core_module

core = core_module()
START = pin.SE3(pin.exp3(np.array([0.3, -0.2, 0.5])), np.array([0.01, -0.02, 0.3]))
OFFSET = np.array([0.004, -0.003, 0.01, 0.1, -0.25, 0.05])


def times(end: float) -> np.ndarray:
    """Before, during and after, every join and both ends exactly, and a few thousand in between."""
    return np.unique(np.concatenate((np.linspace(-0.2, end + 0.3, 2001), [0.0, 0.5, 0.7, 1.2, 1.7, end])))


@pytest.mark.parametrize("kind", ["motion", "path"])
def test_the_compiled_path_samples_what_the_python_reference_does(kind):
    if kind == "motion":
        reference, end = PoseMotion(START, OFFSET, 0.7, 0.5), 1.2
    else:  # a move, a pause, a move back (the joins at 1.2 and 1.7 s)
        reference = PosePath(START, [(OFFSET, 0.7), (np.zeros(6), 0.5), (-0.5 * OFFSET, 0.3)], delay=0.5)
        end = reference.end_time
    path = compiled_path(core, reference)
    for t in times(end):
        sample, twist, derivative = reference(float(t))
        rotation, position, twist_c, derivative_c = path.sample(float(t))
        # bytes, not values: a join's two moves differ only in the signs of zeros (the ending move's b'' is -0.0)
        assert position.tobytes() == np.ascontiguousarray(sample[:3]).tobytes(), f"t = {t}"
        assert twist_c.tobytes() == twist.tobytes(), f"t = {t}"
        assert derivative_c.tobytes() == derivative.tobytes(), f"t = {t}"
        np.testing.assert_allclose(rotation, pin.exp3(sample[3:]), rtol=0, atol=1e-14, err_msg=f"t = {t}")
        np.testing.assert_allclose(rotation @ rotation.T, np.eye(3), rtol=0, atol=1e-14)


def test_the_compiled_rotation_turns_about_the_fixed_world_axis_and_its_rates_are_the_twist():
    motion = PoseMotion(START, OFFSET, 0.7, 0.5)
    path, h = compiled_path(core, motion), 1e-6
    for t in np.linspace(0.45, 1.25, 33):
        rotation, position, twist, derivative = path.sample(t)
        s = min(max((t - 0.5) / 0.7, 0.0), 1.0)
        blend = 10 * s**3 - 15 * s**4 + 6 * s**5
        np.testing.assert_allclose(pin.log3(rotation @ START.rotation.T), blend * OFFSET[3:], rtol=0, atol=1e-14)
        np.testing.assert_allclose(position, START.translation + blend * OFFSET[:3], rtol=0, atol=1e-16)
        after, before = path.sample(t + h), path.sample(t - h)
        np.testing.assert_allclose((after[1] - before[1]) / (2 * h), twist[:3], rtol=0, atol=1e-8)
        np.testing.assert_allclose(pin.log3(after[0] @ before[0].T) / (2 * h), twist[3:], rtol=0, atol=1e-8)
        if 0.5 + h < t < 1.2 - h:  # the jerk jumps at the ends: a central difference across them is one-sided
            np.testing.assert_allclose((after[2] - before[2]) / (2 * h), derivative, rtol=0, atol=1e-6)


def test_a_path_without_moves_or_with_a_bad_move_is_refused():
    arguments = path_arguments([PoseMotion(START, OFFSET, 0.7)])
    with pytest.raises(ValueError, match="at least one move"):
        core.PosePath(rotations=[], translations=[], offsets=np.zeros((0, 6)), durations=[], delays=[])
    with pytest.raises(ValueError, match="per move"):
        core.PosePath(**{**arguments, "durations": [0.7, 0.7]})
    with pytest.raises(ValueError, match="duration > 0"):
        core.PosePath(**{**arguments, "durations": [0.0]})
    with pytest.raises(ValueError, match="finite delay"):
        core.PosePath(**{**arguments, "delays": [float("nan")]})
