"""References of a rigid-body pose: a minimum-jerk motion by a world offset, and an SE(3) path followed in time."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pinocchio as pin

from bhgrasp._validation import as_positive, as_real, as_vector
from bhgrasp.errors import InputError
from bhgrasp.motion.trajectories import Reference, Sample, minimum_jerk, time_of


class PoseMotion(Reference):
    """Minimum-jerk motion of a rigid-body pose by a world offset: the object reference of the grasp supervisor.

    With the minimum-jerk blend b(t) of :class:`Quintic` (0 -> 1 over ``duration`` after ``delay``):
    ``x(t) = x_0 + b dx`` and ``R(t) = exp(b dtheta) R_0`` (a rotation about the fixed world axis of
    ``dtheta``).  The sample is (x [m], rotation vector log(R) [rad]); the velocity and acceleration are the world
    twist (v [m/s], omega [rad/s]) and its derivative, omega = b' dtheta, which is what the object-space
    controllers read.  (Adding ``dtheta`` to the rotation vector of R_0 instead, as a :class:`Quintic` on the six
    components would, turns about the wrong axis unless R_0 = I.)
    """

    def __init__(self, start: Any, offset: Any, duration: float, delay: float = 0.0) -> None:
        """Build the motion.

        Args:
            start: Initial pose as a ``pinocchio.SE3`` (world <- body).
            offset: (dx [m], dtheta [rad]): translation and rotation vector of the change, world.
            duration: Time of the motion [s] > 0.
            delay: Start time [s] >= 0.
        """
        if not isinstance(start, pin.SE3):
            raise InputError(f"`start` must be a pinocchio.SE3, got {type(start).__name__}")
        self._start = pin.SE3(start)
        self._offset = as_vector(offset, "offset", 6).copy()
        self._offset.flags.writeable = False
        self._duration, self._delay = as_positive(duration, "duration"), as_real(delay, "delay")
        self._pause = not self._offset.any()
        self._blend: tuple[float, ...] | None = None  # what the last sample is a function of, and the sample
        self._sample: Sample = ()

    @property
    def size(self) -> int:
        """Six: position and rotation vector."""
        return 6

    # a motion is fixed once built (its last sample is kept): read-only views of what it was built from
    start = property(lambda self: pin.SE3(self._start), doc="Initial pose (a copy), world <- body.")
    offset = property(lambda self: self._offset, doc="(dx [m], dtheta [rad]), world (read-only).")
    duration = property(lambda self: self._duration, doc="Time of the motion [s].")
    delay = property(lambda self: self._delay, doc="Start time [s].")

    def __call__(self, t: float) -> Sample:
        """Pose (x, log R), twist (v, omega) and its derivative at time ``t`` [s].

        The sample is a function of the blend s alone (before and after the move s is 0 or 1), and a pause's (a zero
        offset) of the signs of the blend and its rates alone (its products are signed zeros): a repeated one is the
        last call's, copied, not computed again.
        """
        duration = self._duration
        s = min(max((time_of(t) - self._delay) / duration, 0.0), 1.0)  # the blend of Quintic(0, 1, ...), in floats
        blend, rate, curvature = minimum_jerk(s)
        rate, curvature = rate / duration, curvature / (duration * duration)
        if self._pause:
            key = (math.copysign(1.0, blend), math.copysign(1.0, rate), math.copysign(1.0, curvature))
        else:
            key = (s, math.copysign(1.0, s))  # -0.0 and 0.0 differ in the sample's bits
        if key != self._blend:
            offset, start = self._offset, self._start
            rotation = pin.exp3(blend * offset[3:]) @ start.rotation
            position = np.concatenate((start.translation + blend * offset[:3], pin.log3(rotation)))
            self._sample, self._blend = (position, rate * offset, curvature * offset), key
        position, velocity, acceleration = self._sample
        return position.copy(), velocity.copy(), acceleration.copy()


class PosePath(Reference):
    """Back-to-back minimum-jerk moves of a rigid-body pose: waypoints joined at rest.

    E.g. a wrist's approach, lift, hold and place.
    Move i starts when move i-1 ends (the first after ``delay``) and changes the pose by its world offset (dx [m],
    dtheta [rad]) as :class:`PoseMotion` does; a zero offset is a pause.  The sample and its derivatives are
    :class:`PoseMotion`'s, from the pose the earlier moves reached; every move starts and ends at rest, so the
    path is C2 at the joins.
    """

    def __init__(self, start: Any, moves: Any, delay: float = 0.0) -> None:
        """Build the path.

        Args:
            start: Initial pose, a ``pinocchio.SE3`` (world <- body).
            moves: Sequence of (offset (6,), duration [s] > 0).
            delay: Start time of the first move [s] >= 0.
        """
        if not isinstance(start, pin.SE3):
            raise InputError(f"`start` must be a pinocchio.SE3, got {type(start).__name__}")
        moves = list(moves)
        if not moves:
            raise InputError("`moves` must hold at least one (offset, duration) pair")
        segments: list[PoseMotion] = []
        pose, begin = pin.SE3(start), as_real(delay, "delay")
        for i, move in enumerate(moves):
            if len(move) != 2:
                raise InputError(f"`moves[{i}]` must be an (offset (6,), duration [s]) pair, got {move!r}")
            offset, duration = as_vector(move[0], f"moves[{i}] offset", 6), as_positive(move[1], f"moves[{i}] duration")
            segments.append(PoseMotion(pose, offset, duration, begin))
            pose = pin.SE3(pin.exp3(offset[3:]) @ pose.rotation, pose.translation + offset[:3])
            begin += duration
        self.segments: tuple[PoseMotion, ...] = tuple(segments)  # each fixed once built
        self.end_time, self._end = begin, pose

    end = property(lambda self: pin.SE3(self._end), doc="The pose the last move reaches (a copy).")

    @property
    def size(self) -> int:
        """Six: position and rotation vector."""
        return 6

    def __call__(self, t: float) -> Sample:
        """Pose (x, log R), world twist and its derivative at time ``t`` [s]."""
        t = time_of(t)
        for segment in self.segments:
            if t < segment.delay + segment.duration:
                return segment(t)
        return self.segments[-1](t)


__all__ = ["PoseMotion", "PosePath"]
