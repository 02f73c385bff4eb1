"""Issue 32 item 6: grasp synthesis and a grasp scene for any hand (the opposition search).

The hand here is written in this file: a four-finger gripper (two fingers on each side of the palm, each a
proximal and a distal link flexing in its own vertical plane, a 10 mm pad sphere on the tip).  The checks are
independent of the search: coal distances in the simulator's scene, closed forms of the traced lines, Newton on the
held object.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from urdf_parts import rod

import bhgrasp as bh
from bhgrasp.grasp.metrics import finger_normal_forces
from bhgrasp.grasp.opposition import opposed_grasp, opposed_grasps
from bhgrasp.grasp.pad_placement import pad_radii
from bhgrasp.grasp.probes import TRACE_TOLERANCE, ObjectProbe, first_hit
from bhgrasp.scenarios.object_grasp import object_grasp, run_object_grasp
from bhgrasp.sim.start_check import pair_distances

KNUCKLES = {  # finger -> knuckle x, y [m] on the palm, and the sign of its joint axes along y (-1 closes toward -x)
    "F1": (0.06, 0.025, -1.0),
    "F2": (0.06, -0.025, -1.0),
    "F3": (-0.06, 0.025, 1.0),
    "F4": (-0.06, -0.025, 1.0),
}
LINKS = (0.07, 0.05)  # [m] proximal, distal
PAD = 0.010  # [m]
BOX = bh.Box(size=(0.05, 0.08, 0.05), mass=0.3, pose=pin.SE3(np.eye(3), np.array([0.0, 0.0, 0.10])))
GRAVITY = np.array([0.0, 0.0, -9.81])


def gripper_urdf(pads: bool = True) -> str:
    """Palm at the origin (top face z = 0), fingers up along z; ``sign`` -1 closes toward -x, +1 toward +x."""
    palm = (
        '<link name="palm"><inertial><origin xyz="0 0 -0.01"/><mass value="0.5"/><inertia ixx="4e-4" '
        'iyy="6e-4" izz="9e-4" ixy="0" ixz="0" iyz="0"/></inertial><collision><origin xyz="0 0 -0.01"/>'
        '<geometry><box size="0.16 0.1 0.02"/></geometry></collision></link>'
    )
    parts = ['<?xml version="1.0"?><robot name="gripper4">', palm]
    limit = '<limit lower="-0.6" upper="1.6" effort="2" velocity="3"/>'
    for name, (x, y, sign) in KNUCKLES.items():
        pad = f'<collision><geometry><sphere radius="{PAD}"/></geometry></collision>' if pads else ""
        parts += [
            rod(f"{name}_proximal", LINKS[0]),
            rod(f"{name}_distal", LINKS[1]),
            f'<link name="{name}"><inertial><mass value="0.01"/><inertia ixx="4e-7" iyy="4e-7" izz="4e-7" ixy="0" '
            f'ixz="0" iyz="0"/></inertial>{pad}</link>',
            f'<joint name="{name}_proximal_joint" type="revolute"><parent link="palm"/><child link="{name}_proximal"/>'
            f'<origin xyz="{x} {y} 0"/><axis xyz="0 {sign} 0"/>{limit}</joint>',
            f'<joint name="{name}_distal_joint" type="revolute"><parent link="{name}_proximal"/>'
            f'<child link="{name}_distal"/><origin xyz="0 0 {LINKS[0]}"/><axis xyz="0 {sign} 0"/>{limit}</joint>',
            f'<joint name="{name}_tip" type="fixed"><parent link="{name}_distal"/><child link="{name}"/>'
            f'<origin xyz="0 0 {LINKS[1]}"/></joint>',
        ]
    return "".join([*parts, "</robot>"])


def load(tmp: Path, pads: bool = True) -> bh.Hand:
    path = tmp / "gripper4.urdf"
    path.write_text(gripper_urdf(pads))
    return bh.Hand.from_urdf(path)


@pytest.fixture(scope="module")
def hand(tmp_path_factory) -> bh.Hand:
    return load(tmp_path_factory.mktemp("gripper"))


@pytest.fixture(scope="module")
def setup(hand):
    return object_grasp(BOX, hand=hand, directions=0)  # across the box's faces


def test_pads_are_the_spheres_on_the_fingertip_frames(hand, tmp_path) -> None:
    assert pad_radii(hand) == dict.fromkeys(KNUCKLES, PAD)
    assert pad_radii(bh.BarrettHand()) == dict.fromkeys(("F1", "F2", "F3"), 0.010)  # the synthesis' documented pads
    with pytest.raises(bh.InputError, match="finger 'F1' has no collision sphere.*pad_radius"):
        pad_radii(load(tmp_path, pads=False))


def test_traced_lines_meet_the_closed_forms() -> None:
    """A sphere of radius R: a line at distance b from its centre enters at sqrt(R^2 - b^2) before the chord's
    middle, normal (p - c) / R; a box: its face; a line that passes by: no hit; a start inside: no hit."""
    centre, radius = np.array([0.01, -0.02, 0.1]), 0.03
    sphere = bh.Sphere(radius=radius, mass=0.1, pose=pin.SE3(np.eye(3), centre))
    probe = ObjectProbe(sphere.geometry(), sphere.pose)
    offset = np.array([0.0, 0.012, 0.01])  # b = |offset| from the centre, normal to the line (along -x)
    start = centre + offset + np.array([0.2, 0.0, 0.0])
    point, normal = first_hit(probe, start, np.array([-1.0, 0.0, 0.0]), 0.5)
    expected = centre + offset + np.array([np.sqrt(radius**2 - offset @ offset), 0.0, 0.0])
    np.testing.assert_allclose(point, expected, atol=TRACE_TOLERANCE)
    np.testing.assert_allclose(normal, (expected - centre) / radius, atol=1e-3)
    box_probe = ObjectProbe(BOX.geometry(), BOX.pose)
    point, normal = first_hit(box_probe, np.array([-0.2, 0.01, 0.11]), np.array([1.0, 0.0, 0.0]), 0.5)
    np.testing.assert_allclose(point, [-0.025, 0.01, 0.11], atol=TRACE_TOLERANCE)
    np.testing.assert_allclose(normal, [-1.0, 0.0, 0.0], atol=1e-9)
    assert first_hit(box_probe, np.array([-0.2, 0.05, 0.11]), np.array([1.0, 0.0, 0.0]), 0.5) is None  # passes by
    assert first_hit(box_probe, BOX.pose.translation, np.array([1.0, 0.0, 0.0]), 0.5) is None  # starts inside


def test_the_grasp_touches_with_its_pads_only(setup) -> None:
    """coal in the simulator's scene: at q_contact each pad touches the box and every other link keeps 1.5 mm; the
    pre-grasp pads stand 20 mm off, the approach's target presses them 8 mm in; two pads a side, 50 mm apart (their
    knuckles' distance)."""
    scene, c = setup.simulator.scene, setup.candidate
    assert sorted(c.fingers) == sorted(KNUCKLES) and c.quality.force_closure and c.holds_weight

    def distances(q_hand: np.ndarray) -> dict[str, float]:
        q, _ = scene.initial_state(q_hand)
        pairs = [p for p in scene.pairs if p.body_b == scene.object_names[0] and p.joint_a != 0]
        return dict(zip((p.body_a for p in pairs), pair_distances(scene, q, [p.index for p in pairs])))

    pads = set(KNUCKLES)  # the tip links, whose one shape is the pad
    at_contact, pregrasp, closed = distances(c.q_contact), distances(c.q_pregrasp), distances(c.q_close)
    for pad in pads:
        assert abs(at_contact[pad]) < 2e-5  # [m]
        assert pregrasp[pad] == pytest.approx(0.02, abs=1e-4)
        assert closed[pad] == pytest.approx(-0.008, abs=1e-4)
    assert min(d for name, d in at_contact.items() if name not in pads) > 1.5e-3
    sides = {sign: c.points[[KNUCKLES[f][2] == sign for f in c.fingers]] for sign in (-1.0, 1.0)}
    for points in sides.values():
        assert np.linalg.norm(points[0] - points[1]) == pytest.approx(0.05, abs=1e-6)
    assert np.all(np.abs(sides[-1.0][:, 0] - 0.025) < 1e-5) and np.all(np.abs(sides[1.0][:, 0] + 0.025) < 1e-5)


def test_the_search_is_deterministic(hand) -> None:
    first, second = (opposed_grasps(hand, BOX, fingers=("F1", "F2", "F3"), directions=2) for _ in range(2))
    assert len(first) == len(second) > 0
    assert all(np.array_equal(a.q_contact, b.q_contact) for a, b in zip(first, second))


def test_the_gripper_grasps_lifts_and_turns_the_box_and_learns_its_mass(setup, hand) -> None:
    """The demo's sequence (SMC-adaptive law from half the mass, the friction-cone QP) on a hand written in this
    file; at rest at the end the contact forces on the box sum to -m g (Newton, the pedestal left behind)."""
    result = run_object_grasp(setup, offset=(0.0, 0.0, 0.01, 0.0, 0.1, 0.0), duration=2.5)
    assert result.slip_events == 0 and result.infeasible_samples == 0 and result.force_error < 0.01
    assert result.mass_estimate == pytest.approx(BOX.mass, rel=0.01)
    assert result.position_error < 1e-4 and result.rotation_error < 1e-3  # [m], [rad]
    traj = result.trajectory
    contacts = traj.contacts_at(len(traj) - 1)
    assert all(body in KNUCKLES for body, _ in contacts["bodies"])
    np.testing.assert_allclose(contacts["force"].sum(axis=0), -BOX.mass * GRAVITY, atol=0.01)  # [N]
    assert np.all(finger_normal_forces(hand, traj)[-1] > 1.0)  # every pad presses [N]


def test_an_object_out_of_reach_is_refused_with_the_reasons(hand) -> None:
    far = bh.Box(size=(0.05, 0.05, 0.05), mass=0.3, pose=pin.SE3(np.eye(3), np.array([0.0, 0.0, 0.5])))
    with pytest.raises(bh.UnreachableError, match=r"no grasp of Box at \[0.0, 0.0, 0.5\] m by gripper4.*out of reach"):
        opposed_grasp(hand, far, fingers=("F1", "F2", "F3"), directions=2)
