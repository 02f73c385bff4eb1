"""The packaged URDF tested like code (mujoco_menagerie style): names, limits, masses, inertias, simulation.

The truths here are Barrett's published tables (sources in urdf/README.md), read independently of
Pinocchio from the XML itself, and two other URDF consumers (yourdfpy, MuJoCo).
"""

from __future__ import annotations

import logging
import re
import warnings
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import bhgrasp as bh
from bhgrasp.barrett.transmission import MAX_MOTOR_TORQUE

JOINTS = ["F1_spread", "F1_proximal", "F1_distal", "F2_spread", "F2_proximal", "F2_distal", "F3_proximal", "F3_distal"]
# Barrett WIKI-MASS v5 masses [kg]: palm with pad, knuckle x2, inner link x3, fingertip x3.
BARRETT_TOTAL_MASS = 0.60858 + 2 * 0.14109 + 3 * 0.062139 + 3 * 0.04166


@pytest.fixture(scope="module")
def urdf_root() -> ET.Element:
    return ET.parse(bh.barrett_urdf_path()).getroot()


def test_loads_in_pinocchio_without_warnings() -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        model = pin.buildModelFromUrdf(str(bh.barrett_urdf_path()))
    assert model.nq == model.nv == 8


def test_joint_names_and_order(barrett: bh.Hand, urdf_root: ET.Element) -> None:
    assert list(barrett.joint_names) == JOINTS
    revolute = [j.get("name") for j in urdf_root.iter("joint") if j.get("type") == "revolute"]
    assert sorted(revolute) == sorted(JOINTS)
    assert barrett.fingers == ("F1", "F2", "F3")
    for frame in ("F1_tip", "F2_tip", "F3_tip", "palm_surface"):
        assert barrett.model.existFrame(frame)


def test_limits_are_barretts(barrett: bh.Hand) -> None:
    degrees = {"spread": 180.0, "proximal": 140.0, "distal": 48.0}
    for i, joint in enumerate(barrett.joint_names):
        assert barrett.lower[i] == 0.0
        assert np.degrees(barrett.upper[i]) == pytest.approx(degrees[joint.split("_")[1]], abs=1e-9)
    # Velocity limits from the puck default MV [counts/ms], 4096 counts/rev and the gear ratios.
    motor_speed = {
        "spread": 50e3 / 4096 * 2 * np.pi,
        "proximal": 200e3 / 4096 * 2 * np.pi,
        "distal": 200e3 / 4096 * 2 * np.pi,
    }
    ratio = {"spread": 17.5, "proximal": 125.0, "distal": 93.75}
    for i, joint in enumerate(barrett.joint_names):
        kind = joint.split("_")[1]
        assert barrett.velocity_limit[i] == pytest.approx(motor_speed[kind] / ratio[kind], rel=1e-3)
        assert barrett.effort_limit[i] == pytest.approx(MAX_MOTOR_TORQUE * ratio[kind], rel=1e-3)  # the pucks' MT


def test_mimic_tags_document_the_couplings(urdf_root: ET.Element) -> None:
    mimic = {j.get("name"): j.find("mimic") for j in urdf_root.iter("joint") if j.find("mimic") is not None}
    assert mimic["F2_spread"].get("joint") == "F1_spread" and float(mimic["F2_spread"].get("multiplier")) == 1.0
    for finger in ("F1", "F2", "F3"):
        tag = mimic[f"{finger}_distal"]
        assert tag.get("joint") == f"{finger}_proximal"
        assert float(tag.get("multiplier")) == pytest.approx(125.0 / 375.0)  # libbarrett J2_RATIO / J3_RATIO


def test_total_mass_is_barretts(barrett: bh.Hand, urdf_root: ET.Element) -> None:
    xml_mass = sum(float(m.get("value")) for m in urdf_root.iter("mass"))
    assert xml_mass == pytest.approx(BARRETT_TOTAL_MASS, abs=1e-9)
    assert barrett.total_mass == pytest.approx(BARRETT_TOTAL_MASS, abs=1e-9)
    assert BARRETT_TOTAL_MASS == pytest.approx(1.20, abs=0.005)


def test_inertias_are_physical(urdf_root: ET.Element) -> None:
    for link in urdf_root.iter("link"):
        inertial = link.find("inertial")
        if inertial is None:
            continue
        t = {k: float(v) for k, v in inertial.find("inertia").attrib.items()}
        tensor = np.array(
            [[t["ixx"], t["ixy"], t["ixz"]], [t["ixy"], t["iyy"], t["iyz"]], [t["ixz"], t["iyz"], t["izz"]]]
        )
        principal = np.linalg.eigvalsh(tensor)
        assert principal.min() > 0, link.get("name")
        a, b, c = principal
        assert a + b >= c and a + c >= b and b + c >= a, link.get("name")


def test_geometry_matches_barretts_kinematics(barrett: bh.Hand) -> None:
    """Recommended parameter set: spread axes at x = -/+25 mm, knuckle axes 50 mm out at 75.4 mm, 70 mm proximal."""
    q = barrett.neutral()
    origin = {name: barrett.frame_placement(q, name).translation for name in barrett.frame_names()}
    np.testing.assert_allclose(origin["F1_spread"], [-0.025, 0.0, 0.0754], atol=1e-12)
    np.testing.assert_allclose(origin["F2_spread"], [0.025, 0.0, 0.0754], atol=1e-12)
    np.testing.assert_allclose(origin["F3_proximal"], [0.0, 0.050, 0.0754], atol=1e-12)
    for finger in ("F1", "F2", "F3"):
        proximal, distal = origin[f"{finger}_proximal"], origin[f"{finger}_distal"]
        assert np.linalg.norm(distal - proximal) == pytest.approx(0.070, abs=1e-6)
        assert proximal[2] == pytest.approx(0.0754)
        assert np.degrees(np.arcsin((distal - proximal)[2] / 0.070)) == pytest.approx(2.456, abs=1e-3)
        tip = origin[f"{finger}_tip"]
        assert np.linalg.norm(tip - distal) == pytest.approx(0.050)
        # Fixed 40 deg bend: at q = 0 the distal link rises 40 deg above the palm plane.
        assert np.degrees(np.arcsin((tip - distal)[2] / 0.050)) == pytest.approx(40.0, abs=1e-9)
    # F1 and F2 side by side opposing F3 at zero spread (Barrett's D-H): fingertips on -y, F3's on +y.
    tips = barrett.fingertip_positions(q)
    assert tips[0, 1] < 0 and tips[1, 1] < 0 and tips[2, 1] > 0


def test_yourdfpy_validates_without_warnings(caplog: pytest.LogCaptureFixture) -> None:
    import yourdfpy

    with caplog.at_level(logging.WARNING):
        robot = yourdfpy.URDF.load(str(bh.barrett_urdf_path()), build_scene_graph=True, load_meshes=False)
        assert robot.validate()
    assert not caplog.records, [record.getMessage() for record in caplog.records]
    assert set(robot.joint_names) >= set(JOINTS)


def test_mujoco_loads_it_with_the_same_dynamics(barrett: bh.Hand) -> None:
    """A second physics engine reads the same URDF: its mass matrix and gravity torques must equal Pinocchio's."""
    mujoco = pytest.importorskip("mujoco", reason="MuJoCo is a test dependency; installed by .ci/run")
    model = mujoco.MjModel.from_xml_path(str(bh.barrett_urdf_path()))
    assert [model.joint(i).name for i in range(model.njnt)] == JOINTS
    data = mujoco.MjData(model)
    rng = np.random.default_rng(7)
    for _ in range(5):
        q = barrett.random_configuration(rng)
        data.qpos[:], data.qvel[:] = q, 0.0
        mujoco.mj_forward(model, data)
        mass = np.zeros((model.nv, model.nv))
        mujoco.mj_fullM(model, data, mass)
        np.testing.assert_allclose(mass, barrett.mass_matrix(q), atol=1e-10)
        np.testing.assert_allclose(data.qfrc_bias, barrett.gravity_torques(q), atol=1e-10)


def test_one_second_of_aba_under_random_torques_stays_finite(barrett: bh.Hand) -> None:
    rng = np.random.default_rng(3)
    q, v, dt = barrett.neutral(), np.zeros(barrett.nv), 1e-4
    for _ in range(10_000):
        tau = 0.05 * barrett.effort_limit * rng.uniform(-1.0, 1.0, barrett.nv)
        v = v + dt * barrett.forward_dynamics(q, v, tau)
        q = q + dt * v
    assert np.all(np.isfinite(q)) and np.all(np.isfinite(v))


def test_the_provenance_cites_only_public_sources_it_lists() -> None:
    """urdf/README.md names no file outside the repository as if it were in it; every source key it or the URDF's
    comments use (the keys of the collected public data) is listed with its public location."""
    folder = Path(__file__).resolve().parents[1] / "urdf"
    readme, urdf = (folder / "README.md").read_text(), (folder / "barrett_hand.urdf").read_text()
    assert "shared/" not in readme
    listed = set(re.findall(r"^\| ([A-Z][A-Za-z0-9-]+) \|", readme.split("## Sources", 1)[1], flags=re.MULTILINE))
    known = {
        "WIKI-MASS",
        "WIKI-KIN",
        "WIKI-SAFE",
        "MAN-262",
        "MAN-BH8",
        "LIBB",
        "HERB",
        "JHU",
        "SWX",
        "ROB",
        "ROB-old",
        "RISE",
        "BRP",
        "GRASPIT",
        "ORAVE",
        "AIKIDO",
        "BLAYER",
    }
    used = {key for key in known if re.search(rf"(?<![A-Za-z-]){re.escape(key)}(?![A-Za-z-])", readme + urdf)}
    assert used and used <= listed, f"source keys used but not listed: {sorted(used - listed)}"
