"""Continuous object paths for the grasp supervisor: a circle, and waypoints with blends.

:class:`PoseCircle` lifts the object clear of its support, then carries its centre of mass ``turns`` times around a
circle of radius ``radius`` in the plane of two world directions (u, v) through the lifted point, the orientation
held.  The arc angle follows a minimum-jerk blend, so the path starts and ends at rest:

    x(t) = x_0 + b_l(t) l + r (u (1 - cos phi) + v sin phi),   phi(t) = 2 pi turns b(t),

b_l and b the minimum-jerk blends of the lift and of the circle (0 -> 1).  The centre is x_0 + l + r u; the path
first heads along +v.  Velocity and acceleration are in closed form (world twist, omega = 0).

:class:`PoseWaypoints` joins moves between waypoints with minimum-jerk blends: each move (a world offset, as
:class:`~bhgrasp.motion.trajectories.PoseMotion` makes it) starts ``overlap`` seconds before the previous one ends, and
the moves add up (Flash & Hogan 1985's superposition of minimum-jerk strokes): the object passes by the inner waypoints
without stopping and ends at rest at the last one.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pinocchio as pin

from bhgrasp._validation import as_positive, as_real, as_vector
from bhgrasp.errors import InputError
from bhgrasp.motion.trajectories import Reference, Sample, minimum_jerk, time_of

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
        try:
            axes = np.asarray(plane, dtype=float)
        except (TypeError, ValueError):
            axes = np.empty(0)
        orthonormal = axes.shape == (2, 3) and np.all(np.isfinite(axes))
        if not (orthonormal and np.allclose(axes @ axes.T, np.eye(2), atol=1e-9)):
            raise InputError(f"`plane` must be two orthonormal 3-vectors (u, v), got {plane!r}")
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
        s = min(max((time_of(t) - self.delay - self.lift_time) / self.duration, 0.0), 1.0)
        blend, rate, curvature = minimum_jerk(s)
        full = 2.0 * np.pi * self.turns
        return full * blend, full * rate / self.duration, full * curvature / self.duration**2

    def displacement(self, phi: float) -> np.ndarray:
        """The centre of mass's offset [m] from the lifted point at arc angle ``phi`` [rad]."""
        return self.radius * (self.u * (1.0 - np.cos(phi)) + self.v * np.sin(phi))

    def __call__(self, t: float) -> Sample:
        """Pose (x, log R), world twist and its derivative at time ``t`` [s]."""
        s = min(max((time_of(t) - self.delay) / self.lift_time, 0.0), 1.0)
        blend, blend_rate, blend_curvature = minimum_jerk(s)
        phi, phi_dot, phi_ddot = self.arc(t)
        tangent = self.radius * (self.u * np.sin(phi) + self.v * np.cos(phi))  # d displacement / d phi
        inward = self.radius * (self.u * np.cos(phi) - self.v * np.sin(phi))  # d tangent / d phi
        position = self.start.translation + blend * self.lift + self.displacement(phi)
        velocity = blend_rate / self.lift_time * self.lift + tangent * phi_dot
        acceleration = blend_curvature / self.lift_time**2 * self.lift + inward * phi_dot**2 + tangent * phi_ddot
        zero = np.zeros(3)
        return (
            np.concatenate((position, pin.log3(self.start.rotation))),
            np.concatenate((velocity, zero)),
            np.concatenate((acceleration, zero)),
        )

    def extremes(self) -> np.ndarray:
        """(8, 6) offsets from ``start`` on the path: the lift, and the circle every 45 deg after it.

        For checking the path against a grasp's manipulable space before running it (first order: a circle in an
        allowed plane is allowed; its points name a missing direction otherwise).
        """
        rows = [np.concatenate((self.lift + self.displacement(phi), np.zeros(3))) for phi in (0.0, *_EXTREME_ANGLES)]
        return np.array(rows)


class PoseWaypoints(Reference):
    """Moves by world offsets, each a minimum-jerk blend, overlapping by ``overlap``: a path through waypoints.

    With move i's blend b_i(t) (0 -> 1 over its duration d_i from its start t_i = delay + sum_(j<i) (d_j -
    overlap)): x(t) = x_0 + sum_i b_i dx_i and R(t) = E_n ... E_1 R_0, E_i = exp(b_i dtheta_i) (each a turn about
    a fixed world axis).  The world twist is omega = sum_i P_i b_i' dtheta_i with P_i = E_n ... E_(i+1), and its
    derivative sum_i (P_i b_i'' dtheta_i + omega_(>i) x P_i b_i' dtheta_i), omega_(>i) the part of omega from the
    moves after i.  ``overlap`` 0 gives :class:`~bhgrasp.motion.trajectories.PosePath` (waypoints joined at rest).
    """

    def __init__(self, start: pin.SE3, moves: Any, overlap: float = 0.0, delay: float = 0.0) -> None:
        """Build the path.

        Args:
            start: Initial pose (world <- body).
            moves: Sequence of (offset (6,): dx [m], dtheta [rad], world; duration [s] > ``overlap``).
            overlap: How long [s] each move starts before the previous one ends (>= 0).
            delay: Start time of the first move [s].
        """
        if not isinstance(start, pin.SE3):
            raise InputError(f"`start` must be a pinocchio.SE3, got {type(start).__name__}")
        pairs = isinstance(moves, (list, tuple)) and len(moves) > 0
        pairs = pairs and all(isinstance(move, (list, tuple)) and len(move) == 2 for move in moves)
        if not pairs:
            raise InputError(f"`moves` must be one or more (offset (6,), duration [s]) pairs, got {moves!r}")
        self.start, self.overlap = pin.SE3(start), as_real(overlap, "overlap")
        self.offsets = np.array([as_vector(move[0], f"moves[{i}] offset", 6) for i, move in enumerate(moves)])
        self.durations = np.array([as_positive(move[1], f"moves[{i}] duration") for i, move in enumerate(moves)])
        if self.overlap < 0.0 or np.any(self.durations <= self.overlap):
            raise InputError(
                f"`overlap` must be >= 0 and shorter than every move, got {overlap} for durations "
                f"{self.durations.tolist()} [s]"
            )
        self.starts = as_real(delay, "delay") + np.concatenate(([0.0], np.cumsum(self.durations[:-1] - self.overlap)))

    @property
    def size(self) -> int:
        """Six: position and rotation vector."""
        return 6

    @property
    def end_time(self) -> float:
        """When the last move ends [s] (at rest)."""
        return float(self.starts[-1] + self.durations[-1])

    def __call__(self, t: float) -> Sample:
        """Pose (x, log R), world twist and its derivative at time ``t`` [s]."""
        t = time_of(t)
        blends = [minimum_jerk(min(max((t - t0) / d, 0.0), 1.0)) for t0, d in zip(self.starts, self.durations)]
        b = np.array([blend for blend, _, _ in blends])
        rate = np.array([r / d for (_, r, _), d in zip(blends, self.durations)])
        curvature = np.array([c / d**2 for (_, _, c), d in zip(blends, self.durations)])
        dx, dtheta = self.offsets[:, :3], self.offsets[:, 3:]
        rotation, omega, alpha = self.start.rotation, np.zeros(3), np.zeros(3)
        for i in range(len(b)):  # R_i = E_i R_(i-1): the later turns carry the earlier ones' rates
            turn = pin.exp3(b[i] * dtheta[i])
            rotation = turn @ rotation
            alpha = turn @ alpha + np.cross(rate[i] * dtheta[i], turn @ omega) + curvature[i] * dtheta[i]
            omega = turn @ omega + rate[i] * dtheta[i]
        position = self.start.translation + b @ dx
        return (
            np.concatenate((position, pin.log3(rotation))),
            np.concatenate((rate @ dx, omega)),
            np.concatenate((curvature @ dx, alpha)),
        )

    def extremes(self) -> np.ndarray:
        """(n, 6) offsets from ``start`` at each waypoint (the moves' sums; rotation vectors added, first order)."""
        return np.cumsum(self.offsets, axis=0)


__all__ = ["PoseCircle", "PoseWaypoints"]
