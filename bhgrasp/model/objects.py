"""Rigid objects and fixed environment shapes: what a body is (shape, mass, inertia, pose, friction).

Conventions: SI units ([m], [kg], [kg m^2], [N/m], [N s/m]).  Each object's body frame sits at its centre of
mass, aligned with the axes of the shape (the cylinder and capsule axes are the body z axis); the shape is
centred on it.  ``pose`` is ``transform_body_to_world``; ``velocity`` is the spatial velocity (linear, angular)
of the COM in world-aligned coordinates.  Coal conventions (coal 3.0.3, checked in tests/test_objects.py):
``coal.Cylinder(r, L)`` has full height ``L``; ``coal.Capsule(r, L)`` has a cylindrical part of length ``L``
(total length ``L + 2 r``); ``coal.Halfspace(n, d)`` is the solid ``{x : n.x <= d}``.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from dataclasses import dataclass, field, fields
from typing import Any

import coal
import numpy as np
import pinocchio as pin

from bhgrasp._validation import as_positive, as_real, as_unit, as_vector, require_rotation
from bhgrasp.errors import InputError

__all__ = ["Box", "Capsule", "Cylinder", "FixedBox", "Plane", "RigidObject", "Sphere", "table", "wall"]

_COMMON = ("mass", "density", "pose", "velocity", "friction", "name")


def _as_pose(value: Any, name: str = "pose") -> pin.SE3:
    if not isinstance(value, pin.SE3):
        raise InputError(
            f"`{name}` must be a pinocchio.SE3 (pin.SE3(rotation, translation)), got {type(value).__name__}"
        )
    if not (np.all(np.isfinite(value.rotation)) and np.all(np.isfinite(value.translation))):
        raise InputError(f"`{name}` must be finite, got {value!r}")
    require_rotation(value.rotation, name)
    return pin.SE3(value)  # a copy: SE3 is mutable


def frozen_array(array: np.ndarray, dtype: type = np.float64) -> np.ndarray:
    """A read-only copy of ``array`` as ``dtype``."""
    array = np.array(array, dtype=dtype)  # always a copy
    array.setflags(write=False)
    return array


@dataclass(frozen=True, eq=False, repr=False, kw_only=True)
class RigidObject(ABC):
    """A free rigid body: a primitive shape with mass, inertia, initial pose and velocity, friction.

    Not instantiated directly: use :class:`Sphere`, :class:`Box`, :class:`Cylinder` or :class:`Capsule`.
    Exactly one of ``mass`` and ``density`` is given; afterwards ``mass`` holds the resolved mass (so a copy
    made with ``dataclasses.replace`` of a density-defined object needs ``mass=None``).

    Attributes:
        mass: Mass [kg].
        density: Density [kg/m^3], or ``None`` if the mass was given.
        pose: ``transform_body_to_world`` of the COM frame.
        velocity: Initial spatial velocity of the COM, (linear [m/s], angular [rad/s]), world-aligned, (6,).
        friction: Coulomb friction coefficient (>= 0).
        name: Display name.
    """

    mass: float | None = None
    density: float | None = None
    pose: pin.SE3 = field(default_factory=pin.SE3.Identity)
    velocity: np.ndarray = field(default_factory=lambda: np.zeros(6))
    friction: float = 0.8
    name: str | None = None

    def __post_init__(self) -> None:
        for name in self._shape_fields():  # radius, length: positive scalars; size: 3 positive edge lengths
            value = getattr(self, name)
            object.__setattr__(self, name, _as_size(value) if name == "size" else as_positive(value, name))
        if (self.mass is None) == (self.density is None):
            raise InputError(
                f"exactly one of `mass` [kg] and `density` [kg/m^3] must be given, "
                f"got mass={self.mass!r}, density={self.density!r}"
            )
        if self.density is not None:
            object.__setattr__(self, "density", as_positive(self.density, "density"))
            object.__setattr__(self, "mass", self.density * self.volume)
        else:
            object.__setattr__(self, "mass", as_positive(self.mass, "mass"))
        object.__setattr__(self, "pose", _as_pose(self.pose))
        object.__setattr__(self, "velocity", frozen_array(as_vector(self.velocity, "velocity", 6)))
        object.__setattr__(self, "friction", as_real(self.friction, "friction"))

    @property
    def volume(self) -> float:
        """Volume [m^3]."""
        return self._mass_properties()[0]

    @property
    def inertia(self) -> np.ndarray:
        """Rotational inertia about the COM in the body frame, (3, 3) [kg m^2] (a fresh array)."""
        return np.diag(self.mass * self._mass_properties()[1])

    @property
    def bounding_radius(self) -> float:
        """Radius [m] of the smallest sphere centred on the COM that contains the shape."""
        return self._mass_properties()[2]

    def spatial_inertia(self) -> pin.Inertia:
        """The body's spatial inertia expressed in its COM frame."""
        return pin.Inertia(self.mass, np.zeros(3), self.inertia)

    @abstractmethod
    def geometry(self) -> coal.ShapeBase:
        """A new coal shape centred on the body frame."""

    def collision_shapes(self) -> list[coal.CollisionGeometry]:
        """The shapes the simulator collides, in the body frame: :meth:`geometry` (a decomposed mesh has several)."""
        return [self.geometry()]

    @abstractmethod
    def _mass_properties(self) -> tuple[float, np.ndarray, float]:
        """Volume [m^3], principal inertia per unit mass (3,) [m^2] (body axes), bounding radius [m]."""

    def _shape_fields(self) -> list[str]:
        return [f.name for f in fields(self) if f.name not in _COMMON]

    def __repr__(self) -> str:
        shape = [f"{name}={np.round(getattr(self, name), 6).tolist()}" for name in self._shape_fields()]
        label = "" if self.name is None else f"name={self.name!r}, "
        position = np.round(self.pose.translation, 6).tolist()
        return f"{type(self).__name__}({label}{', '.join(shape)}, mass={self.mass:.6g}, position={position})"


@dataclass(frozen=True, eq=False, repr=False)
class Sphere(RigidObject):
    """A solid sphere of ``radius`` [m]; I = 2/5 m r²."""

    radius: float

    def geometry(self) -> coal.Sphere:
        """A new ``coal.Sphere(radius)``."""
        return coal.Sphere(self.radius)

    def _mass_properties(self) -> tuple[float, np.ndarray, float]:
        r = self.radius
        return 4.0 / 3.0 * math.pi * r**3, np.full(3, 0.4 * r**2), r


@dataclass(frozen=True, eq=False, repr=False)
class Box(RigidObject):
    """A solid box of full edge lengths ``size`` = (x, y, z) [m]; I = m/12 diag(y²+z², x²+z², x²+y²)."""

    size: np.ndarray

    def geometry(self) -> coal.Box:
        """A new ``coal.Box(x, y, z)`` (full edge lengths)."""
        return coal.Box(*self.size)

    def _mass_properties(self) -> tuple[float, np.ndarray, float]:
        x2, y2, z2 = self.size**2
        return float(np.prod(self.size)), np.array([y2 + z2, x2 + z2, x2 + y2]) / 12.0, 0.5 * math.sqrt(x2 + y2 + z2)


@dataclass(frozen=True, eq=False, repr=False)
class Cylinder(RigidObject):
    """A solid cylinder of ``radius`` r [m], full ``length`` L [m] along body z; I_zz = m r²/2, I_xx = m (3r²+L²)/12."""

    radius: float
    length: float

    def geometry(self) -> coal.Cylinder:
        """A new ``coal.Cylinder(radius, length)`` (``length`` is the full height)."""
        return coal.Cylinder(self.radius, self.length)

    def _mass_properties(self) -> tuple[float, np.ndarray, float]:
        r, length = self.radius, self.length
        i_xx = (3 * r**2 + length**2) / 12
        return math.pi * r**2 * length, np.array([i_xx, i_xx, r**2 / 2]), math.hypot(r, length / 2)


@dataclass(frozen=True, eq=False, repr=False)
class Capsule(RigidObject):
    """A cylinder of ``radius`` r [m] and ``length`` L [m] along body z capped by two hemispheres (z in ±(L/2 + r))."""

    radius: float
    length: float

    def geometry(self) -> coal.Capsule:
        """A new ``coal.Capsule(radius, length)`` (``length`` of the cylindrical part)."""
        return coal.Capsule(self.radius, self.length)

    def _mass_properties(self) -> tuple[float, np.ndarray, float]:
        # Per unit mass, split by volume: cylinder m_c = pi r² L / V, each hemisphere m_h = (2/3) pi r³ / V.
        # Cylinder about the centre: I_xx = m_c (3r² + L²)/12, I_zz = m_c r²/2.
        # Hemisphere about the centre of its flat face (= centre of its sphere): half a sphere's inertia,
        # 2/5 m_h r² about every axis.  Its COM lies 3r/8 from the flat face, so about its own COM
        # I_xx = 2/5 m_h r² - m_h (3r/8)² (parallel axis, moving to the COM), and about the capsule centre,
        # at distance L/2 + 3r/8 from that COM: I_xx = 2/5 m_h r² - m_h (3r/8)² + m_h (L/2 + 3r/8)²
        #                                             = m_h (2r²/5 + L²/4 + 3Lr/8).   I_zz = 2/5 m_h r².
        r, length = self.radius, self.length
        volume = math.pi * r**2 * (length + 4.0 / 3.0 * r)
        m_c, m_h = math.pi * r**2 * length / volume, 2.0 / 3.0 * math.pi * r**3 / volume
        i_xx = m_c * (3 * r**2 + length**2) / 12 + 2 * m_h * (0.4 * r**2 + length**2 / 4 + 3 * length * r / 8)
        return volume, np.array([i_xx, i_xx, m_c * r**2 / 2 + 0.8 * m_h * r**2]), length / 2 + r


def _as_size(value: Any) -> np.ndarray:
    size = as_vector(value, "size", 3)
    if np.any(size <= 0.0):
        raise InputError(f"`size` must hold 3 positive edge lengths [m], got {size.tolist()}")
    return frozen_array(size)


@dataclass(frozen=True, eq=False)
class Plane:
    """A fixed half-space: ``{x : normal.x <= offset}`` is solid, its surface is ``normal.x = offset``.

    Attributes:
        normal: Outward unit normal in the world frame (normalised on construction).
        offset: Signed distance [m] of the surface from the world origin along ``normal``.
        friction: Coulomb friction coefficient (>= 0).
        name: Display name.
    """

    normal: np.ndarray = field(default_factory=lambda: np.array([0.0, 0.0, 1.0]))
    offset: float = 0.0
    friction: float = 0.8
    name: str | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "normal", frozen_array(as_unit(self.normal, "normal")))
        object.__setattr__(self, "offset", as_real(self.offset, "offset", nonnegative=False))
        object.__setattr__(self, "friction", as_real(self.friction, "friction"))

    @property
    def placement(self) -> pin.SE3:
        """Placement of :meth:`geometry` in the world: the identity."""
        return pin.SE3.Identity()

    def geometry(self) -> coal.Halfspace:
        """A new ``coal.Halfspace(normal, offset)``."""
        return coal.Halfspace(self.normal, self.offset)


@dataclass(frozen=True, eq=False)
class FixedBox:
    """A fixed box (table top, wall) of full edge lengths ``size`` [m], centred on ``pose`` (body -> world)."""

    size: np.ndarray
    pose: pin.SE3 = field(default_factory=pin.SE3.Identity)
    friction: float = 0.8
    name: str | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "size", _as_size(self.size))
        object.__setattr__(self, "pose", _as_pose(self.pose))
        object.__setattr__(self, "friction", as_real(self.friction, "friction"))

    @property
    def placement(self) -> pin.SE3:
        """Placement of :meth:`geometry` in the world (a copy of ``pose``)."""
        return pin.SE3(self.pose)

    def geometry(self) -> coal.Box:
        """A new ``coal.Box`` of ``size``."""
        return coal.Box(*self.size)


def table(height: float = 0.0, friction: float = 0.8) -> Plane:
    """A horizontal table top: the plane z = ``height`` [m] with normal +z, solid below."""
    return Plane(normal=(0.0, 0.0, 1.0), offset=as_real(height, "height", False), friction=friction, name="table")


def wall(point: Any, normal: Any, friction: float = 0.8) -> Plane:
    """A plane through ``point`` [m] (world) with outward ``normal``; the solid lies on the side opposite ``normal``."""
    unit = frozen_array(as_unit(normal, "normal"))
    return Plane(normal=unit, offset=float(unit @ as_vector(point, "point", 3)), friction=friction, name="wall")
