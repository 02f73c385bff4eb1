"""A body held on a spring: the compliant environment of thesis chapter 4 (4.3)-(4.7)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import coal
import numpy as np
import pinocchio as pin

from bhgrasp._validation import as_positive, as_real, as_unit
from bhgrasp.errors import InputError
from bhgrasp.model.objects import RigidObject, frozen_array


@dataclass(frozen=True, eq=False)
class SpringMounted:
    """A body that can only translate along ``direction``, held at its initial pose by a spring-damper.

    The compliant environment of the thesis (4.3)-(4.7): ``m_o z'' + D_s z' + K_s (z_o - z_c) = F_o`` with
    ``z_o`` the displacement along ``direction`` and ``z_c`` its rest value (the initial pose); the thesis has
    no damper (``damping = 0``).  This is a description only; the scene turns it into a prismatic joint.

    Attributes:
        body: The rigid body (its ``pose`` is the rest pose).
        direction: Unit direction of motion in the world frame (normalised on construction).
        stiffness: Spring stiffness K_s [N/m] (> 0).
        damping: Viscous damping D_s [N s/m] (>= 0).
        name: Display name; defaults to the body's name.
    """

    body: RigidObject
    direction: np.ndarray
    stiffness: float
    damping: float = 0.0
    name: str | None = None

    def __post_init__(self) -> None:
        if not isinstance(self.body, RigidObject):
            raise InputError(f"`body` must be a RigidObject (Sphere, Box, ...), got {type(self.body).__name__}")
        object.__setattr__(self, "direction", frozen_array(as_unit(self.direction, "direction")))
        object.__setattr__(self, "stiffness", as_positive(self.stiffness, "stiffness"))
        object.__setattr__(self, "damping", as_real(self.damping, "damping"))
        if self.name is None:
            object.__setattr__(self, "name", self.body.name)

    @property
    def mass(self) -> float:
        """Mass of the body [kg]."""
        return self.body.mass

    @property
    def friction(self) -> float:
        """Friction coefficient of the body."""
        return self.body.friction

    @property
    def pose(self) -> pin.SE3:
        """Rest pose of the body, ``transform_body_to_world``."""
        return self.body.pose

    @property
    def natural_frequency(self) -> float:
        """Undamped natural frequency sqrt(K_s / m_o) [rad/s]."""
        return math.sqrt(self.stiffness / self.mass)

    def geometry(self) -> coal.ShapeBase:
        """A new coal shape of the body."""
        return self.body.geometry()

    def collision_shapes(self) -> list[coal.CollisionGeometry]:
        """The shapes the simulator collides (the body's)."""
        return self.body.collision_shapes()


__all__ = ["SpringMounted"]
