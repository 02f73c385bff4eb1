"""Continuous object paths for the grasp supervisor (issue 17, item 3): a circle after a lift.

:class:`PoseCircle` lifts the object clear of its support, then carries its centre of mass ``turns`` times around a
circle of radius ``radius`` in the plane of two world directions (u, v) through the lifted point, the orientation
held.  The arc angle follows a minimum-jerk blend, so the path starts and ends at rest:

    x(t) = x_0 + b_l(t) l + r (u (1 - cos phi) + v sin phi),   phi(t) = 2 pi turns b(t),

b_l and b the minimum-jerk blends of the lift and of the circle (0 -> 1).  The centre is x_0 + l + r u; the path
first heads along +v.  Velocity and acceleration are in closed form (world twist, omega = 0).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pinocchio as pin

from bhgrasp._validation import as_positive, as_real, as_vector
from bhgrasp.errors import InputError
from bhgrasp.trajectories import Reference, Sample, _time, minimum_jerk

_EXTREME_ANGLES = np.arange(1, 8) * np.pi / 4  # the circle's points checked by :meth:`PoseCircle.extremes`


class PoseCircle(Reference):
    """Lift by ``lift``, then go around a circle: a continuous object reference (world, centre of mass)."""

    def __init__(
        self,
        start: pin.SE3,
        radius: float,
        plane: Any = ((0.0, 1.0, 0.0), (0.0, 0.0, 1.0)),
        duration: float = 2.0,
        delay: float = 0.0,
        turns: float = 1.0,
        lift: Any = (0.0, 0.0, 0.01),
        lift_time: float = 0.5,
    ) -> None:
        """Build the path.

        Args:
            start: Initial pose (world <- body); its orientation is held.
            radius: Circle radius [m] > 0.
            plane: Two orthonormal world directions (u, v): the centre lies along u from the lifted point, the
                motion starts along v.
            duration: Time [s] of the circle, after the lift.
            delay: Start time of the lift [s].
            turns: Number of times around (> 0; 1: back to the lifted point).
            lift: World offset [m] of the lift.
            lift_time: Duration of the lift [s].
        """
        if not isinstance(start, pin.SE3):
            raise InputError(f"`start` must be a pinocchio.SE3, got {type(start).__name__}")
        axes = np.asarray(plane, dtype=float)
        if (
            axes.shape != (2, 3)
            or not np.all(np.isfinite(axes))
            or not np.allclose(axes @ axes.T, np.eye(2), atol=1e-9)
        ):
            raise InputError(f"`plane` must be two orthonormal 3-vectors (u, v), got {np.asarray(plane).tolist()}")
        self.start, self.u, self.v = pin.SE3(start), axes[0].copy(), axes[1].copy()
        self.radius, self.duration = as_positive(radius, "radius"), as_positive(duration, "duration")
        self.delay, self.turns = as_real(delay, "delay"), as_positive(turns, "turns")
        self.lift, self.lift_time = as_vector(lift, "lift", 3), as_positive(lift_time, "lift_time")

    @property
    def size(self) -> int:
        """Six: position and rotation vector."""
        return 6

    @property
    def end_time(self) -> float:
        """When the circle ends [s] (at rest)."""
        return self.delay + self.lift_time + self.duration

    def arc(self, t: float) -> tuple[float, float, float]:
        """The arc angle phi [rad] and its first two time derivatives at ``t`` [s]."""
        s = min(max((_time(t) - self.delay - self.lift_time) / self.duration, 0.0), 1.0)
        blend, rate, curvature = minimum_jerk(s)
        full = 2.0 * np.pi * self.turns
        return full * blend, full * rate / self.duration, full * curvature / self.duration**2

    def displacement(self, phi: float) -> np.ndarray:
        """The centre of mass's offset [m] from the lifted point at arc angle ``phi`` [rad]."""
        return self.radius * (self.u * (1.0 - np.cos(phi)) + self.v * np.sin(phi))

    def __call__(self, t: float) -> Sample:
        """Pose (x, log R), world twist and its derivative at time ``t`` [s]."""
        s = min(max((_time(t) - self.delay) / self.lift_time, 0.0), 1.0)
        blend, blend_rate, blend_curvature = minimum_jerk(s)
        phi, phi_dot, phi_ddot = self.arc(t)
        tangent = self.radius * (self.u * np.sin(phi) + self.v * np.cos(phi))  # d displacement / d phi
        inward = self.radius * (self.u * np.cos(phi) - self.v * np.sin(phi))  # d tangent / d phi
        position = self.start.translation + blend * self.lift + self.displacement(phi)
        velocity = blend_rate / self.lift_time * self.lift + tangent * phi_dot
        acceleration = blend_curvature / self.lift_time**2 * self.lift + inward * phi_dot**2 + tangent * phi_ddot
        zero = np.zeros(3)
        return (np.concatenate((position, pin.log3(self.start.rotation))), np.concatenate((velocity, zero)),
                np.concatenate((acceleration, zero)))  # fmt: skip

    def extremes(self) -> np.ndarray:
        """(8, 6) offsets from ``start`` on the path: the lift, and the circle every 45 deg after it.

        For checking the path against a grasp's manipulable space before running it (first order: a circle in an
        allowed plane is allowed; its points name a missing direction otherwise).
        """
        rows = [np.concatenate((self.lift + self.displacement(phi), np.zeros(3))) for phi in (0.0, *_EXTREME_ANGLES)]
        return np.array(rows)


__all__ = ["PoseCircle"]
