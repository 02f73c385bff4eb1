"""What the grasp demo's controller does not know: the uncertainties a real set-up has, as demo arguments.

Sensor noise and delay, joint friction, torque limits and a wrong friction coefficient, as keyword arguments of
:func:`~bhgrasp.scenarios.grasp_demo.run_grasp_demo`.

Sensors (:class:`~bhgrasp.sim.sensor_model.SensorModel`, the controller reads through them):

- ``pose_noise`` = (sigma [m], sigma [rad]): the object tracker's position and orientation;
- ``twist_noise`` = (sigma [m/s], sigma [rad/s]): its linear and angular velocity;
- ``force_noise`` = sigma [N]: each component of each measured contact force;
- ``delay`` [s]: the age of every reading (joints, object, contacts);
- ``tracker_rate`` [Hz] and ``tracker_latency`` [s]: the object's readings come from a tracker's frames, taken at
  that rate and delivered that late (:class:`~bhgrasp.sim.sensor_model.SensorModel`).

Plant (the simulated hand and box, not the controller's model):

- ``joint_friction`` [N m]: Coulomb friction on every joint; ``joint_damping`` [N m s/rad]: viscous (default 0.05);
- ``torque_limit`` [N m]: each joint torque is clipped to it;
- ``friction``: the true friction coefficient of the box, its pedestal and the pads (default 0.8).

Controller: ``mu``, the friction coefficient its force distribution assumes (default 0.6).

The true final error (:func:`final_pose_error`) compares the object's true pose with the requested motion; the
controller's own logged error is what it sensed, against the motion it planned.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pinocchio as pin

from bhgrasp._validation import as_positive, as_real, as_vector
from bhgrasp.errors import InputError
from bhgrasp.motion.pose_references import PoseMotion
from bhgrasp.sim.sensor_model import SensorModel

SENSED = ("pose_noise", "twist_noise", "force_noise", "delay", "tracker_rate", "tracker_latency")
PLANT = ("friction", "joint_friction", "joint_damping", "torque_limit")
UNCERTAINTIES = (*SENSED, *PLANT, "mu")


def check_uncertainty(**values: Any) -> None:
    """Check uncertainty arguments (names in :data:`UNCERTAINTIES`) without running anything.

    Raises:
        InputError: An unknown name, or a value of the wrong shape or range; the message names it.
    """
    unknown = sorted(set(values) - set(UNCERTAINTIES))
    if unknown:
        raise InputError(f"no uncertainty {unknown[0]!r}; the grasp demo takes {', '.join(UNCERTAINTIES)}")
    for name in ("pose_noise", "twist_noise"):
        if name in values:
            sigma = as_vector(values[name], name, 2)
            if (sigma < 0.0).any():
                raise InputError(f"`{name}` standard deviations must be >= 0, got {sigma.tolist()}")
    for name in ("force_noise", "delay", "joint_friction", "joint_damping", "tracker_rate", "tracker_latency"):
        if name in values:
            as_real(values[name], name)
    for name in ("friction", "mu", "torque_limit"):
        if name in values and values[name] is not None:
            as_positive(values[name], name)


def sensor_model(sensor_noise: Any = None, **sensed: Any) -> SensorModel:
    """The demo's :class:`~bhgrasp.sim.sensor_model.SensorModel`: joint noise (sigma_q, sigma_v) and :data:`SENSED`."""
    check_uncertainty(**sensed)
    joints = (0.0, 0.0) if sensor_noise is None else as_vector(sensor_noise, "sensor_noise", 2)
    pose = as_vector(sensed.get("pose_noise", (0.0, 0.0)), "pose_noise", 2)
    twist = as_vector(sensed.get("twist_noise", (0.0, 0.0)), "twist_noise", 2)
    return SensorModel(
        joint_position=joints[0],
        joint_velocity=joints[1],
        object_position=pose[0],
        object_rotation=pose[1],
        object_velocity=twist[0],
        object_angular_velocity=twist[1],
        contact_force=sensed.get("force_noise", 0.0),
        delay=sensed.get("delay", 0.0),
        tracker_rate=sensed.get("tracker_rate", 0.0),
        tracker_latency=sensed.get("tracker_latency", 0.0),
    )


def final_pose_error(trajectory, supervisor) -> np.ndarray:
    """The object's true pose error (x - x_d [m], log(R R_d^T) [rad], world) at the trajectory's last sample.

    The target is the *requested* motion (the supervisor's ``offset`` from the pose the grasp caught), not the one
    it planned and tracked (which drops what the grasp cannot make); NaN when the controller never held the object.
    """
    grasp = supervisor.grasp
    reference, t = grasp.reference, float(trajectory.t[-1])
    if reference is None:
        return np.full(6, np.nan)
    if isinstance(reference, PoseMotion):
        sample = PoseMotion(reference.start, supervisor.offset, reference.duration, reference.delay)(t)[0]
        target = pin.SE3(pin.exp3(sample[3:]), sample[:3])
    else:  # another kind of reference: the one tracked
        target = grasp.target(t)[0]
    x, y, z, w = trajectory.object_quaternion[-1, 0]
    rotation = pin.Quaternion(w, x, y, z).toRotationMatrix()
    position = trajectory.object_position[-1, 0]
    return np.concatenate((position - target.translation, pin.log3(rotation @ target.rotation.T)))


__all__ = ["PLANT", "SENSED", "UNCERTAINTIES", "check_uncertainty", "final_pose_error", "sensor_model"]
