"""Rigid objects against independent truths: Monte-Carlo mass properties, coal collision queries, validation."""

from __future__ import annotations

import dataclasses
import math
import re
from collections.abc import Callable

import coal
import numpy as np
import pinocchio as pin
import pytest

from bhgrasp.errors import InputError
from bhgrasp.model.objects import (
    Box,
    Capsule,
    Cylinder,
    FixedBox,
    Plane,
    RigidObject,
    Sphere,
    table,
    wall,
)
from bhgrasp.model.spring_mounted import SpringMounted

SAMPLES = 1_000_000  # Monte-Carlo points per shape: relative standard error of the inertia ~0.1%
NASTY_POSE = pin.SE3(pin.rpy.rpyToMatrix(0.3, -0.7, 1.1), np.array([0.1, -0.2, 0.35]))

# name -> (object, half-extents of its axis-aligned bounding box, "inside" predicate on body-frame points (n, 3)).
# The predicates and boxes are written from the geometric definitions, independently of bhgrasp.model.objects.
SHAPES: dict[str, tuple[RigidObject, np.ndarray, Callable[[np.ndarray], np.ndarray]]] = {
    "sphere": (
        Sphere(0.04, mass=0.3),
        np.full(3, 0.04),
        lambda p: np.einsum("ij,ij->i", p, p) <= 0.04**2,
    ),
    "box": (
        Box((0.06, 0.05, 0.03), mass=0.5),
        np.array([0.03, 0.025, 0.015]),
        lambda p: np.all(np.abs(p) <= [0.03, 0.025, 0.015], axis=1),
    ),
    "cylinder": (
        Cylinder(0.02, 0.09, mass=0.4),
        np.array([0.02, 0.02, 0.045]),
        lambda p: (p[:, 0] ** 2 + p[:, 1] ** 2 <= 0.02**2) & (np.abs(p[:, 2]) <= 0.045),
    ),
    "capsule": (  # distance to the axis segment z in [-L/2, L/2] at most r
        Capsule(0.02, 0.07, mass=0.4),
        np.array([0.02, 0.02, 0.035 + 0.02]),
        lambda p: _segment_distance_squared(p, 0.035) <= 0.02**2,
    ),
    "stubby_capsule": (  # hemispheres dominate: stresses the hemisphere terms of the derivation
        Capsule(0.03, 0.01, mass=0.4),
        np.array([0.03, 0.03, 0.005 + 0.03]),
        lambda p: _segment_distance_squared(p, 0.005) <= 0.03**2,
    ),
}


def _segment_distance_squared(p: np.ndarray, half_length: float) -> np.ndarray:
    closest = np.clip(p[:, 2], -half_length, half_length)
    return p[:, 0] ** 2 + p[:, 1] ** 2 + (p[:, 2] - closest) ** 2


def _support(obj: RigidObject | FixedBox, direction_body: np.ndarray) -> float:
    """Max of direction . x over the shape (body frame, shape centred), from the shape's definition."""
    a = direction_body
    if isinstance(obj, Sphere):
        return obj.radius
    if isinstance(obj, (Box, FixedBox)):
        return float(np.abs(a) @ (np.asarray(obj.size) / 2))
    if isinstance(obj, Cylinder):
        return obj.length / 2 * abs(a[2]) + obj.radius * math.hypot(a[0], a[1])
    if isinstance(obj, Capsule):
        return obj.length / 2 * abs(a[2]) + obj.radius
    raise AssertionError(type(obj))


def _transform(pose: pin.SE3) -> coal.Transform3s:
    return coal.Transform3s(pose.rotation, pose.translation)


def _collides(
    o1: coal.ShapeBase, t1: coal.Transform3s, o2: coal.ShapeBase, t2: coal.Transform3s
) -> coal.CollisionResult:
    request, result = coal.CollisionRequest(), coal.CollisionResult()
    request.enable_contact = True
    coal.collide(o1, t1, o2, t2, request, result)
    return result


def _distance(o1: coal.ShapeBase, t1: coal.Transform3s, o2: coal.ShapeBase, t2: coal.Transform3s) -> float:
    return coal.distance(o1, t1, o2, t2, coal.DistanceRequest(), coal.DistanceResult())


def _at(position: tuple[float, float, float]) -> coal.Transform3s:
    return coal.Transform3s(np.eye(3), np.asarray(position, dtype=float))


# ---------------------------------------------------------------------------------------------- mass properties
@pytest.mark.parametrize("name", list(SHAPES))
def test_volume_and_inertia_match_monte_carlo_integration(name: str) -> None:
    obj, half, inside = SHAPES[name]
    half = 1.1 * half  # sample a slightly larger box so that every boundary of the shape is exercised
    rng = np.random.default_rng(20240607)
    points = rng.uniform(-half, half, size=(SAMPLES, 3))
    box_volume = float(np.prod(2 * half))
    keep = inside(points)
    # Each sample contributes box_volume * 1_inside(p) * f(p); mean = integral, standard error = std / sqrt(N).
    volume_samples = box_volume * keep
    volume_se = volume_samples.std() / math.sqrt(SAMPLES)
    assert abs(volume_samples.mean() - obj.volume) < 5 * volume_se
    assert abs(volume_samples.mean() / obj.volume - 1) < 0.01

    rho = obj.mass / obj.volume  # [kg/m^3]
    p = points * keep[:, None]
    r2 = np.einsum("ij,ij->i", p, p)
    errors = []
    for i in range(3):
        for j in range(3):
            f = rho * box_volume * ((i == j) * r2 - p[:, i] * p[:, j])
            estimate, se = f.mean(), f.std() / math.sqrt(SAMPLES)
            assert abs(estimate - obj.inertia[i, j]) < 5 * se + 1e-15, (i, j, estimate, obj.inertia[i, j], se)
            errors.append(abs(estimate - obj.inertia[i, j]) / obj.inertia.diagonal().max())
    assert max(errors) < 0.01  # 1% of the largest moment: ~5-10 standard errors at this sample count
    assert np.max(np.linalg.norm(points[keep], axis=1)) <= obj.bounding_radius
    assert np.max(np.linalg.norm(points[keep], axis=1)) > 0.9 * obj.bounding_radius


def test_capsule_inertia_reduces_to_sphere_and_tends_to_cylinder() -> None:
    r = 0.03
    np.testing.assert_allclose(Capsule(r, 1e-12, mass=2.0).inertia, Sphere(r, mass=2.0).inertia, rtol=1e-9)
    long_capsule, cylinder = Capsule(r, 100.0, mass=2.0), Cylinder(r, 100.0, mass=2.0)
    np.testing.assert_allclose(long_capsule.inertia, cylinder.inertia, rtol=1e-3)


@pytest.mark.parametrize("name", list(SHAPES))
def test_mass_from_density_and_spatial_inertia(name: str) -> None:
    obj = SHAPES[name][0]
    from_density = dataclasses.replace(obj, mass=None, density=750.0)
    assert from_density.mass == pytest.approx(750.0 * obj.volume, rel=1e-15)
    assert from_density.density == 750.0 and obj.density is None
    spatial = obj.spatial_inertia()
    assert spatial.mass == obj.mass
    np.testing.assert_array_equal(spatial.lever, np.zeros(3))
    np.testing.assert_allclose(spatial.inertia, obj.inertia, rtol=1e-15)


def test_exactly_one_of_mass_and_density() -> None:
    message = re.escape("exactly one of `mass` [kg] and `density` [kg/m^3] must be given, got mass=")
    with pytest.raises(InputError, match=message + r"None, density=None"):
        Sphere(0.1)
    with pytest.raises(InputError, match=message + r"1\.0, density=1000\.0"):
        Sphere(0.1, mass=1.0, density=1000.0)


def test_defaults_copies_and_immutability() -> None:
    velocity, pose = np.arange(6.0), pin.SE3(NASTY_POSE)
    sphere = Sphere(0.05, mass=1.0, pose=pose, velocity=velocity, name="ball")
    velocity[0], pose.translation = 99.0, np.zeros(3)
    np.testing.assert_array_equal(sphere.velocity, np.arange(6.0))
    assert sphere.pose.isApprox(NASTY_POSE)
    assert not sphere.velocity.flags.writeable
    with pytest.raises(dataclasses.FrozenInstanceError):
        sphere.radius = 1.0  # type: ignore[misc]
    default = Box((0.1, 0.1, 0.1), mass=1.0)
    assert default.pose.isIdentity() and default.friction == 0.8 and default.name is None
    np.testing.assert_array_equal(default.velocity, np.zeros(6))
    assert default.geometry() is not default.geometry()
    assert repr(sphere) == "Sphere(name='ball', radius=0.05, mass=1, position=[0.1, -0.2, 0.35])"
    with pytest.raises(TypeError, match="abstract"):
        RigidObject(mass=1.0)  # type: ignore[abstract]


# ---------------------------------------------------------------------------------------------- coal geometry
@pytest.mark.parametrize("name", list(SHAPES))
@pytest.mark.parametrize(
    "direction",
    [(1, 0, 0), (-1, 0, 0), (0, 1, 0), (0, -1, 0), (0, 0, 1), (0, 0, -1), (0.3, -0.5, 0.8)],
)
@pytest.mark.parametrize("pose", [pin.SE3.Identity(), NASTY_POSE], ids=["identity", "rotated"])
def test_coal_geometry_has_the_documented_extent(name: str, direction: tuple, pose: pin.SE3) -> None:
    """A half-space below the shape's lowest point along `direction` touches it exactly where the closed form says."""
    obj = dataclasses.replace(SHAPES[name][0], pose=pose)
    u = np.asarray(direction, dtype=float) / np.linalg.norm(direction)
    lowest = u @ pose.translation - _support(obj, -pose.rotation.T @ u)  # min of u . x over the shape
    geometry, placement = obj.geometry(), _transform(pose)
    eps = 1e-9
    assert _collides(geometry, placement, coal.Halfspace(u, lowest + eps), coal.Transform3s()).isCollision()
    assert not _collides(geometry, placement, coal.Halfspace(u, lowest - eps), coal.Transform3s()).isCollision()
    assert _distance(geometry, placement, coal.Halfspace(u, lowest - 1e-3), coal.Transform3s()) == pytest.approx(
        1e-3, abs=1e-9
    )


@pytest.mark.parametrize("pose", [pin.SE3.Identity(), NASTY_POSE], ids=["identity", "rotated"])
def test_fixed_box_geometry_and_placement(pose: pin.SE3) -> None:
    fixed = FixedBox((0.8, 0.6, 0.04), pose=pose, friction=0.5, name="top")
    assert fixed.placement.isApprox(pose) and fixed.placement is not fixed.pose
    for u in np.eye(3):
        lowest = u @ pose.translation - _support(fixed, -pose.rotation.T @ u)
        placement = _transform(fixed.placement)
        assert _collides(
            fixed.geometry(), placement, coal.Halfspace(u, lowest + 1e-9), coal.Transform3s()
        ).isCollision()
        assert not _collides(
            fixed.geometry(), placement, coal.Halfspace(u, lowest - 1e-9), coal.Transform3s()
        ).isCollision()


def test_plane_convention_and_contact_signs() -> None:
    """Coal 3.0.3: Halfspace(n, d) is solid where n.x <= d; penetration_depth < 0 in contact; normal o1 -> o2."""
    ground = Plane()
    np.testing.assert_array_equal(ground.normal, [0.0, 0.0, 1.0])
    assert ground.offset == 0.0 and ground.placement.isIdentity()
    ball, above = coal.Sphere(0.01), _at((0.0, 0.0, 0.005))
    result = _collides(ball, above, ground.geometry(), _transform(ground.placement))
    assert result.isCollision()
    contact = result.getContact(0)
    assert contact.penetration_depth == pytest.approx(-0.005, abs=1e-12)
    np.testing.assert_allclose(contact.normal, [0.0, 0.0, -1.0], atol=1e-12)  # from the sphere into the plane
    swapped = _collides(ground.geometry(), _transform(ground.placement), ball, above).getContact(0)
    np.testing.assert_allclose(swapped.normal, [0.0, 0.0, 1.0], atol=1e-12)  # from the plane into the sphere
    assert not _collides(ball, _at((0.0, 0.0, 0.0101)), ground.geometry(), coal.Transform3s()).isCollision()
    assert _collides(ball, _at((0.0, 0.0, -1.0)), ground.geometry(), coal.Transform3s()).isCollision()  # solid


def test_plane_normalises_its_normal() -> None:
    plane = Plane(normal=(0.0, 3.0, 4.0), offset=0.2, friction=0.0, name="slope")
    np.testing.assert_allclose(plane.normal, [0.0, 0.6, 0.8], rtol=1e-15)
    assert plane.friction == 0.0 and plane.name == "slope" and not plane.normal.flags.writeable


def test_table_is_a_horizontal_plane_at_its_height() -> None:
    top = table(0.3, friction=0.4)
    np.testing.assert_array_equal(top.normal, [0.0, 0.0, 1.0])
    assert (top.offset, top.friction, top.name) == (0.3, 0.4, "table")
    touching = _collides(coal.Sphere(0.01), _at((0.2, 0.1, 0.305)), top.geometry(), coal.Transform3s())
    assert touching.getContact(0).penetration_depth == pytest.approx(-0.005, abs=1e-12)
    assert not _collides(coal.Sphere(0.01), _at((0.2, 0.1, 0.311)), top.geometry(), coal.Transform3s()).isCollision()


def test_wall_passes_through_its_point_with_the_solid_behind() -> None:
    side = wall(point=(0.5, 0.2, 0.1), normal=(-2.0, 0.0, 0.0), friction=0.3)
    np.testing.assert_array_equal(side.normal, [-1.0, 0.0, 0.0])
    assert side.offset == pytest.approx(-0.5) and side.friction == 0.3 and side.name == "wall"
    touching = _collides(coal.Sphere(0.01), _at((0.495, 0.0, 0.0)), side.geometry(), coal.Transform3s())
    assert touching.getContact(0).penetration_depth == pytest.approx(-0.005, abs=1e-12)
    assert not _collides(coal.Sphere(0.01), _at((0.489, 0.0, 0.0)), side.geometry(), coal.Transform3s()).isCollision()
    assert _collides(coal.Sphere(0.01), _at((0.7, 0.0, 0.0)), side.geometry(), coal.Transform3s()).isCollision()


# ---------------------------------------------------------------------------------------------- spring-mounted body
def test_spring_mounted_validates_and_delegates() -> None:
    body = Box((0.1, 0.1, 0.05), density=500.0, pose=NASTY_POSE, friction=0.6, name="plate")
    mounted = SpringMounted(body, direction=(0.0, 0.0, -2.0), stiffness=400.0, damping=2.0)
    np.testing.assert_array_equal(mounted.direction, [0.0, 0.0, -1.0])
    assert (mounted.stiffness, mounted.damping, mounted.name) == (400.0, 2.0, "plate")
    assert mounted.mass == body.mass == pytest.approx(0.25)
    assert mounted.friction == 0.6 and mounted.pose.isApprox(NASTY_POSE)
    assert isinstance(mounted.geometry(), coal.Box)
    np.testing.assert_array_equal(mounted.geometry().halfSide, [0.05, 0.05, 0.025])
    assert mounted.natural_frequency == pytest.approx(math.sqrt(400.0 / 0.25))
    assert SpringMounted(body, (1, 0, 0), 1.0, name="other").name == "other"
    assert SpringMounted(body, (1, 0, 0), 1.0).damping == 0.0


# ---------------------------------------------------------------------------------------------- invalid input
BAD_POSE = pin.SE3(np.eye(3), np.array([0.0, np.nan, 0.0]))
INVALID: list[tuple[Callable[[], object], str]] = [
    (lambda: Sphere(-0.01, mass=1.0), "`radius` must be a positive finite number, got -0.01"),
    (lambda: Sphere(0.0, mass=1.0), "`radius` must be a positive finite number, got 0.0"),
    (lambda: Sphere(math.nan, mass=1.0), "`radius` must be a positive finite number, got nan"),
    (lambda: Sphere("big", mass=1.0), "`radius` must be a positive number, got 'big'"),
    (lambda: Cylinder(0.1, -1.0, mass=1.0), "`length` must be a positive finite number, got -1.0"),
    (lambda: Cylinder(math.inf, 1.0, mass=1.0), "`radius` must be a positive finite number, got inf"),
    (lambda: Capsule(0.1, math.inf, mass=1.0), "`length` must be a positive finite number, got inf"),
    (lambda: Capsule(0.0, 0.1, mass=1.0), "`radius` must be a positive finite number, got 0.0"),
    (lambda: Box((0.1, 0.2), mass=1.0), "`size` must have shape (3,), got shape (2,)"),
    (lambda: Box((0.1, -0.2, 0.3), mass=1.0), "`size` must hold 3 positive edge lengths [m], got [0.1, -0.2, 0.3]"),
    (lambda: Box((0.1, math.nan, 0.3), mass=1.0), "`size` must be finite"),
    (lambda: Box("abc", mass=1.0), "`size` must be a numeric array, got 'abc'"),
    (lambda: Sphere(0.1, mass=-1.0), "`mass` must be a positive finite number, got -1.0"),
    (lambda: Sphere(0.1, mass=math.nan), "`mass` must be a positive finite number, got nan"),
    (lambda: Sphere(0.1, density=0.0), "`density` must be a positive finite number, got 0.0"),
    (lambda: Sphere(0.1, density=math.inf), "`density` must be a positive finite number, got inf"),
    (lambda: Sphere(0.1, mass=1.0, friction=-0.1), "`friction` must be a finite number >= 0, got -0.1"),
    (lambda: Sphere(0.1, mass=1.0, friction=math.nan), "`friction` must be a finite number >= 0, got nan"),
    (lambda: Sphere(0.1, mass=1.0, friction=None), "`friction` must be a finite number >= 0, got None"),
    (
        lambda: Sphere(0.1, mass=1.0, pose=np.eye(4)),
        "`pose` must be a pinocchio.SE3 (pin.SE3(rotation, translation)), got ndarray",
    ),
    (lambda: Sphere(0.1, mass=1.0, pose=BAD_POSE), "`pose` must be finite"),
    (lambda: Sphere(0.1, mass=1.0, velocity=np.zeros(3)), "`velocity` must have shape (6,), got shape (3,)"),
    (lambda: Sphere(0.1, mass=1.0, velocity=[0, 0, 0, 0, 0, math.inf]), "`velocity` must be finite"),
    (lambda: Plane(normal=(0.0, 0.0, 0.0)), "`normal` must be a non-zero 3-vector, got [0.0, 0.0, 0.0]"),
    (lambda: Plane(normal=(0.0, 1.0)), "`normal` must have shape (3,), got shape (2,)"),
    (lambda: Plane(offset=math.nan), "`offset` must be a finite number, got nan"),
    (lambda: Plane(friction=-1.0), "`friction` must be a finite number >= 0, got -1.0"),
    (lambda: FixedBox((1.0, 0.0, 1.0)), "`size` must hold 3 positive edge lengths [m], got [1.0, 0.0, 1.0]"),
    (lambda: FixedBox((1.0, 1.0, 1.0), pose=(0, 0, 0)), "`pose` must be a pinocchio.SE3"),
    (lambda: FixedBox((1.0, 1.0, 1.0), friction=math.inf), "`friction` must be a finite number >= 0, got inf"),
    (lambda: table(math.nan), "`height` must be a finite number, got nan"),
    (lambda: table(0.0, friction=-0.5), "`friction` must be a finite number >= 0, got -0.5"),
    (lambda: wall((0.0, 0.0), (1.0, 0.0, 0.0)), "`point` must have shape (3,), got shape (2,)"),
    (lambda: wall((0.0, 0.0, 0.0), (0.0, 0.0, 0.0)), "`normal` must be a non-zero 3-vector"),
    (lambda: SpringMounted("box", (0, 0, 1), 1.0), "`body` must be a RigidObject (Sphere, Box, ...), got str"),
    (lambda: SpringMounted(Sphere(0.1, mass=1.0), (0, 0, 0), 1.0), "`direction` must be a non-zero 3-vector"),
    (lambda: SpringMounted(Sphere(0.1, mass=1.0), (0, 0, 1, 0), 1.0), "`direction` must have shape (3,)"),
    (lambda: SpringMounted(Sphere(0.1, mass=1.0), (0, 0, 1), 0.0), "`stiffness` must be a positive finite number"),
    (lambda: SpringMounted(Sphere(0.1, mass=1.0), (0, 0, 1), math.nan), "`stiffness` must be a positive finite"),
    (
        lambda: SpringMounted(Sphere(0.1, mass=1.0), (0, 0, 1), 1.0, damping=-2.0),
        "`damping` must be a finite number >= 0, got -2.0",
    ),
]


@pytest.mark.parametrize(("build", "message"), INVALID, ids=[message[:40] for _, message in INVALID])
def test_invalid_input_raises_input_error_naming_the_argument(build: Callable[[], object], message: str) -> None:
    with pytest.raises(InputError, match="^" + re.escape(message)):
        build()
