"""Every bad input raises a specific BhgraspError that names the argument, the value and what was expected."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import bhgrasp as bh

VALID_URDF = bh.barrett_urdf_path().read_text()


def write(tmp_path: Path, text: str, name: str = "hand.urdf") -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


def test_error_classes_derive_from_the_matching_builtins() -> None:
    assert issubclass(bh.InputError, bh.BhgraspError) and issubclass(bh.InputError, ValueError)
    assert issubclass(bh.ModelError, bh.BhgraspError) and issubclass(bh.ModelError, ValueError)
    assert issubclass(bh.UnreachableError, bh.BhgraspError) and issubclass(bh.UnreachableError, ValueError)


# ---------------------------------------------------------------------- URDF files
def test_missing_urdf(tmp_path: Path) -> None:
    with pytest.raises(bh.ModelError, match="URDF file not found: .*nowhere.urdf"):
        bh.Hand.from_urdf(tmp_path / "nowhere.urdf")


def test_malformed_xml(tmp_path: Path) -> None:
    with pytest.raises(bh.ModelError, match="not well-formed XML"):
        bh.Hand.from_urdf(write(tmp_path, VALID_URDF[:2000]))


def test_not_a_robot(tmp_path: Path) -> None:
    with pytest.raises(bh.ModelError, match="must have a <robot> root element, got <sdf>"):
        bh.Hand.from_urdf(write(tmp_path, "<sdf version='1.6'><model name='m'/></sdf>"))


def test_external_entities_are_neither_expanded_nor_fetched(tmp_path: Path) -> None:
    secret = write(tmp_path, "TOP-SECRET-MARKER", "secret.txt")
    xxe = VALID_URDF.replace(
        '<robot name="barrett_hand">',
        f'<!DOCTYPE robot [<!ENTITY leak SYSTEM "file://{secret}">]>\n<robot name="barrett_hand"><!-- &leak; -->',
    )
    xxe = xxe.replace('<material name="bh_black">', '<material name="&leak;">')
    with pytest.raises(bh.ModelError, match="declares a DTD or XML entities") as caught:
        bh.Hand.from_urdf(write(tmp_path, xxe))
    assert "TOP-SECRET-MARKER" not in str(caught.value)


def test_internal_entity_bomb_is_refused(tmp_path: Path) -> None:
    bomb = (
        '<?xml version="1.0"?><!DOCTYPE robot [<!ENTITY a "aaaaaaaaaa"><!ENTITY b "&a;&a;&a;&a;&a;">]>'
        '<robot name="&b;"/>'
    )
    with pytest.raises(bh.ModelError, match="DTD or XML entities"):
        bh.Hand.from_urdf(write(tmp_path, bomb))


def test_urdf_pinocchio_rejects(tmp_path: Path) -> None:
    broken = VALID_URDF.replace('<limit lower="0" upper="2.443460952792061" velocity="2.454" effort="13.75"/>', "", 1)
    with pytest.raises(bh.ModelError, match="Pinocchio cannot build a model"):
        bh.Hand.from_urdf(write(tmp_path, broken))


def test_urdf_without_moving_joints(tmp_path: Path) -> None:
    with pytest.raises(bh.ModelError, match="no moving joints"):
        bh.Hand.from_urdf(write(tmp_path, '<robot name="rock"><link name="base"/></robot>'))


def test_unknown_fingertip_frame() -> None:
    with pytest.raises(bh.InputError, match="unknown frame 'F4_tip'; valid frames: universe, .*F3_tip"):
        bh.Hand.from_urdf(bh.barrett_urdf_path(), fingertips=["F1_tip", "F4_tip"])


# ---------------------------------------------------------------------- names
def test_unknown_joint_name_lists_the_valid_ones(barrett: bh.Hand) -> None:
    with pytest.raises(
        bh.InputError, match="unknown joint 'F3_spread'; valid joints: F1_spread, F1_proximal, .*F3_distal"
    ):
        barrett.configuration(F3_spread=0.1)


def test_unknown_finger_and_frame(barrett: bh.Hand) -> None:
    q = barrett.neutral()
    with pytest.raises(bh.InputError, match="unknown finger 'thumb'; valid fingers: F1, F2, F3"):
        barrett.fingertip_jacobian(q, "thumb")
    with pytest.raises(bh.InputError, match="unknown frame 'wrist'"):
        barrett.frame_placement(q, "wrist")
    with pytest.raises(bh.InputError, match="unknown finger 'F4'"):
        bh.finger_ik(barrett, "F4", [0, 0, 0.1])
    with pytest.raises(bh.InputError, match="unknown frame 'nowhere'"):
        barrett.external_forces(q, {"nowhere": [0, 0, 1]})


def test_joint_value_outside_its_limits(barrett: bh.Hand) -> None:
    with pytest.raises(bh.InputError, match=r"joint 'F1_distal' = 1.0 rad is outside its limits \[0, 0.837758\]"):
        barrett.configuration(F1_distal=1.0)


# ---------------------------------------------------------------------- arrays
@pytest.mark.parametrize(
    ("call", "argument"),
    [
        (lambda h, bad: h.fingertip_positions(bad), "q"),
        (lambda h, bad: h.mass_matrix(bad), "q"),
        (lambda h, bad: h.nonlinear_effects(np.zeros(8), bad), "v"),
        (lambda h, bad: h.coriolis_matrix(np.zeros(8), bad), "v"),
        (lambda h, bad: h.forward_dynamics(np.zeros(8), np.zeros(8), bad), "tau"),
        (lambda h, bad: h.inverse_dynamics(np.zeros(8), np.zeros(8), bad), "a"),
        (lambda h, bad: h.regressor(np.zeros(8), np.zeros(8), bad), "a"),
        (lambda h, bad: h.gravity_torques(bad), "q"),
    ],
)
@pytest.mark.parametrize(
    ("bad", "message"),
    [
        (np.zeros(7), r"must have shape \(8,\), got shape \(7,\)"),
        (np.zeros((8, 1)), r"must have shape \(8,\), got shape \(8, 1\)"),
        (np.r_[np.zeros(7), np.nan], r"must be finite, got NaN/inf at flat index \[7\]"),
        (np.r_[np.inf, np.zeros(7)], r"must be finite, got NaN/inf at flat index \[0\]"),
        ("eight", "must be a numeric array"),
    ],
)
def test_bad_arrays(barrett: bh.Hand, call, argument: str, bad, message: str) -> None:
    with pytest.raises(bh.InputError, match=f"`{argument}` {message}"):
        call(barrett, bad)


def test_bad_external_forces(barrett: bh.Hand) -> None:
    q = v = tau = np.zeros(8)
    with pytest.raises(bh.InputError, match=r"`f_ext` must have shape \(9, 6\), got shape \(8, 6\)"):
        barrett.forward_dynamics(q, v, tau, np.zeros((8, 6)))
    with pytest.raises(bh.InputError, match=r"`f_ext` must hold 9 forces .* got 2"):
        barrett.forward_dynamics(q, v, tau, [pin.Force.Zero(), pin.Force.Zero()])
    with pytest.raises(bh.InputError, match=r"`forces\['F1_tip'\]` must be finite"):
        barrett.external_forces(q, {"F1_tip": [0.0, np.nan, 1.0]})
    with pytest.raises(bh.InputError, match=r"`forces\['F1_tip'\]` must have shape \(3,\), got shape \(2,\)"):
        barrett.external_forces(q, {"F1_tip": [0.0, 1.0]})


def test_bad_gravity_placement_and_seed(barrett: bh.Hand) -> None:
    with pytest.raises(bh.InputError, match=r"`gravity` must have shape \(3,\)"):
        bh.BarrettHand(gravity=(0.0, -9.81))
    with pytest.raises(bh.InputError, match="`base_placement` must be a pinocchio.SE3, got ndarray"):
        bh.BarrettHand(base_placement=np.eye(4))
    with pytest.raises(bh.InputError, match="`rng` must be a numpy.random.Generator or an integer seed, got None"):
        barrett.random_configuration(None)


def test_bad_ik_arguments(barrett: bh.Hand) -> None:
    with pytest.raises(bh.InputError, match=r"`position` must have shape \(3,\)"):
        bh.finger_ik(barrett, "F1", [0.1, 0.2])
    with pytest.raises(bh.InputError, match=r"`targets\['F1'\]` must be finite"):
        bh.ik(barrett, {"F1": [np.nan, 0, 0]})
    with pytest.raises(bh.InputError, match="`restarts` needs a seeded `rng`"):
        bh.ik(barrett, {"F1": [0, 0, 0.1]}, restarts=3)
    with pytest.raises(bh.InputError, match="`tolerance` must be a positive finite number, got -1.0"):
        bh.ik(barrett, {"F1": [0, 0, 0.1]}, tolerance=-1)
    with pytest.raises(bh.InputError, match="`n` must be a positive integer, got 0"):
        bh.workspace(barrett, "F1", 0, rng=0)


def test_bad_input_loses_nothing(barrett: bh.Hand) -> None:
    """A rejected call leaves the hand as it was: later calls give the same answers."""
    q = barrett.random_configuration(2)
    before = barrett.mass_matrix(q), barrett.gravity.copy()
    with pytest.raises(bh.InputError):
        barrett.gravity = (np.nan, 0.0, 0.0)
    with pytest.raises(bh.InputError):
        barrett.mass_matrix(np.full(8, np.nan))
    np.testing.assert_array_equal(barrett.mass_matrix(q), before[0])
    np.testing.assert_array_equal(barrett.gravity, before[1])
