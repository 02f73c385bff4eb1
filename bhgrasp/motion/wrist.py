"""A wrist reference: a world pose reference of the hand base in mount coordinates (:class:`MountReference`)."""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from bhgrasp.errors import InputError
from bhgrasp.model.mount import angular_map, angular_map_rate, mount_coordinates
from bhgrasp.motion.trajectories import Reference, Sample


class MountReference(Reference):
    """A world pose reference of the hand base turned into mount coordinates (size 6) for a mounted hand's servo.

    ``pose``: a Reference of size 6 giving the base pose (x [m], rotation vector of world <- base [rad]) with its
    world twist (v [m/s], omega [rad/s]) and twist derivative, as :class:`~bhgrasp.motion.trajectories.PoseMotion` does;
    ``origin``: the mount's origin in the world (the mounted hand's ``base_placement``).  The coordinates are
    c = coordinates(origin^-1 pose), their rates c_dot = (R_o^T v, E^-1 R_o^T omega) and accelerations
    c_dd = (R_o^T a, E^-1 (R_o^T alpha - dE/dt angle rates)) (:func:`~bhgrasp.model.mount.angular_map`,
    :func:`~bhgrasp.model.mount.angular_map_rate`).
    """

    def __init__(self, pose: Reference, origin: pin.SE3) -> None:
        """Wrap ``pose`` for a mount whose origin is ``origin`` (world <- mount)."""
        if not isinstance(pose, Reference) or pose.size != 6:
            raise InputError(f"`pose` must be a Reference of size 6 (position, rotation vector), got {pose!r}")
        if not isinstance(origin, pin.SE3):
            raise InputError(f"`origin` must be a pinocchio.SE3, got {type(origin).__name__}")
        self._pose, self._origin = pose, pin.SE3(origin)
        self._pose_sample = b""  # the last pose sample's bytes and its coordinates, kept: a wrist at rest repeats it
        self._coordinates: Sample = ()

    @property
    def size(self) -> int:
        """Six mount coordinates."""
        return 6

    # fixed once built (the coordinates of the last pose sample are kept)
    pose = property(lambda self: self._pose, doc="The pose reference (size 6).")
    origin = property(lambda self: pin.SE3(self._origin), doc="The mount's origin (a copy), world <- mount.")

    def __call__(self, t: float) -> Sample:
        """Coordinates, their rates and accelerations at ``t`` [s] (for a repeated pose sample: the last, copied)."""
        sample, twist, derivative = self._pose(t)
        key = sample.tobytes() + twist.tobytes() + derivative.tobytes()
        if key != self._pose_sample:
            self._coordinates, self._pose_sample = self._convert(sample, twist, derivative), key
        c, c_dot, c_dd = self._coordinates
        return c.copy(), c_dot.copy(), c_dd.copy()

    def _convert(self, sample: np.ndarray, twist: np.ndarray, derivative: np.ndarray) -> Sample:
        """The mount coordinates, rates and accelerations of a pose sample (class docstring)."""
        rotation_t = self._origin.rotation.T
        local = self._origin.actInv(pin.SE3(pin.exp3(sample[3:]), sample[:3]))
        c = mount_coordinates(local)
        angular = angular_map(c)
        c_dot = np.concatenate((rotation_t @ twist[:3], np.linalg.solve(angular, rotation_t @ twist[3:])))
        spin = rotation_t @ derivative[3:] - angular_map_rate(c, c_dot) @ c_dot[3:]
        return c, c_dot, np.concatenate((rotation_t @ derivative[:3], np.linalg.solve(angular, spin)))


__all__ = ["MountReference"]
