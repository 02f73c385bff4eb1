"""A hand on a moving wrist: six actuated mount joints between the world and the hand base.

A grasp is followed by lift, carry, shake and place, which the arm does: :func:`mounted` returns the hand with six
1-DOF joints in front of its own, ``mount_x``, ``mount_y``, ``mount_z`` (prismatic along the mount frame's axes
[m]) and ``mount_yaw``, ``mount_pitch``, ``mount_roll`` (revolute about z, then the new y, then the new x [rad]).
With mount coordinates c = (x, y, z, yaw, pitch, roll) the hand base frame W sits at

    M(c) = P * SE3(Rz(yaw) Ry(pitch) Rx(roll), (x, y, z)),

P the mount's origin in the world (the unmounted hand's ``base_placement``), so c = 0 leaves the hand where it was.
The mount joints are massless; the palm's inertia rides on the roll joint, so the mount carries the whole hand, and
a contact point's velocity includes the wrist's motion (the point Jacobians have the mount columns).

Why actuated joints and not a prescribed base motion: the hand's inertia couples to the wrist's acceleration, the
fingers' contact velocities include the wrist's, and the wrist feels the object's load, all without a second code
path: the mounted hand is a :class:`~bhgrasp.model.hand.Hand` like any other (``nq`` = 6 + the hand's), so the engines,
batches, recorder, sensing and viewer handle it unchanged.  A stiff servo on the mount joints
(:class:`~bhgrasp.controllers.mount.MountServo`) drives it along a reference
(:class:`~bhgrasp.motion.wrist.MountReference`), as an arm's joint servos do.

Limits: translation +-``reach`` [m]; yaw and roll +-pi; pitch +-1.5 rad (the Z-Y-X angles are singular at
+-pi/2).  Gravity stays the hand's (world coordinates), in any direction.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pinocchio as pin

from bhgrasp._validation import as_positive, as_vector
from bhgrasp.errors import ModelError
from bhgrasp.model.hand import Hand

MOUNT_JOINTS = ("mount_x", "mount_y", "mount_z", "mount_yaw", "mount_pitch", "mount_roll")
_JOINT_MODELS = (
    pin.JointModelPX,
    pin.JointModelPY,
    pin.JointModelPZ,
    pin.JointModelRZ,
    pin.JointModelRY,
    pin.JointModelRX,
)
PITCH_LIMIT = 1.5  # [rad] inside the Z-Y-X singularity at pi/2
MOUNT_SPEED = (2.0, 2.0, 2.0, 2 * np.pi, 2 * np.pi, 2 * np.pi)  # [m/s, rad/s] an arm's wrist, roughly
MOUNT_EFFORT = (500.0, 500.0, 500.0, 50.0, 50.0, 50.0)  # [N, N m]


def mounted(hand: Hand, reach: float = 1.0, name: str | None = None) -> Hand:
    """The hand on a six-joint wrist mount whose origin is the hand's current ``base_placement``.

    Args:
        hand: Any fixed-base hand (its collision geometry comes along: ``hand.collision_geometry`` or its URDF's).
        reach: Translation limit of the mount joints [m] (both directions).
        name: Display name (default: the hand's name, "on a wrist mount").

    Raises:
        ModelError: The hand already has mount joints.
    """
    reach = as_positive(reach, "reach")
    if any(joint in hand.joint_names for joint in MOUNT_JOINTS):
        raise ModelError(f"{hand.name!r} is already mounted (it has the joints {MOUNT_JOINTS})")
    wrist = pin.Model()
    wrist.name = "mount"
    joint = 0
    for joint_name, joint_model in zip(MOUNT_JOINTS, _JOINT_MODELS):
        joint = wrist.addJoint(joint, joint_model(), pin.SE3.Identity(), joint_name)
        wrist.addJointFrame(joint)
        wrist.appendBodyToJoint(joint, pin.Inertia.Zero(), pin.SE3.Identity())
    model, geometry = pin.appendModel(
        wrist,
        hand.model,
        pin.GeometryModel(),
        hand.collision_model(),
        wrist.getFrameId(MOUNT_JOINTS[-1]),
        pin.SE3.Identity(),
    )
    model.name = hand.model.name
    limits = {
        "lowerPositionLimit": [-reach] * 3 + [-np.pi, -PITCH_LIMIT, -np.pi],
        "upperPositionLimit": [reach] * 3 + [np.pi, PITCH_LIMIT, np.pi],
        "velocityLimit": MOUNT_SPEED,
        "effortLimit": MOUNT_EFFORT,
    }
    for attribute, mount_values in limits.items():  # the mount's coordinates come first
        values = getattr(model, attribute).copy()
        values[:6] = mount_values
        setattr(model, attribute, values)
    return Hand(
        model,
        hand.fingertip_frames,
        name=name or f"{hand.name} on a wrist mount",
        base_placement=hand.base_placement,
        gravity=hand.gravity,
        urdf_path=hand.urdf_path,
        collision_geometry=geometry,
        base_joints=MOUNT_JOINTS + hand.base_joints,
    )


def mount_pose(coordinates: Any) -> pin.SE3:
    """SE3(Rz(yaw) Ry(pitch) Rx(roll), (x, y, z)): the hand base in the mount frame for coordinates c (6,)."""
    c = as_vector(coordinates, "coordinates", 6)
    rotation = pin.rpy.rpyToMatrix(c[5], c[4], c[3])  # Pinocchio's rpy: R = Rz(yaw) Ry(pitch) Rx(roll)
    return pin.SE3(rotation, c[:3].copy())


def mount_coordinates(pose: pin.SE3) -> np.ndarray:
    """The coordinates c (6,) of a hand base pose in the mount frame (pitch in (-pi/2, pi/2))."""
    roll, pitch, yaw = pin.rpy.matrixToRpy(pose.rotation)
    return np.array([*pose.translation, yaw, pitch, roll])


def angular_map(coordinates: Any) -> np.ndarray:
    """E (3, 3) with omega = E (yaw_dot, pitch_dot, roll_dot): the mount frame's angular velocity of the base."""
    c = as_vector(coordinates, "coordinates", 6)
    yaw, pitch = c[3], c[4]
    z = np.array([0.0, 0.0, 1.0])
    y = np.array([-np.sin(yaw), np.cos(yaw), 0.0])  # Rz(yaw) e_y
    x = np.array([np.cos(yaw) * np.cos(pitch), np.sin(yaw) * np.cos(pitch), -np.sin(pitch)])  # Rz Ry e_x
    return np.column_stack((z, y, x))


def angular_map_rate(coordinates: Any, rates: Any) -> np.ndarray:
    """dE/dt (3, 3) along coordinate rates (6,): omega_dot = E (angle accelerations) + dE/dt (angle rates)."""
    c, c_dot = as_vector(coordinates, "coordinates", 6), as_vector(rates, "rates", 6)
    yaw, pitch, yaw_dot, pitch_dot = c[3], c[4], c_dot[3], c_dot[4]
    sy, cy, sp, cp = np.sin(yaw), np.cos(yaw), np.sin(pitch), np.cos(pitch)
    y_rate = np.array([-cy, -sy, 0.0]) * yaw_dot
    x_rate = np.array(
        [-sy * cp * yaw_dot - cy * sp * pitch_dot, cy * cp * yaw_dot - sy * sp * pitch_dot, -cp * pitch_dot]
    )
    return np.column_stack((np.zeros(3), y_rate, x_rate))


__all__ = [
    "MOUNT_JOINTS",
    "angular_map",
    "angular_map_rate",
    "mount_coordinates",
    "mount_pose",
    "mounted",
]
