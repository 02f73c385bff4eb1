"""The BH8-280's sensors against independent truths: the gear train's closed forms
and libbarrett's published numbers (encoders), the Jacobian reaction torques of bhgrasp.grasp.sensing and r x F
(fingertip torque), Barrett's published strain-gauge points and libbarrett's tactile scale (counts, ranges,
saturation), force conservation, symmetry and the hand's collision geometry (tactile pads), Newton's third law
(a contact read the same from either side of its pair), a simulated grasp of a box and a finger stalled on a block."""

from __future__ import annotations

import coal
import numpy as np
import pinocchio as pin
import pytest

import bhgrasp as bh
from bhgrasp.barrett import (
    BarrettDriver,
    BarrettSensors,
    digitise_pressures,
    encoder_counts,
    finger_pad,
    link_positions,
    motor_angles,
    palm_pad,
    strain_counts,
    strain_torques,
)
from bhgrasp.barrett.readout import S_TACT_FULL
from bhgrasp.barrett.transmission import DISTAL_ALONE_RATIO, MAX_MOTOR_TORQUE, WORM_EFFICIENCY
from bhgrasp.bench.protocol import DT
from bhgrasp.bench.trial import contact_law
from bhgrasp.data import State
from bhgrasp.errors import InputError
from bhgrasp.grasp.sensing import ContactSensing
from bhgrasp.model.objects import FixedBox
from bhgrasp.scenarios.box_grasp import box_grasp
from bhgrasp.sim import Simulator
from bhgrasp.sim.actuation import BarrettActuation
from bhgrasp.sim.scene import Scene

COUNT = 2 * np.pi / 4096  # [rad] one motor count (libbarrett MotorPuck: rpc = 2 pi / CTS, CTS = 4096)
SG_PER_NM = (3460 - 667) / 2.28  # Barrett's self-preservation points: SG 667 and 3460 at +/-1.14 N m
FINGERS = ("F1", "F2", "F3")
TILTED = pin.SE3(pin.exp3(np.array([0.3, -0.2, 0.5])), np.array([0.1, -0.05, 0.2]))


@pytest.fixture(scope="module")
def hand() -> bh.Hand:
    return bh.BarrettHand(base_placement=TILTED)


@pytest.fixture(scope="module")
def sensors(hand) -> BarrettSensors:
    return BarrettSensors(hand)


def contacts(hand, q, rows) -> State:
    """A state at ``q`` with contacts (link, point in that link's frame [m], normal and force in that frame)."""
    bodies, points, normals, forces = [], [], [], []
    for link, point, normal, force in rows:
        placement = hand.frame_placement(q, link)
        bodies.append((link, "object"))
        points.append(placement.act(np.asarray(point, dtype=float)))
        normals.append(placement.rotation @ normal)
        forces.append(placement.rotation @ force)
    return State(
        0.0,
        q,
        np.zeros(hand.nv),
        contact_points=np.array(points).reshape(-1, 3),
        contact_normals=np.array(normals).reshape(-1, 3),
        contact_forces=np.array(forces).reshape(-1, 3),
        contact_bodies=tuple(bodies),
    )


def pad_point(pad_name: str, u: float, w: float, h: float) -> tuple[str, np.ndarray]:
    """A point at pad coordinates [m] in its frame: fingertip (x, y, z) = (u, h, w); palm: GraspIt's x, y negated."""
    if pad_name == "palm":
        return "palm_surface", np.array([-u, -w, h])
    return f"{pad_name}_distal_link", np.array([u, h, w])


def pad_normal(pad_name: str) -> np.ndarray:
    return np.array([0.0, 0.0, 1.0]) if pad_name == "palm" else np.array([0.0, 1.0, 0.0])


def cell_forces(reading, pad) -> np.ndarray:
    index = ("F1", "F2", "F3", "palm").index(pad.name)
    return reading.tactile[index] * 1e4 * pad.areas  # N/cm^2 * cm^2


# ------------------------------------------------------------------ encoders
def test_motor_angle_is_125_proximal_armed_and_turns_the_distal_at_93_75_broken_away() -> None:
    q_proximal = np.array([0.4, 1.1, 2.0])
    armed = motor_angles(q_proximal, q_proximal / 3, 0.0)
    np.testing.assert_allclose(armed[:3], 125.0 * q_proximal, rtol=1e-15)  # libbarrett J2_RATIO
    # broken away: the proximal holds, the motor turns on by delta and drives the distal alone through its worm
    delta = np.array([5.0, 20.0, 40.0])  # [rad] at the motor
    broken = motor_angles(q_proximal, q_proximal / 3 + delta / 93.75, 0.0)
    np.testing.assert_allclose(broken[:3], 125.0 * q_proximal + delta, rtol=1e-15)
    assert motor_angles(q_proximal, q_proximal / 3, 0.7)[3] == pytest.approx(17.5 * 0.7, rel=1e-15)


def test_encoder_counts_are_quantised_angles_and_libbarrett_recovers_the_joints() -> None:
    rng = np.random.default_rng(3)
    for _ in range(50):
        q_proximal, spread = rng.uniform(0, 2.44, 3), rng.uniform(0, np.pi)
        q_distal = q_proximal / 3 + rng.uniform(0, 0.5, 3) * (rng.random(3) < 0.5)  # armed or broken away
        primary, secondary = encoder_counts(q_proximal, q_distal, spread)
        assert primary.dtype.kind == "i" and secondary.dtype.kind == "i"
        motor = np.append(125.0 * q_proximal + 93.75 * (q_distal - q_proximal / 3), 17.5 * spread)  # the gear train
        np.testing.assert_array_equal(primary, np.rint(motor / COUNT))
        np.testing.assert_array_equal(secondary, np.rint(50.0 * q_proximal / COUNT))
        inner, outer = link_positions(primary, secondary)
        inner_resolution, motor_resolution = 0.5 * COUNT / 50.0, 0.5 * COUNT * (1 / 125 + 1 / 375)
        assert np.abs(inner[:3] - q_proximal).max() <= inner_resolution * (1 + 1e-9)
        assert np.abs(outer[:3] - q_distal).max() <= (inner_resolution + motor_resolution) * (1 + 1e-9)
        assert inner[3] == outer[3] and abs(inner[3] - spread) <= 0.5 * COUNT / 17.5 * (1 + 1e-9)
        # unquantised, libbarrett's outer formula is the true distal angle, armed or broken away
        _, exact = link_positions(motor / COUNT, 50.0 * q_proximal / COUNT)
        np.testing.assert_allclose(exact[:3], q_distal, rtol=1e-12, atol=1e-12)


def test_without_secondary_encoders_libbarrett_is_right_only_before_breakaway() -> None:
    q_proximal = np.array([0.5, 1.0, 1.5])
    armed = motor_angles(q_proximal, q_proximal / 3, 0.0) / COUNT
    inner, outer = link_positions(armed)
    np.testing.assert_allclose(inner[:3], q_proximal, rtol=1e-12)
    np.testing.assert_allclose(outer[:3], q_proximal / 3, rtol=1e-12)
    broken = motor_angles(q_proximal, q_proximal / 3 + 0.2, 0.0) / COUNT
    assert (link_positions(broken)[0][:3] > q_proximal + 0.1).all()  # reads the distal's travel as proximal
    # Robotnik's full finger range, 195 000 counts, is 137.1 degrees of proximal (barrett_public_data.md 1.3)
    assert np.degrees(link_positions(np.array([195000, 0, 0, 36000]))[0][0]) == pytest.approx(137.1, abs=0.05)


# ------------------------------------------------------------------ fingertip torque
def test_fingertip_torque_is_the_distal_joints_contact_torque(hand, sensors) -> None:
    rng = np.random.default_rng(5)
    q = hand.random_configuration(rng)
    rows = []
    for link in ("F1_distal_link", "F2_distal_link", "F3_distal_link", "F1_proximal_link", "palm"):
        for _ in range(3):
            rows.append((link, rng.uniform(-0.02, 0.05, 3), np.array([0.0, 1.0, 0.0]), rng.normal(size=3)))
    state = contacts(hand, q, rows)
    loads = sensors.loads(state)
    reaction = ContactSensing(hand).reaction_torques(state)  # sum of J_p^T F_on_hand (Pinocchio Jacobians)
    distal = [hand.joint_index(f"{f}_distal") for f in FINGERS]
    np.testing.assert_allclose(loads.fingertip_torque, reaction[distal], rtol=1e-12, atol=1e-15)
    # closed form: 4 N on the tip frame (50 mm out), pressing along the pad normal, opens the fingertip: -0.05 * 4
    push = contacts(hand, q, [("F2_distal_link", [0.05, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 4.0, 0.0])])
    np.testing.assert_allclose(sensors.loads(push).fingertip_torque, [0.0, -0.2, 0.0], atol=1e-14)
    # as the hardware reports it: SG counts rising as the tip is pushed open, 1225 per N m about "around 2000"
    reading = sensors.read(push)
    assert reading.fingertip_torque.dtype.kind == "i"
    zero = (667 + 3460) / 2  # midway between Barrett's two points
    np.testing.assert_array_equal(reading.fingertip_torque, np.rint([zero, zero + 0.2 * SG_PER_NM, zero]))
    np.testing.assert_allclose(reading.fingertip_torque_nm, [0.0, -0.2, 0.0], atol=0.5 / SG_PER_NM)


def test_strain_gauge_counts_follow_barretts_published_points() -> None:
    """SG is "a number between 0 and 4095", "around 2000" unloaded, 3460 and 667 at the +/-1.14 N m of the
    self-preservation (wiki Hand/280/KinematicsJointRangesConversionFactors); it rises as the tip is pushed open."""
    assert abs(int(strain_counts(0.0)) - 2000) < 100  # "around 2000" unloaded (the line is fitted elsewhere)
    torques = np.linspace(-1.6, 1.6, 3201)
    counts = strain_counts(torques)
    assert (np.diff(counts) <= 0).all() and counts.min() > 0 and counts.max() < 4095  # +/-1 N m and more: in range
    assert np.abs(strain_torques(counts) - torques).max() <= 0.5 / SG_PER_NM * (1 + 1e-9)  # half a count
    np.testing.assert_array_equal(strain_counts([-3.0, 3.0, -1e6]), [4095, 0, 4095])  # saturated, never beyond


def test_tactile_cells_report_twelve_bit_counts_over_256() -> None:
    """libbarrett's FullTactParser: a 12-bit count / 256 [N/cm^2]: steps of 1/256, full scale 4095/256."""
    pressures = np.array([0.0, 1.0 / 512 - 1e-9, 1.0 / 512 + 1e-9, 3.3, 15.99, 16.0, 400.0, -2.0])
    np.testing.assert_array_equal(
        digitise_pressures(pressures) * 256, [0, 0, 1, round(3.3 * 256), round(15.99 * 256), 4095, 4095, 0]
    )


def test_the_environment_pressing_a_link_reads_as_an_object_would(hand, sensors) -> None:
    """A table, stand or wall is body a of its pair (force on the hand link b): Newton's third law says the reading
    equals that of the same contact written the other way round (the link first, the force on the other body)."""
    rng = np.random.default_rng(11)
    q = hand.random_configuration(rng)
    rows = [
        (
            link,
            rng.uniform(0.0, 0.05, 3) * [1, 0.2, 0.2],
            np.array([0.0, 1.0, 0.0]),
            rng.normal(size=3) + np.array([0, 3, 0]),
        )
        for link in ("F1_distal_link", "F3_distal_link", "palm_surface")
        for _ in range(2)
    ]
    as_object = contacts(hand, q, rows)
    as_environment = State(
        0.0,
        q,
        np.zeros(hand.nv),
        contact_points=as_object.contact_points,
        contact_normals=-as_object.contact_normals,
        contact_forces=-as_object.contact_forces,
        contact_bodies=tuple(("table", link) for link, _ in as_object.contact_bodies),
    )
    first, second = sensors.loads(as_object), sensors.loads(as_environment)
    np.testing.assert_allclose(second.fingertip_torque, first.fingertip_torque, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(second.tactile, first.tactile, rtol=1e-12, atol=1e-15)
    assert np.abs(first.fingertip_torque[[0, 2]]).min() > 1e-3 and first.tactile.sum() > 0
    # two objects touching each other touch no sensor
    apart = State(
        0.0,
        q,
        np.zeros(hand.nv),
        contact_points=as_object.contact_points[:1],
        contact_normals=as_object.contact_normals[:1],
        contact_forces=as_object.contact_forces[:1],
        contact_bodies=(("cup", "box"),),
    )
    assert not sensors.loads(apart).fingertip_torque.any() and not sensors.loads(apart).tactile.any()


# ------------------------------------------------------------------ tactile pads
def test_pad_layouts_match_graspit() -> None:
    """Cell counts and sensing areas from GraspIt!'s BarrettBH8_280_Tactile.xml (rows, columns in mm)."""
    finger, palm = finger_pad("F1"), palm_pad()
    assert finger.cells.shape == palm.cells.shape == (24, 4)
    rows_mm = 5 * 5.5 + 3.0 + 2.5 + 1.75
    assert finger.areas.sum() == pytest.approx(rows_mm * (4.65 + 4.7 + 4.7) * 1e-6, rel=1e-12)
    assert palm.areas == pytest.approx(np.full(24, 1e-4), rel=1e-12)  # 10 mm squares


@pytest.mark.parametrize("pad", [*(finger_pad(f) for f in FINGERS), palm_pad()], ids=lambda p: p.name)
def test_cells_conserve_the_pads_normal_force(hand, sensors, pad) -> None:
    rng = np.random.default_rng(7)
    q = hand.random_configuration(rng)
    lo, hi = pad.cells[:, [0, 2]].min(axis=0), pad.cells[:, [1, 3]].max(axis=0)
    rows, pressing = [], 0.0
    for centre in rng.uniform(lo + 0.004, hi - 0.004, (4, 2)):
        for u, w in centre + rng.uniform(-0.0015, 0.0015, (3, 2)):  # a patch of three points
            if pad.name == "palm" and abs(w) > 0.011 and abs(u) > 0.0275:
                continue  # a palm corner without cells (rows of 5 at |w| > 11.5 mm span |u| <= 27 mm)
            link, point = pad_point(pad.name, u, w, 0.0005)
            normal = pad_normal(pad.name) + rng.normal(scale=0.05, size=3)
            normal /= np.linalg.norm(normal)
            force = rng.uniform(0.5, 3.0) * normal + rng.normal(scale=0.3, size=3)
            rows.append((link, point, normal, force))
            pressing += max(normal @ force, 0.0)
    reading = sensors.loads(contacts(hand, q, rows))
    index = ("F1", "F2", "F3", "palm").index(pad.name)
    assert cell_forces(reading, pad).sum() == pytest.approx(pressing, rel=1e-12)
    assert (np.delete(reading.tactile, index, axis=0) == 0).all()
    assert (reading.tactile[index] > 0).sum() > len(rows) // 3  # patches span several cells


def test_contacts_off_the_pads_read_nothing(hand, sensors) -> None:
    q = hand.neutral()
    press = ([0.0, 1.0, 0.0], [0.0, 5.0, 0.0])
    rows = [
        ("F1_distal_link", [0.03, -0.01, 0.0], *press),  # back of the fingertip
        ("F1_distal_link", [0.0595, 0.001, 0.0], *press),  # beyond the last row
        ("F2_distal_link", [0.03, 0.01, 0.0095], *press),  # beside the columns
        ("F3_proximal_link", [0.03, 0.01, 0.0], *press),  # inner link
        (*pad_point("palm", 0.033, 0.017, 0.0), [0, 0, 1], [0, 0, 5]),  # a palm corner without cells
        ("palm", [0.0, 0.05, 0.09], [0, 0, 1], [0, 0, 5]),  # F3's knuckle housing
    ]
    reading = sensors.loads(contacts(hand, q, rows))
    assert (reading.tactile == 0).all()
    on = [("F1_distal_link", [0.03, 0.01, 0.0], *press), (*pad_point("palm", 0.02, 0.005, 0.0), [0, 0, 1], [0, 0, 5])]
    assert (sensors.loads(contacts(hand, q, on)).tactile.sum(axis=1) > 0).tolist() == [True, False, False, True]


def test_a_contact_between_two_equal_cells_splits_equally(hand, sensors) -> None:
    q = hand.neutral()
    palm = palm_pad()
    # palm row 0 cells 1 and 2 span u = [-16, -6] and [-5, 5] mm: midway at u = -5.5 mm, row centre w = 16.5 mm
    reading = sensors.loads(contacts(hand, q, [(*pad_point("palm", -0.0055, 0.0165, 0.0005), [0, 0, 1], [0, 0, 6])]))
    forces = cell_forces(reading, palm)
    np.testing.assert_allclose(forces[[1, 2]], [3.0, 3.0], rtol=1e-12)
    assert forces.sum() == pytest.approx(6.0, rel=1e-12)
    # fingertip rows 0 and 1 span x = [19.5, 25] and [25.5, 31] mm: midway at x = 25.25 mm, on the middle column
    finger = finger_pad("F3")
    reading = sensors.loads(contacts(hand, q, [(*pad_point("F3", 0.02525, 0.0, 0.0105), [0, 1, 0], [0, 4, 0])]))
    forces = cell_forces(reading, finger)
    np.testing.assert_allclose(forces[0:3], forces[3:6], rtol=1e-12)
    np.testing.assert_allclose(forces[[0, 3]], forces[[2, 5]], rtol=1e-2)  # side columns 4.65 vs 4.7 mm wide
    assert forces[6:].sum() == 0.0 and forces.sum() == pytest.approx(4.0, rel=1e-12)


@pytest.mark.parametrize("pad", [finger_pad("F1"), palm_pad()], ids=lambda p: p.name)
def test_the_centroid_of_the_cell_forces_is_at_the_contact(hand, sensors, pad) -> None:
    rng = np.random.default_rng(11)
    q = hand.neutral()
    pitch = np.array([6.0, 5.2]) * 1e-3 if pad.name != "palm" else np.array([11.0, 11.0]) * 1e-3
    box = (np.array([22e-3, -4e-3]), np.array([46e-3, 4e-3])) if pad.name != "palm" else (-0.02, 0.02)
    index = ("F1", "F2", "F3", "palm").index(pad.name)
    for uw in rng.uniform(*box, size=(20, 2)):
        reading = sensors.loads(
            contacts(hand, q, [(*pad_point(pad.name, *uw, 0.0005), pad_normal(pad.name), 2.0 * pad_normal(pad.name))])
        )
        forces = cell_forces(reading, pad)
        centroid = forces @ pad.centres / forces.sum()
        assert (np.abs(centroid - uw) <= 0.5 * pitch).all(), (uw, centroid)
        assert index == 3 or (forces > 0).sum() >= 2  # a fingertip patch is wider than one cell


def test_pads_lie_on_the_links_faces(hand) -> None:
    """Each fingertip pad lies on the inner face of its distal collision box, facing the way the finger closes; the
    palm pad lies on the top of the palm's cylinder (the URDF's collision geometry, read through Pinocchio)."""
    geometry = hand.collision_model()
    model = hand.model
    q = hand.configuration(F1_proximal=0.8, F2_proximal=0.8, F3_proximal=0.8)
    for finger in FINGERS:
        pad = finger_pad(finger)
        box = next(
            g
            for g in geometry.geometryObjects
            if model.frames[g.parentFrame].name == pad.frame and isinstance(g.geometry, coal.Box)
        )
        centre, half = box.placement.translation, box.geometry.halfSide
        assert (pad.cells[:, 0] >= centre[0] - half[0]).all() and (pad.cells[:5, 1] <= centre[0] + half[0]).all()
        assert (np.abs(pad.cells[:, 2:]) <= half[2]).all()  # within the link's width
        # the pad normal (+y) is the direction the pad's middle moves when the proximal joint closes
        middle = np.array([pad.centres[:, 0].mean(), half[1], 0.0])
        step = np.zeros(hand.nv)
        step[hand.joint_index(f"{finger}_proximal")] = 1e-6
        moved = hand.frame_placement(q + step, pad.frame).act(middle) - hand.frame_placement(q, pad.frame).act(middle)
        normal = hand.frame_placement(q, pad.frame).rotation[:, 1]
        assert moved @ normal / np.linalg.norm(moved) > 0.9
    palm = palm_pad()
    cylinder = next(
        g
        for g in geometry.geometryObjects
        if isinstance(g.geometry, coal.Cylinder) and model.frames[g.parentFrame].name == "palm"
    )
    top = cylinder.placement.translation[2] + cylinder.geometry.halfLength
    surface = model.frames[model.getFrameId("palm_surface")].placement.translation
    assert surface[2] == pytest.approx(top, abs=1e-12)
    corners = palm.cells[:, [[0, 2], [0, 3], [1, 2], [1, 3]]]  # (24, 4, 2)
    assert np.linalg.norm(corners, axis=2).max() < cylinder.geometry.radius


# ------------------------------------------------------------------ a simulated grasp
def test_a_simulated_grasp_of_a_box_lights_the_fingertip_pads() -> None:
    setup = box_grasp(mass=0.3, actuation="barrett")
    simulator, state = setup.simulator, setup.state
    sensors = BarrettSensors(setup.hand)
    for _ in range(500):
        state, _ = simulator.step(state, np.array([0.0, 0.05, 0.05, 0.05]))  # beyond MT: a test of the pads
    reading, loads = sensors.read(state), sensors.loads(state)
    reaction = ContactSensing(setup.hand).reaction_torques(state)
    distal = [setup.hand.joint_index(f"{f}_distal") for f in FINGERS]
    np.testing.assert_allclose(loads.fingertip_torque, reaction[distal], rtol=1e-10, atol=1e-12)
    assert (loads.fingertip_torque < 0).all()  # the box pushes every fingertip open
    np.testing.assert_array_equal(reading.fingertip_torque, strain_counts(loads.fingertip_torque))
    beyond = loads.fingertip_torque < -(4095 - (667 + 3460) / 2) / SG_PER_NM  # past the SG's top count
    np.testing.assert_array_equal(reading.strain_saturated, beyond)
    np.testing.assert_array_equal(reading.tactile_saturated, loads.tactile >= 4095 / 256)  # flagged where beyond
    np.testing.assert_array_equal(reading.tactile, digitise_pressures(loads.tactile))
    normals = np.einsum("ij,ij->i", state.contact_normals, state.contact_forces)
    for f, finger in enumerate(FINGERS):
        link = f"{finger}_distal_link"
        rows = [k for k, (a, _) in enumerate(state.contact_bodies) if a == link]
        placement = setup.hand.frame_placement(state.q, link)
        x, y, z = placement.rotation.T @ (state.contact_points[rows] - placement.translation).T  # link frame
        strip = (x >= 0.01925) & (x <= 0.05775) & (np.abs(z) <= 0.0078) & (y >= 0)  # GraspIt's cells, 0.25 mm margin
        assert strip.any()  # (the box's face may also touch the link's edges, beside the pad)
        total = cell_forces(loads, finger_pad(finger)).sum()
        assert total == pytest.approx(np.maximum(normals[rows][strip], 0).sum(), rel=1e-12) and total > 0.1
        assert (reading.tactile[f] > 0).sum() >= 2
    assert (reading.tactile[3] == 0).all()  # nothing touches the palm
    inner, outer = reading.inner_link_position, reading.outer_link_position
    q = np.asarray(state.q)
    assert np.abs(inner[:3] - q[[setup.hand.joint_index(f"{f}_proximal") for f in FINGERS]]).max() < COUNT / 50
    assert np.abs(outer[:3] - q[distal]).max() < COUNT / 50 + COUNT / 93.75


def test_a_finger_stalled_on_a_block_reads_its_push_within_the_sensors_ranges() -> None:
    """F3 closed by close() onto a fixed block (environment, body a of its pair): at rest the worm's 1 N m holds the
    contact, so the SG reads about 1225 counts over its zero, inside 0..4095, through the driver's update()."""
    hand = bh.BarrettHand()
    block = FixedBox(size=(0.06, 0.03, 0.02), pose=pin.SE3(np.eye(3), np.array([0.0, 0.035, 0.185])), name="block")
    actuation = BarrettActuation(hand, saturate=True)
    simulator = Simulator(Scene(hand, [], environment=[block]), dt=DT, contact=contact_law(), actuation=actuation)
    driver = BarrettDriver(hand)
    driver.script([(0.0, "close", "F3")])
    trajectory = simulator.run(driver, 0.8, progress=False)
    assert {tuple(b) for b in trajectory.contacts_at(len(trajectory) - 1)["bodies"]} == {("block", "F3_distal_link")}
    driver.update()
    counts = driver.fingertip_torque()
    # Newton at rest about the distal axis: the contact's moment is the worm's torque less the tip's weight
    q = trajectory.q[-1]
    worm = WORM_EFFICIENCY * DISTAL_ALONE_RATIO * MAX_MOTOR_TORQUE  # 1 N m
    moment = hand.gravity_torques(q)[7] - worm  # [N m] on the fingertip, opening
    assert abs(strain_torques(counts[2]) - moment) < 2e-3 and 3000 < counts[2] < 4095  # HSG 3000 is "~1 kg"
    assert counts[0] == counts[1] == strain_counts(0.0)  # the idle fingers feel nothing
    pads = driver.tactile()
    assert pads[2].sum() > 0 and not pads[[0, 1, 3]].any()  # the block presses F3's pad alone
    assert pads.max() == 4095 / 256  # a 22 N tip load on a few cells saturates them: reported at full scale, ...
    pressures = driver.readout.sensors.loads(driver.readout.sensed).tactile  # ... where the load is beyond it
    saturated = driver.readout.reading(S_TACT_FULL).tactile_saturated
    assert saturated.any() and (pressures[saturated] > 4095 / 256).all()
    np.testing.assert_array_equal(pads[~saturated], np.rint(pressures[~saturated] * 256) / 256)


# ------------------------------------------------------------------ the reading and its errors
def test_readings_are_frozen_and_bad_inputs_are_named(hand, sensors, allegro) -> None:
    reading = sensors.read(State(0.0, hand.neutral(), np.zeros(hand.nv)))
    assert reading.primary_encoder.shape == (4,) and reading.tactile.shape == (4, 24)
    with pytest.raises(ValueError):
        reading.tactile[0, 0] = 1.0
    with pytest.raises(AttributeError):
        reading.t = 1.0  # type: ignore[misc]
    with pytest.raises(InputError, match=r"`state.q` must have shape \(8,\), got shape \(3,\)"):
        sensors.read(State(0.0, np.zeros(3), np.zeros(3)))
    bad = State(0.0, hand.neutral(), np.zeros(8), contact_points=np.zeros((2, 3)), contact_bodies=(("palm", "b"),))
    with pytest.raises(InputError, match=r"`state.contact_points` must have shape \(1, 3\), got shape \(2, 3\)"):
        sensors.read(bad)
    with pytest.raises(InputError, match="`spread` must exceed 0.0005 m"):
        BarrettSensors(hand, spread=1e-4)
    with pytest.raises(InputError, match="lacks joints"):
        BarrettSensors(allegro)
