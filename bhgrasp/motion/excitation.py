"""A persistently exciting object path: lift, then oscillate in position and orientation (for identification).

Adaptive laws learn a parameter only along the directions the motion excites (persistent excitation: the regressor's
integral of Y^T Y over a window stays positive definite).  :class:`PoseExcitation` lifts the object clear of its
support, then sums sinusoids of distinct frequencies on each axis, so that the object's mass and the inertia about
the axes it turns about become observable.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pinocchio as pin

from bhgrasp._validation import as_positive, as_real, as_vector
from bhgrasp.errors import InputError
from bhgrasp.motion.trajectories import Reference, Sample, minimum_jerk, time_of

_AXES = np.eye(3)


class PoseExcitation(Reference):
    """Lift by ``lift``, then oscillate: the object reference of an identification run (world, COM).

    After ``delay`` the position moves by ``lift`` along a minimum-jerk blend over ``lift_time``.  From then on
    (tau = time since the lift ended), six channels c_i = A_i w(tau) sin(2 pi f_i tau), under the minimum-jerk ramp
    w from 0 to 1 over ``ramp``, move the position by (c_0, c_1, c_2) and turn the orientation by the angles
    (c_3, c_4, c_5) about the world axes x, then y, then z:
    ``R = exp(c_3 e_x) exp(c_4 e_y) exp(c_5 e_z) R_lifted``.  The sample is (x [m], log R [rad]); velocity and
    acceleration are the world twist (v, omega) and its derivative, in closed form.
    """

    def __init__(
        self,
        start: pin.SE3,
        amplitude: Any,
        frequency: Any,
        delay: float = 0.0,
        lift: Any = (0.0, 0.0, 0.01),
        lift_time: float = 0.5,
        ramp: float = 0.5,
    ) -> None:
        """Build the path.

        Args:
            start: Initial pose (world <- body).
            amplitude: Six amplitudes: position [m] along x, y, z and angles [rad] about x, y, z.
            frequency: Six frequencies [Hz] (> 0; distinct ones excite independently).
            delay: Start time of the lift [s].
            lift: World offset [m] of the lift.
            lift_time: Duration of the lift [s].
            ramp: Duration of the oscillation's fade-in [s].
        """
        if not isinstance(start, pin.SE3):
            raise InputError(f"`start` must be a pinocchio.SE3, got {type(start).__name__}")
        self.start = pin.SE3(start)
        self.amplitude = as_vector(amplitude, "amplitude", 6)
        self.frequency = as_vector(frequency, "frequency", 6)
        if np.any(self.frequency <= 0.0):
            raise InputError(f"`frequency` must be > 0 [Hz] on every axis, got {self.frequency.tolist()}")
        self.delay, self.lift = as_real(delay, "delay"), as_vector(lift, "lift", 3)
        self.lift_time, self.ramp = as_positive(lift_time, "lift_time"), as_positive(ramp, "ramp")

    @property
    def size(self) -> int:
        """Six: position and rotation vector."""
        return 6

    def channels(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The six oscillation channels c, c_dot, c_ddot at time ``t`` [s] (zero until the lift ends)."""
        tau = time_of(t) - self.delay - self.lift_time
        if tau <= 0.0:
            return np.zeros(6), np.zeros(6), np.zeros(6)
        w, w_dot, w_ddot = minimum_jerk(min(tau / self.ramp, 1.0))
        w_dot, w_ddot = w_dot / self.ramp, w_ddot / (self.ramp * self.ramp)
        omega = 2.0 * np.pi * self.frequency
        sine, cosine = np.sin(omega * tau), np.cos(omega * tau)
        value = self.amplitude * w * sine
        rate = self.amplitude * (w_dot * sine + w * omega * cosine)
        curvature = self.amplitude * (w_ddot * sine + 2.0 * w_dot * omega * cosine - w * omega * omega * sine)
        return value, rate, curvature

    def __call__(self, t: float) -> Sample:
        """Pose (x, log R), world twist and its derivative at time ``t`` [s]."""
        s = min(max((time_of(t) - self.delay) / self.lift_time, 0.0), 1.0)
        blend, blend_rate, blend_curvature = minimum_jerk(s)
        c, c_dot, c_ddot = self.channels(t)
        position = self.start.translation + blend * self.lift + c[:3]
        velocity = blend_rate / self.lift_time * self.lift + c_dot[:3]
        acceleration = blend_curvature / self.lift_time**2 * self.lift + c_ddot[:3]
        # R = Ra Rb Rc R_0; omega = a' e_x + Ra b' e_y + Ra Rb c' e_z, and d/dt (R_ab u) = omega_ab x (R_ab u)
        ra, rab = pin.exp3(c[3] * _AXES[0]), pin.exp3(c[3] * _AXES[0]) @ pin.exp3(c[4] * _AXES[1])
        rotation = rab @ pin.exp3(c[5] * _AXES[2]) @ self.start.rotation
        turn_a, turn_b, turn_c = c_dot[3] * _AXES[0], ra @ (c_dot[4] * _AXES[1]), rab @ (c_dot[5] * _AXES[2])
        omega = turn_a + turn_b + turn_c
        alpha = (
            c_ddot[3] * _AXES[0]
            + ra @ (c_ddot[4] * _AXES[1])
            + np.cross(turn_a, turn_b)
            + rab @ (c_ddot[5] * _AXES[2])
            + np.cross(turn_a + turn_b, turn_c)
        )
        return (
            np.concatenate((position, pin.log3(rotation))),
            np.concatenate((velocity, omega)),
            np.concatenate((acceleration, alpha)),
        )

    def extremes(self) -> np.ndarray:
        """(13, 6) offsets from ``start`` the path reaches at most: the lift, and the lift +- each amplitude.

        For checking the path against a grasp's manipulable space before running it (first order: each axis alone).
        """
        lift = np.concatenate((self.lift, np.zeros(3)))
        rows = [lift]
        for i in range(6):
            for sign in (1.0, -1.0):
                row = lift.copy()
                row[i] += sign * self.amplitude[i]
                rows.append(row)
        return np.array(rows)


__all__ = ["PoseExcitation"]
