"""bhgrasp: model, simulate and control a multi-fingered robot hand (the Barrett BH8-280 first, any URDF hand after).

The public API is re-exported here; ``import bhgrasp`` never imports matplotlib or meshcat.
"""

from bhgrasp import controllers, metrics, trajectories, tuning
from bhgrasp.errors import (
    BhgraspError,
    CompiledEngineUnavailable,
    InputError,
    ModelError,
    SimulationDiverged,
    UnreachableError,
)
from bhgrasp.grasp import (
    ContactForceQP,
    ContactForceResult,
    GraspQuality,
    ferrari_canny,
    grasp_map,
    grasp_quality,
    hand_jacobian,
    internal_forces,
    is_force_closure,
    pseudo_inverse_forces,
)
from bhgrasp.hand import BarrettHand, Hand
from bhgrasp.ik import FingerIKResult, IKResult, Workspace, finger_ik, ik, workspace
from bhgrasp.objects import Box, Capsule, Cylinder, FixedBox, Plane, Sphere, SpringMounted, table, wall
from bhgrasp.orientation import rotation_from_zyz, zyz_from_rotation
from bhgrasp.planar import planar_finger, thesis_impedance_finger, thesis_one_link_finger, thesis_two_link_finger
from bhgrasp.resources import barrett_urdf_path, example_robot_data_dir, example_robot_data_urdf
from bhgrasp.sim import Simulator
from bhgrasp.sim.actuation import BarrettActuation, FullyActuated
from bhgrasp.sim.contact import Contact, SpringDamper
from bhgrasp.sim.scene import Scene
from bhgrasp.sim.state import State, Trajectory

__all__ = [
    "BarrettActuation",
    "BarrettHand",
    "BhgraspError",
    "Box",
    "Capsule",
    "CompiledEngineUnavailable",
    "Contact",
    "ContactForceQP",
    "ContactForceResult",
    "Cylinder",
    "FingerIKResult",
    "FixedBox",
    "FullyActuated",
    "GraspQuality",
    "Hand",
    "IKResult",
    "InputError",
    "ModelError",
    "Plane",
    "Scene",
    "SimulationDiverged",
    "Simulator",
    "Sphere",
    "SpringDamper",
    "SpringMounted",
    "State",
    "Trajectory",
    "UnreachableError",
    "Workspace",
    "barrett_urdf_path",
    "controllers",
    "example_robot_data_dir",
    "example_robot_data_urdf",
    "ferrari_canny",
    "finger_ik",
    "grasp_map",
    "grasp_quality",
    "hand_jacobian",
    "ik",
    "internal_forces",
    "is_force_closure",
    "metrics",
    "planar_finger",
    "pseudo_inverse_forces",
    "rotation_from_zyz",
    "table",
    "thesis_impedance_finger",
    "thesis_one_link_finger",
    "thesis_two_link_finger",
    "trajectories",
    "tuning",
    "wall",
    "workspace",
    "zyz_from_rotation",
]

__version__ = "0.1.0"
