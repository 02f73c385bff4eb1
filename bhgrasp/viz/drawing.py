"""What the MeshCat views draw, and when: colours, shapes, contact arrows and cones, the object's ghost, frames."""

from __future__ import annotations

import meshcat.geometry as mg
import numpy as np
import pinocchio as pin

from bhgrasp._validation import as_positive
from bhgrasp.data import Trajectory
from bhgrasp.errors import InputError
from bhgrasp.model.objects import Box, Capsule, Cylinder, RigidObject, Sphere

MAX_FPS = 60.0
LOOP_FOREVER = float("inf")  # replay repetitions (msgpack float64 inf: JavaScript's Infinity)
ROOT = "bhgrasp"
HAND_RGBA = (0.55, 0.57, 0.62, 1.0)
OBJECT_RGBA = (0.95, 0.55, 0.15, 0.45)  # translucent: the contact forces and cones inside it stay visible
ENVIRONMENT_RGBA = (0.45, 0.35, 0.25, 1.0)
CONE_HEIGHT = 0.015  # [m] drawn friction cones
DISPLAY_FORCE_SCALE = 0.005  # [m/N] arrows of display()


def checked_fps(fps: float) -> float:
    """``fps`` [frames per simulated second] of a replay or a live view: positive and at most :data:`MAX_FPS`."""
    fps = as_positive(fps, "fps")
    if fps > MAX_FPS:
        raise InputError(f"`fps` must be <= {MAX_FPS:g} (a set_transform costs ~0.2 ms per node), got {fps}")
    return fps


def frame_samples(t: np.ndarray, fps: float) -> np.ndarray:
    """Indices of the samples nearest to t0, t0 + 1/fps, ... up to the last sample."""
    times = np.arange(t[0], t[-1] + 0.5 / fps, 1.0 / fps)
    return np.unique(np.clip(np.searchsorted(t, times), 0, len(t) - 1))


def object_poses(traj: Trajectory, k: int) -> list[pin.SE3]:
    """Each object's pose at sample ``k`` of a recorded run."""
    poses = []
    for position, quaternion in zip(traj.object_position[k], traj.object_quaternion[k]):
        poses.append(pin.XYZQUATToSE3(np.concatenate((position, quaternion))))
    return poses


def contact_overlays(point, normal, force, sticking: bool, force_scale: float, mu: float) -> dict[str, tuple]:
    """(transform, scale, visible) of a contact's force arrow (stick or slip colour) and friction cone.

    The arrow is the force on the object, from the contact point, ``force_scale`` [m/N] long per newton; the cone
    has its apex at the point, its axis along the normal and radius mu * height (the friction cone's half-angle).
    """
    point, normal, force = (np.asarray(a, dtype=float) for a in (point, normal, force))
    magnitude = float(np.linalg.norm(force))
    direction = force / magnitude if magnitude > 1e-9 else normal
    length = max(force_scale * magnitude, 1e-4)
    arrow = _along(direction, point + 0.5 * length * direction)
    cone = _along(normal, point + 0.5 * CONE_HEIGHT * normal)
    return {
        "stick": (arrow, (1.0, length, 1.0), sticking),
        "slip": (arrow, (1.0, length, 1.0), not sticking),
        "cone": (cone, (mu * CONE_HEIGHT, CONE_HEIGHT, mu * CONE_HEIGHT), True),
    }


def hidden_overlays() -> dict[str, tuple]:
    """The contact overlays hidden (for a contact slot not in use)."""
    return dict.fromkeys(("stick", "slip", "cone"), (np.eye(4), (1.0, 1.0, 1.0), False))


def _along(direction: np.ndarray, centre: np.ndarray) -> np.ndarray:
    """A rigid transform whose local y axis (three.js cylinders' axis) points along ``direction``, at ``centre``."""
    transform = np.eye(4)
    transform[:3, :3] = pin.Quaternion.FromTwoVectors(np.array([0.0, 1.0, 0.0]), direction).toRotationMatrix()
    transform[:3, 3] = centre
    return transform


def translation(position: np.ndarray) -> np.ndarray:
    """The 4x4 homogeneous transform of a translation ``position`` [m]."""
    transform = np.eye(4)
    transform[:3, 3] = position
    return transform


def animate_ghost(view, traj: Trajectory, k: int, poses: list[pin.SE3]) -> None:
    """Place the desired-pose ghost of sample ``k`` (from the logged ``object_error``) in animation frame ``view``."""
    error = traj.log["object_error"][k]
    node = view[f"{ROOT}/desired_pose"]
    if not (poses and np.all(np.isfinite(error))):
        node.set_property("visible", "boolean", False)
        return
    pose = poses[0]
    rotation = pin.exp3(-error[3:]) @ pose.rotation  # log(R R_d^T) = e_rot
    node.set_transform(pin.SE3(rotation, pose.translation - error[:3]).homogeneous)
    node.set_property("visible", "boolean", True)


def meshcat_shape(item: RigidObject) -> mg.Geometry | None:
    """The MeshCat geometry of a primitive object (None for a shape MeshCat cannot draw)."""
    if isinstance(item, Box):
        return mg.Box(list(item.size))
    if isinstance(item, Sphere):
        return mg.Sphere(item.radius)
    if isinstance(item, Cylinder | Capsule):
        return None  # along z in coal, along y in three.js: not drawn as a ghost
    return None


__all__ = [
    "CONE_HEIGHT",
    "DISPLAY_FORCE_SCALE",
    "ENVIRONMENT_RGBA",
    "HAND_RGBA",
    "LOOP_FOREVER",
    "MAX_FPS",
    "OBJECT_RGBA",
    "ROOT",
    "animate_ghost",
    "checked_fps",
    "contact_overlays",
    "frame_samples",
    "hidden_overlays",
    "meshcat_shape",
    "object_poses",
    "translation",
]
