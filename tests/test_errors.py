"""Every bad input raises a specific BhgraspError that names the argument, the value and what was expected."""

from __future__ import annotations

import warnings
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
    broken = VALID_URDF.replace('<limit lower="0" upper="2.443460952792061" velocity="2.454" effort="2.667"/>', "", 1)
    with pytest.raises(bh.ModelError, match="Pinocchio cannot build a model"):
        bh.Hand.from_urdf(write(tmp_path, broken))


def test_urdf_without_moving_joints(tmp_path: Path) -> None:
    with pytest.raises(bh.ModelError, match="no moving joints"):
        bh.Hand.from_urdf(write(tmp_path, '<robot name="rock"><link name="base"/></robot>'))


def test_unknown_fingertip_frame() -> None:
    with pytest.raises(bh.InputError, match="unknown frame 'F4_tip'; valid frames: universe, .*F3_tip"):
        bh.Hand.from_urdf(bh.barrett_urdf_path(), fingertips=["F1_tip", "F4_tip"], mimic="independent")


def test_mimic_couplings_load_coupled_or_as_independent_joints_and_nothing_else(tmp_path: Path) -> None:
    """The packaged Barrett URDF documents its couplings with <mimic>: loaded coupled by default (4 coordinates, the
    hand before breakaway), or as the 8 independent joints of bh.BarrettHand(); no coupling is silently dropped."""
    coupled = bh.Hand.from_urdf(bh.barrett_urdf_path())
    assert coupled.joint_names == ("F1_spread", "F1_proximal", "F2_proximal", "F3_proximal")
    assert {(c.joint, c.mimics) for c in coupled.couplings} == {
        ("F2_spread", "F1_spread"),
        ("F1_distal", "F1_proximal"),
        ("F2_distal", "F2_proximal"),
        ("F3_distal", "F3_proximal"),
    }
    hand = bh.Hand.from_urdf(bh.barrett_urdf_path(), mimic="independent")
    assert hand.nv == 8 and hand.joint_names == bh.BarrettHand().joint_names and hand.couplings == ()
    with pytest.raises(bh.InputError, match="`mimic` must be 'coupled' or 'independent', got 'apply'"):
        bh.Hand.from_urdf(bh.barrett_urdf_path(), mimic="apply")


def test_default_fingertips_are_the_leaves_below_a_moving_joint(tmp_path: Path) -> None:
    """The Barrett URDF's palm pad is a leaf fixed to the palm: not a finger.  A sensor fixed on a fingertip is."""
    assert bh.Hand.from_urdf(bh.barrett_urdf_path(), mimic="independent").fingers == ("F1_tip", "F2_tip", "F3_tip")
    sensor = (
        '<link name="F3_sensor"/><joint name="F3_sensor_joint" type="fixed"><parent link="F3_tip"/>'
        '<child link="F3_sensor"/></joint></robot>'
    )
    hand = bh.Hand.from_urdf(write(tmp_path, VALID_URDF.replace("</robot>", sensor)), mimic="independent")
    assert hand.fingers == ("F1_tip", "F2_tip", "F3_sensor")


# ---------------------------------------------------------------------- URDF inertias and encoding
KNUCKLE_MASS = '<mass value="0.14109"/>'  # first occurrence: F1_knuckle_link
KNUCKLE_ORIGIN = '<origin xyz="0.030616 -7.3219e-05 -0.011201" rpy="0 0 0"/>'
KNUCKLE_INERTIA = (
    '<inertia ixx="2.0672e-05" ixy="2.6024e-07" ixz="6.3481e-06" iyy="7.4105e-05" iyz="1.7118e-08" izz="6.8207e-05"/>'
)
ZERO_INERTIA = '<inertia ixx="0" ixy="0" ixz="0" iyy="0" iyz="0" izz="0"/>'


def inertia(ixx: float, ixy: float, ixz: float, iyy: float, iyz: float, izz: float) -> str:
    return f'<inertia ixx="{ixx}" ixy="{ixy}" ixz="{ixz}" iyy="{iyy}" iyz="{iyz}" izz="{izz}"/>'


@pytest.mark.parametrize(
    ("old", "new", "message"),
    [
        pytest.param(
            KNUCKLE_MASS,
            '<mass value="-0.14109"/>',
            r"<inertial> mass must be a finite number >= 0 \[kg\], got '-0.14109'",
            id="negative-mass",
        ),
        pytest.param(
            KNUCKLE_MASS,
            '<mass value="nan"/>',
            r"<inertial> mass must be a finite number >= 0 \[kg\], got 'nan'",
            id="nan-mass",
        ),
        pytest.param(
            KNUCKLE_MASS,
            '<mass value="inf"/>',
            r"<inertial> mass must be a finite number >= 0 \[kg\], got 'inf'",
            id="inf-mass",
        ),
        pytest.param(
            KNUCKLE_MASS,
            "",
            r"<inertial> mass must be a finite number >= 0 \[kg\], got no <mass value=...>",
            id="no-mass",
        ),
        pytest.param(
            'iyy="7.4105e-05"',
            'iyy="nan"',
            r"<inertial> needs six finite <inertia> components ixx, ixy, ixz, iyy, iyz, izz \[kg m\^2\], got iyy='nan'",
            id="nan-inertia",
        ),
        pytest.param(
            KNUCKLE_INERTIA,
            "",
            r"<inertial> needs six finite <inertia> components .* got no <inertia>",
            id="no-inertia",
        ),
        pytest.param(
            KNUCKLE_ORIGIN,
            '<origin xyz="0.03 nan 0"/>',
            r"<inertial> <origin xyz> must be 3 finite numbers, got '0.03 nan 0'",
            id="nan-origin",
        ),
        pytest.param(
            'ixx="2.0672e-05"',
            'ixx="-2.0672e-05"',
            r"the inertia tensor must be positive semi-definite, got principal moments \[-2.1\d+e-05, .*\] kg m\^2 "
            r"\(ixx=-2.0672e-05, ixy=2.6024e-07, .*\)",
            id="negative-ixx",
        ),
        pytest.param(
            KNUCKLE_INERTIA,
            inertia(1e-5, 0, 0, 1e-5, 2e-5, 1e-5),
            r"the inertia tensor must be positive semi-definite, got principal moments \[-1e-05, 1e-05, 3e-05\]",
            id="indefinite-with-positive-diagonal",
        ),
        pytest.param(
            'ixx="2.0672e-05"',
            'ixx="2.0e-04"',
            r"the moments of inertia ixx, iyy, izz break the triangle inequality "
            r"\(6.8207e-05 \+ 7.4105e-05 < 0.0002 kg m\^2\): no rigid body has them",
            id="triangle-inequality",
        ),
    ],
)
def test_urdf_with_an_impossible_inertial_is_refused(tmp_path: Path, old: str, new: str, message: str) -> None:
    assert old in VALID_URDF
    with pytest.raises(bh.ModelError, match=r"URDF '.*hand.urdf' link 'F1_knuckle_link': " + message):
        bh.Hand.from_urdf(write(tmp_path, VALID_URDF.replace(old, new, 1)))


def test_urdf_inertia_that_pinocchio_merges_into_inf_is_refused(tmp_path: Path) -> None:
    """Each link is finite, but the fixed fingertip link merges into its parent body with an infinite mass."""
    huge = VALID_URDF.replace('<mass value="0.04166"/>', '<mass value="1e308"/>', 1).replace(
        '<link name="F1_tip"/>',
        f'<link name="F1_tip"><inertial><mass value="1e308"/>{ZERO_INERTIA}</inertial></link>',
    )
    with pytest.raises(
        bh.ModelError,
        match=r"URDF '.*hand.urdf': the body of joint 'F1_distal' \(links F1_distal_link, F1_tip\) must have a finite "
        r"mass >= 0 \[kg\], centre of mass and inertia in Pinocchio's model, got mass inf",
    ):
        bh.Hand.from_urdf(write(tmp_path, huge))


def test_urdf_point_masses_and_massless_links_stay_legal(tmp_path: Path) -> None:
    legal = VALID_URDF.replace(
        '<link name="F1_tip"/>', f'<link name="F1_tip"><inertial><mass value="0"/>{ZERO_INERTIA}</inertial></link>'
    ).replace(
        '<link name="F2_tip"/>', f'<link name="F2_tip"><inertial><mass value="0.01"/>{ZERO_INERTIA}</inertial></link>'
    )
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        hand = bh.Hand.from_urdf(write(tmp_path, legal), mimic="independent")
    assert hand.total_mass == pytest.approx(bh.BarrettHand().total_mass + 0.01)


def test_urdf_principal_moments_breaking_the_triangle_inequality_warn(tmp_path: Path) -> None:
    """Positive definite, ixx, iyy, izz fine, but the products of inertia make I1 + I2 < I3 (as in Allegro's tips)."""
    allegro_tip = inertia(4.701248e-06, 1.255968e-06, 1.2936e-06, 3.649312e-06, 1.7622e-06, 4.701248e-06)
    with pytest.warns(
        UserWarning,
        match=r"no rigid body has the inertias of 1 link\(s\) \('F1_knuckle_link'\); check the signs of ixy, ixz, "
        r"iyz; the dynamics use them as given. E.g. link 'F1_knuckle_link': the principal moments of inertia "
        r"\[2.30064e-06, 3.48527e-06, 7.2659e-06\] kg m\^2 break the triangle inequality",
    ):
        hand = bh.Hand.from_urdf(
            write(tmp_path, VALID_URDF.replace(KNUCKLE_INERTIA, allegro_tip, 1)), mimic="independent"
        )
    assert hand.nv == 8


def test_published_hands_pass_the_inertia_checks() -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        bh.BarrettHand()
    with pytest.warns(UserWarning, match="the principal moments of inertia") as record:  # its fingertips: see above
        allegro = bh.Hand.from_urdf(bh.example_robot_data_urdf("allegro_hand_description/urdf/allegro_right_hand.urdf"))
    assert allegro.nv == 16
    assert len(record) == 1  # one warning for the file, one line of ~600 characters naming every link
    message = str(record[0].message)
    assert "inertias of 4 link(s) ('link_3.0', 'link_7.0', 'link_11.0', 'link_15.0')" in message
    assert "\n" not in message and len(message) < 700


def test_urdf_that_is_not_utf8(tmp_path: Path) -> None:
    path = tmp_path / "hand.urdf"
    path.write_bytes(VALID_URDF.replace("F1_knuckle_link", "F1_kn\xfcckle_link", 1).encode("latin-1"))
    line = VALID_URDF[: VALID_URDF.index("F1_knuckle_link")].count("\n") + 1
    with pytest.raises(
        bh.ModelError,
        match=rf"URDF '.*hand.urdf' is not UTF-8 text: byte 0xfc at offset \d+ \(line {line}\) is invalid UTF-8 "
        r"\(invalid start byte\); save the file as UTF-8",
    ):
        bh.Hand.from_urdf(path)


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


# ---------------------------------------------------------------------- object poses
def spring_mounted(pose: pin.SE3) -> bh.SpringMounted:
    return bh.SpringMounted(bh.Box(size=(0.1, 0.1, 0.1), mass=1.0, pose=pose), direction=(0, 0, 1), stiffness=100.0)


OBJECTS = {
    "Box": lambda pose: bh.Box(size=(0.1, 0.2, 0.3), mass=1.0, pose=pose),
    "Sphere": lambda pose: bh.Sphere(radius=0.05, mass=1.0, pose=pose),
    "Cylinder": lambda pose: bh.Cylinder(radius=0.05, length=0.2, density=500.0, pose=pose),
    "Capsule": lambda pose: bh.Capsule(radius=0.05, length=0.2, mass=1.0, pose=pose),
    "FixedBox": lambda pose: bh.FixedBox(size=(1.0, 1.0, 0.1), pose=pose),
    "SpringMounted": spring_mounted,
}


@pytest.mark.parametrize("kind", OBJECTS)
@pytest.mark.parametrize(
    ("rotation", "message"),
    [
        pytest.param(2.0 * np.eye(3), r"max \|R\^T R - I\| = 3, det R = 8: R = \[\[2.0, 0.0, 0.0\]", id="scaled"),
        pytest.param(np.diag([1.0, 1.0, -1.0]), r"max \|R\^T R - I\| = 0, det R = -1", id="reflection"),
        pytest.param(
            pin.rpy.rpyToMatrix(0.1, 0.2, 0.3) @ np.diag([1.0, 1.0, 1.0 + 1e-6]),
            r"max \|R\^T R - I\| = 2e-06",
            id="stretched",
        ),
    ],
)
def test_object_pose_whose_rotation_is_not_a_rotation(kind: str, rotation: np.ndarray, message: str) -> None:
    """Scene.initial_state turned such a pose into a quaternion, silently normalising 2 I to the identity."""
    with pytest.raises(
        bh.InputError,
        match=r"`pose` must have a rotation matrix as its rotation \(orthonormal, det \+1, within 1e-09\), got "
        + message,
    ):
        OBJECTS[kind](pin.SE3(rotation, np.array([0.1, 0.0, 0.2])))


@pytest.mark.parametrize("kind", OBJECTS)
def test_object_pose_with_nan_and_nearly_orthonormal_rotation(kind: str) -> None:
    rotation = pin.rpy.rpyToMatrix(0.3, -0.2, 1.0)
    with pytest.raises(bh.InputError, match="`pose` must be finite"):
        OBJECTS[kind](pin.SE3(rotation, np.array([0.1, np.nan, 0.2])))
    rounded = rotation + 1e-12  # within the 1e-9 tolerance: accepted, and kept as given
    assert np.array_equal(OBJECTS[kind](pin.SE3(rounded, np.zeros(3))).pose.rotation, rounded)


def test_hand_base_placement_whose_rotation_is_not_a_rotation() -> None:
    """A scaled base rotation was accepted: every world quantity of the hand was then scaled with it."""
    with pytest.raises(bh.InputError, match=r"`base_placement` must have a rotation matrix as its rotation"):
        bh.BarrettHand(base_placement=pin.SE3(2.0 * np.eye(3), np.zeros(3)))
    hand = bh.BarrettHand()
    with pytest.raises(bh.InputError, match=r"det R = -1"):
        hand.base_placement = pin.SE3(np.diag([1.0, 1.0, -1.0]), np.zeros(3))
    assert hand.base_placement.isIdentity()  # refused: nothing changed


def test_the_other_hands_are_an_optional_extra_named_when_missing(monkeypatch: pytest.MonkeyPatch) -> None:
    """example-robot-data (414 MB) is the `hands` extra: without it, asking for the Allegro names the extra."""
    import sys

    from bhgrasp.model import resources

    monkeypatch.setattr(sys, "path", [])
    monkeypatch.setattr(sys, "prefix", "/nonexistent")
    monkeypatch.setattr(sys, "base_prefix", "/nonexistent")
    with pytest.raises(bh.ModelError, match=r"optional extra of bhgrasp .*pip install 'bhgrasp\[hands\]'"):
        resources.example_robot_data_urdf("allegro_hand_description/urdf/allegro_right_hand.urdf")
    pyproject = (Path(__file__).resolve().parents[1] / "pyproject.toml").read_text()
    core = pyproject.split("dependencies = [", 1)[1].split("]", 1)[0]
    assert "example-robot-data" not in core and 'hands = ["example-robot-data' in pyproject
