"""The hand and what it grasps, as models.

:class:`~bhgrasp.model.hand.Hand` (URDF loading, kinematics, dynamics), couplings, resources, planar fingers, objects,
the drive's transmission, the wrist mount, orientation maths and inverse kinematics.
"""

from bhgrasp.model.barrett_hand import BarrettHand
from bhgrasp.model.couplings import Coupling, TwinMap
from bhgrasp.model.hand import Hand
from bhgrasp.model.hand_description import BaseFrame
from bhgrasp.model.hand_ik import IKResult, ik
from bhgrasp.model.household_objects import HOUSEHOLD, household, household_mesh
from bhgrasp.model.ik import FingerIKResult, Workspace, finger_ik, workspace
from bhgrasp.model.mesh_object import Mesh
from bhgrasp.model.mount import MOUNT_JOINTS, mount_coordinates, mount_pose, mounted
from bhgrasp.model.objects import (
    Box,
    Capsule,
    Cylinder,
    FixedBox,
    Plane,
    RigidObject,
    Sphere,
    table,
    wall,
)
from bhgrasp.model.orientation import rotation_from_zyz, zyz_from_rotation
from bhgrasp.model.planar import planar_finger, thesis_impedance_finger, thesis_one_link_finger, thesis_two_link_finger
from bhgrasp.model.resources import barrett_urdf_path, example_robot_data_dir, example_robot_data_urdf
from bhgrasp.model.spring_mounted import SpringMounted
from bhgrasp.model.transmission import DirectDrive, Transmission

__all__ = [
    "HOUSEHOLD",
    "MOUNT_JOINTS",
    "BarrettHand",
    "BaseFrame",
    "Box",
    "Capsule",
    "Coupling",
    "Cylinder",
    "DirectDrive",
    "FingerIKResult",
    "FixedBox",
    "Hand",
    "IKResult",
    "Mesh",
    "Plane",
    "RigidObject",
    "Sphere",
    "SpringMounted",
    "Transmission",
    "TwinMap",
    "Workspace",
    "barrett_urdf_path",
    "example_robot_data_dir",
    "example_robot_data_urdf",
    "finger_ik",
    "household",
    "household_mesh",
    "ik",
    "mount_coordinates",
    "mount_pose",
    "mounted",
    "planar_finger",
    "rotation_from_zyz",
    "table",
    "thesis_impedance_finger",
    "thesis_one_link_finger",
    "thesis_two_link_finger",
    "wall",
    "workspace",
    "zyz_from_rotation",
]
