"""The manipulable space of a grasp (issue 17, item 2) against closed forms: the BH8-280 pinch's one missing motion
is F3's (its finger moves in the plane x = 0), offsets outside it are refused before simulating, with the nearest
allowed one."""

from __future__ import annotations

import numpy as np
import pytest

from bhgrasp.errors import UnreachableError
from bhgrasp.grasp import describe
from bhgrasp.scenarios.box_grasp import box_grasp
from bhgrasp.scenarios.grasp_demo import OFFSET, run_grasp_demo
from bhgrasp.sim import Simulator


@pytest.fixture(scope="module")
def pinch():
    setup = box_grasp(mass=0.6)
    return setup, setup.manipulable_space()


def test_the_pinch_lacks_only_what_f3_cannot_do(pinch) -> None:
    """F3's joints turn about axes parallel to x: its contact cannot move along x, so v_x - r_y omega_z = 0 there."""
    setup, space = pinch
    assert space.dimension == 5 and space.missing.shape == (6, 1)
    lever = space.grasp[:3, 6:9]  # F3's contact frame: rows of G_3 are its force directions
    f3 = setup.hand.fingertip_positions(setup.q_contact)[2]
    r_y = f3[1] - 0.010 - setup.box.pose.translation[1]  # the pad touches the +y face: contact at y = +25 mm
    assert r_y == pytest.approx(0.025, abs=1e-9)
    expected = np.array([1.0, 0, 0, 0, 0, -r_y / space.length])  # the constraint on (v, L omega)
    cosine = abs(space.missing[:, 0] @ expected) / np.linalg.norm(expected)
    assert cosine == pytest.approx(1.0, abs=1e-9)
    assert lever.shape == (3, 3)
    # second method: a direction is allowed iff the fingers make its contact velocities exactly (least squares)
    scale = np.r_[np.ones(3), np.full(3, space.length)]
    for direction in space.basis.T:
        assert space.sliding(direction / scale).max() < 1e-12
    assert space.sliding(space.missing[:, 0] / scale).max() > 0.1
    assert describe(space.missing[:, 0]) == "translation along x combined with rotation about z"


def test_offsets_outside_are_refused_with_the_missing_direction_and_the_nearest_allowed_one(pinch) -> None:
    _, space = pinch
    space.check(OFFSET)  # the demo's lift and turn about x
    message = (
        r"contact F3 would slide or roll 5\.00 mm .*missing: translation along x combined with rotation about "
        r"z\. The nearest offset without sliding is .* though joint F1_spread meets its limit 0 % of it"
    )
    with pytest.raises(UnreachableError, match=message) as refused:
        space.check([0.005, 0, 0, 0, 0, 0])
    nearest = refused.value.result  # a turn about a vertical axis through F3's contact, but F1's spread is at 0
    fraction, joint = space.joint_reach(nearest)
    assert space.sliding(nearest).max() < 1e-12 and fraction < 1e-9 and joint == "F1_spread"
    assert nearest[0] == pytest.approx(0.025 * nearest[5], rel=1e-9)  # v_x = r_y omega_z
    scale = np.r_[np.ones(3), np.full(3, space.length)]
    difference = (nearest - [0.005, 0, 0, 0, 0, 0]) * scale
    np.testing.assert_allclose(space.basis.T @ difference, 0.0, atol=1e-15)  # the orthogonal projection
    with pytest.raises(UnreachableError, match="contact F3 would slide or roll 7.50 mm"):  # 0.3 rad about z at 25 mm
        space.check([0, 0, 0, 0, 0, 0.3])


def test_a_motion_past_a_joint_limit_is_refused_naming_the_joint(pinch) -> None:
    setup, space = pinch
    fraction, joint = space.joint_reach([0, 0, 0.1, 0, 0, 0])
    assert 0.0 < fraction < 1.0
    step = space.joint_map @ np.array([0, 0, 0.1, 0, 0, 0])  # independent: the first limit met along q + s step
    index = setup.hand.joint_index(joint)
    limit = setup.hand.upper[index] if step[index] > 0 else setup.hand.lower[index]
    assert setup.q_contact[index] + fraction * step[index] == pytest.approx(limit, abs=1e-12)
    with pytest.raises(UnreachableError, match=f"joint {joint} reaches its limit"):
        space.check([0, 0, 0.1, 0, 0, 0])


def test_the_demo_refuses_an_impossible_motion_before_simulating(monkeypatch: pytest.MonkeyPatch) -> None:
    def not_run(*args, **kwargs):
        raise AssertionError("the simulation ran")

    monkeypatch.setattr(Simulator, "run", not_run)
    with pytest.raises(UnreachableError, match="missing: translation along x combined with rotation about z"):
        run_grasp_demo(offset=(0.005, 0.0, 0.0, 0.0, 0.0, 0.0))
