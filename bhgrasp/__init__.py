"""bhgrasp: model, simulate and control a multi-fingered robot hand (the Barrett BH8-280 first, any URDF hand after).

The public API is re-exported here; ``import bhgrasp`` never imports matplotlib or meshcat.
"""

from bhgrasp.errors import BhgraspError, InputError, ModelError, UnreachableError
from bhgrasp.hand import BarrettHand, Hand
from bhgrasp.ik import FingerIKResult, IKResult, Workspace, finger_ik, ik, workspace
from bhgrasp.planar import planar_finger, thesis_impedance_finger, thesis_one_link_finger, thesis_two_link_finger
from bhgrasp.resources import barrett_urdf_path, example_robot_data_dir, example_robot_data_urdf

__all__ = [
    "BarrettHand",
    "BhgraspError",
    "FingerIKResult",
    "Hand",
    "IKResult",
    "InputError",
    "ModelError",
    "UnreachableError",
    "Workspace",
    "barrett_urdf_path",
    "example_robot_data_dir",
    "example_robot_data_urdf",
    "finger_ik",
    "ik",
    "planar_finger",
    "thesis_impedance_finger",
    "thesis_one_link_finger",
    "thesis_two_link_finger",
    "workspace",
]

__version__ = "0.1.0"
