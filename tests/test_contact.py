"""Contact detection against analytic geometry, and the force law's defining properties."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import bhgrasp as bh
from bhgrasp.model.objects import Box, Sphere, table
from bhgrasp.sim.contact import ContactEngine
from bhgrasp.sim.contact_law import SpringDamper
from bhgrasp.sim.scene import Scene

FAR = pin.SE3(np.eye(3), np.array([5.0, 0.0, 0.3]))


def engine_for(item, law: SpringDamper | None = None) -> tuple[ContactEngine, Scene]:
    scene = Scene(bh.BarrettHand(base_placement=FAR), [item], [table()])
    return ContactEngine(scene, law or SpringDamper()), scene


def test_sphere_on_plane_geometry() -> None:
    engine, scene = engine_for(Sphere(radius=0.02, mass=0.1, pose=pin.SE3(np.eye(3), np.array([0.1, 0.2, 0.0185]))))
    q, _ = scene.initial_state()
    contacts = engine.detect(q)
    assert len(contacts) == 1
    np.testing.assert_allclose(contacts.normal[0], [0, 0, 1], atol=1e-12)  # from the table (a) to the sphere (b)
    assert contacts.depth[0] == pytest.approx(0.0015, abs=1e-12)
    np.testing.assert_allclose(contacts.point[0], [0.1, 0.2, -0.00075], atol=1e-12)  # midway between surfaces
    record = contacts.records(scene)[0]
    assert (record.body_a, record.body_b) == ("table", "object0")
    np.testing.assert_allclose(record.point_a, [0.1, 0.2, 0.0], atol=1e-12)  # the table's surface
    np.testing.assert_allclose(record.point_b, [0.1, 0.2, -0.0015], atol=1e-12)  # the sphere's lowest point


def test_tilted_box_gets_each_corners_own_depth() -> None:
    """Coal's patch gives every point the deepest depth; bhgrasp measures each corner (analytic truth here)."""
    rotation, centre = pin.rpy.rpyToMatrix(0.0, 0.01, 0.0), np.array([0.0, 0.0, 0.0246])
    engine, scene = engine_for(Box(size=(0.06, 0.05, 0.05), mass=0.2, pose=pin.SE3(rotation, centre)))
    contacts = engine.detect(scene.initial_state()[0])
    corners = np.array([[x, y, -0.025] for x in (-0.03, 0.03) for y in (-0.025, 0.025)]) @ rotation.T + centre
    expected = sorted(-corners[:, 2])
    assert len(contacts) == 4
    # Signed distances are perpendicular to the tilted face, not along the plane normal: O(tilt^2) = 5e-5 relative.
    np.testing.assert_allclose(sorted(contacts.depth), expected, rtol=2e-4)
    np.testing.assert_allclose(contacts.weight, 0.25)


@pytest.mark.parametrize("shape", ["box", "sphere", "halfspace", "capsule"])
def test_signed_distances_agree_with_coal(shape: str) -> None:
    """The closed-form signed distances used for patch depths equal coal's GJK/EPA (inside and outside)."""
    import coal

    from bhgrasp.model.objects import Capsule

    items = {
        "box": Box(
            size=(0.06, 0.05, 0.04), mass=0.2, pose=pin.SE3(pin.rpy.rpyToMatrix(0.3, -0.2, 1.0), np.ones(3) * 0.1)
        ),
        "sphere": Sphere(radius=0.03, mass=0.1, pose=pin.SE3(np.eye(3), np.array([0.1, 0.0, 0.05]))),
        "capsule": Capsule(
            radius=0.02, length=0.05, mass=0.1, pose=pin.SE3(pin.rpy.rpyToMatrix(0.5, 0.1, 0), np.zeros(3))
        ),
    }
    engine, scene = engine_for(items.get(shape, items["sphere"]))
    q = scene.initial_state()[0]
    pin.updateGeometryPlacements(scene.model, scene.data, scene.geometry, engine.geometry_data, q)
    geom = scene.environment_geometries[0] if shape == "halfspace" else scene.object_geometries[0]
    points = np.random.default_rng(1).uniform(-0.08, 0.2, size=(200, 3))
    placement = engine.geometry_data.oMg[geom]
    transform = coal.Transform3s(placement.rotation, placement.translation)
    probe, result = coal.Sphere(1e-12), coal.DistanceResult()
    expected = []
    for point in points:
        result.clear()
        expected.append(
            coal.distance(
                probe,
                coal.Transform3s(np.eye(3), point),
                scene.geometry.geometryObjects[geom].geometry,
                transform,
                coal.DistanceRequest(),
                result,
            )
        )
    np.testing.assert_allclose(engine._signed_distance(geom, points), expected, atol=1e-9)


def test_cylinder_signed_distances_meet_a_second_method() -> None:
    """Inside a cylinder the nearest surface point may be on a flat end, where coal's EPA reads the side wall (the
    bug: a can standing on its pedestal read a 21.7 mm overlap at 9 um).  Truth: outside, coal's GJK; inside, the
    nearest of 200k points spread over the side and both ends (brute force, 0.2 mm grid: within 0.1 mm)."""
    import coal

    radius, half = 0.033, 0.05
    can = bh.Cylinder(
        radius=radius,
        length=2 * half,
        mass=0.3,
        pose=pin.SE3(pin.rpy.rpyToMatrix(0.3, -0.2, 1.0), np.array([0.1, 0.0, 0.05])),
    )
    engine, scene = engine_for(can)
    pin.updateGeometryPlacements(
        scene.model, scene.data, scene.geometry, engine.geometry_data, scene.initial_state()[0]
    )
    geom = scene.object_geometries[0]
    placement = engine.geometry_data.oMg[geom]
    local = np.random.default_rng(2).uniform([-0.05, -0.05, -0.07], [0.05, 0.05, 0.07], size=(400, 3))
    points = local @ placement.rotation.T + placement.translation
    computed = engine._signed_distance(geom, points)
    inside = (np.hypot(local[:, 0], local[:, 1]) < radius) & (np.abs(local[:, 2]) < half)
    angle, height = np.meshgrid(np.linspace(0.0, 2 * np.pi, 1036, endpoint=False), np.linspace(-half, half, 501))
    side = np.column_stack((radius * np.cos(angle).ravel(), radius * np.sin(angle).ravel(), height.ravel()))
    grid = np.linspace(-radius, radius, 331)
    disc = np.array([(x, y) for x in grid for y in grid if x * x + y * y <= radius * radius])
    ends = np.vstack([np.column_stack((disc, np.full(len(disc), z))) for z in (-half, half)])
    surface = np.vstack((side, ends))
    for point, value in zip(local[inside], computed[inside]):
        nearest = np.sqrt(((surface - point) ** 2).sum(axis=1)).min()
        assert value == pytest.approx(-nearest, abs=1e-4)
    probe, request, result = coal.Sphere(1e-12), coal.DistanceRequest(), coal.DistanceResult()
    transform = coal.Transform3s(placement.rotation, placement.translation)
    shape = scene.geometry.geometryObjects[geom].geometry
    outside = [
        coal.distance(probe, coal.Transform3s(np.eye(3), p), shape, transform, request, result) for p in points[~inside]
    ]
    np.testing.assert_allclose(computed[~inside], outside, atol=1e-9)
    assert inside.sum() > 50 and (~inside).sum() > 50


@pytest.mark.parametrize("engine", ["python", "compiled"])
@pytest.mark.parametrize("radius", [0.033, 0.05])
def test_a_can_rests_on_its_pedestal(engine: str, radius: float) -> None:
    """A 0.3 kg can on a pedestal 40 % of its width: after 0.3 s the four patch points carry m g (Newton) and it sank
    m g / k (the spring law's closed form); before, its face patch read the side wall's depth: 4 x 33 N threw the
    33 mm can off at the second step, and the 50 mm can diverged."""
    from bhgrasp.model.objects import FixedBox
    from bhgrasp.sim import Simulator

    mass, stiffness = 0.3, 1e4
    can = bh.Cylinder(
        radius=radius, length=0.1, mass=mass, friction=0.8, pose=pin.SE3(np.eye(3), np.array([0, 0, 0.2]))
    )
    pedestal = FixedBox(size=(0.8 * radius, 0.8 * radius, 0.02), pose=pin.SE3(np.eye(3), np.array([0.0, 0.0, 0.14])))
    law = SpringDamper(stiffness=stiffness, damping=2e-3 * stiffness, friction=0.8)
    simulator = Simulator(Scene(bh.BarrettHand(), [can], environment=[pedestal]), contact=law, engine=engine)
    state = simulator.initial_state()
    for _ in range(300):
        state, _ = simulator.step(state, np.zeros(8))
    assert len(state.contact_bodies) == 4
    np.testing.assert_allclose(state.contact_forces.sum(axis=0), [0.0, 0.0, mass * 9.81], atol=1e-6)  # [N]
    sank = 0.2 - state.object_poses[0].translation[2]
    assert sank == pytest.approx(mass * 9.81 / stiffness, rel=1e-3)  # [m]


def _one_contact(depth: float = 1e-3, displacement=(0.0, 0.0, 0.0), friction: float = 0.5):
    engine, scene = engine_for(Sphere(radius=0.02, mass=0.1, pose=pin.SE3(np.eye(3), np.array([0, 0, 0.02 - depth]))))
    contacts = engine.detect(scene.initial_state()[0])
    contacts.displacement = np.array([displacement], dtype=float)
    contacts.friction = np.array([friction])
    return engine, contacts


def test_normal_force_never_pulls() -> None:
    engine, contacts = _one_contact(depth=1e-4)
    forces, _, _ = engine.forces(contacts, np.array([[0.0, 0.0, 1.0]]))  # separating at 1 m/s: k d - c v < 0
    np.testing.assert_array_equal(forces, 0.0)
    forces, _, _ = engine.forces(contacts, np.array([[0.0, 0.0, -0.01]]))  # approaching: k d + c v
    assert forces[0, 2] == pytest.approx(1e4 * 1e-4 + 20.0 * 0.01)


def test_stick_spring_holds_without_velocity_and_slides_on_the_cone() -> None:
    engine, contacts = _one_contact(depth=1e-3, displacement=(2e-5, 0.0, 0.0), friction=0.5)
    forces, sticking, displacement = engine.forces(contacts, np.zeros((1, 3)))
    np.testing.assert_allclose(forces[0], [-1e4 * 2e-5, 0.0, 10.0])  # f_t = -k_t u with zero velocity: static
    assert sticking[0]
    engine, contacts = _one_contact(depth=1e-3, displacement=(1e-3, 0.0, 0.0), friction=0.5)
    forces, sticking, displacement = engine.forces(contacts, np.zeros((1, 3)))
    np.testing.assert_allclose(forces[0], [-5.0, 0.0, 10.0])  # capped at mu f_n = 0.5 * 10 N
    assert not sticking[0]
    np.testing.assert_allclose(displacement[0], [5.0 / 1e4, 0.0, 0.0])  # anchor follows: k_t |u| = mu f_n


def test_tanh_friction_needs_slip_velocity() -> None:
    law = SpringDamper(friction_law="tanh", slip_velocity=1e-3)
    engine, scene = engine_for(Sphere(radius=0.02, mass=0.1, pose=pin.SE3(np.eye(3), np.array([0, 0, 0.019]))), law)
    contacts = engine.detect(scene.initial_state()[0])
    still, _, _ = engine.forces(contacts, np.zeros((1, 3)))
    assert still[0, 0] == 0.0  # no slip, no friction: a regularised law cannot hold a load at rest
    sliding, _, _ = engine.forces(contacts, np.array([[0.1, 0.0, 0.0]]))
    assert sliding[0, 0] == pytest.approx(-0.8 * 10.0 * np.tanh(100.0))


def test_hunt_crossley_normal_force() -> None:
    law = SpringDamper(stiffness=1e6, damping=100.0, normal_law="hunt-crossley", exponent=1.5)
    engine, scene = engine_for(Sphere(radius=0.02, mass=0.1, pose=pin.SE3(np.eye(3), np.array([0, 0, 0.019]))), law)
    contacts = engine.detect(scene.initial_state()[0])
    forces, _, _ = engine.forces(contacts, np.array([[0.0, 0.0, -0.05]]))
    assert forces[0, 2] == pytest.approx(1e-3**1.5 * (1e6 + 100.0 * 0.05))


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"stiffness": 0.0}, "`stiffness` must be a positive finite number"),
        ({"damping": -1.0}, "`damping` must be a finite number >= 0, got -1.0"),
        ({"friction": float("nan")}, "`friction` must be a finite number >= 0"),
        ({"normal_law": "hertz"}, "`normal_law` must be 'linear' or 'hunt-crossley', got 'hertz'"),
        ({"friction_law": "viscous"}, "`friction_law` must be 'stick-slip' or 'tanh'"),
    ],
)
def test_bad_contact_law(kwargs: dict, message: str) -> None:
    with pytest.raises(bh.InputError, match=message):
        SpringDamper(**kwargs)


def test_scene_pairs_and_names() -> None:
    hand = bh.BarrettHand()
    scene = Scene(hand, [Sphere(radius=0.02, mass=0.1, name="ball"), Box(size=(0.02,) * 3, mass=0.1)], [table()])
    hand_links = scene.hand_geometries
    moving = [g for g in hand_links if scene.geometry.geometryObjects[g].parentJoint != 0]  # not the fixed palm
    # hand x objects, objects x table, object x object, then the table x the moving links
    assert len(scene.pairs) == 2 * len(hand_links) + 2 + 1 + len(moving)
    assert [(p.body_a, p.friction_b) for p in scene.pairs[-len(moving) :]] == [("table", None)] * len(moving)
    assert scene.pairs[-1].friction(0.5) == min(0.5, table().friction)  # the table's and the pad's coefficients
    fixed_only = Scene(hand, [Sphere(radius=0.02, mass=0.1)], [table()], environment_touches_hand=False)
    assert len(fixed_only.pairs) == len(hand_links) + 1
    assert scene.object_names == ["ball", "object1"]
    with pytest.raises(bh.InputError, match="object names must be unique"):
        Scene(hand, [Sphere(radius=0.02, mass=0.1, name="a"), Sphere(radius=0.02, mass=0.1, name="a")])
    with pytest.raises(bh.InputError, match=r"`objects\[0\]` must be a RigidObject or SpringMounted, got str"):
        Scene(hand, ["ball"])
