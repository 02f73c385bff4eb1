"""bhgrasp: model, simulate and control a multi-fingered robot hand (the Barrett BH8-280 first, any URDF hand after).

The public API is re-exported here; ``import bhgrasp`` never imports matplotlib or meshcat.
"""

from bhgrasp.errors import BhgraspError, InputError, ModelError, UnreachableError
from bhgrasp.hand import BarrettHand, Hand
from bhgrasp.resources import barrett_urdf_path, example_robot_data_dir, example_robot_data_urdf

__all__ = [
    "BarrettHand",
    "BhgraspError",
    "Hand",
    "InputError",
    "ModelError",
    "UnreachableError",
    "barrett_urdf_path",
    "example_robot_data_dir",
    "example_robot_data_urdf",
]

__version__ = "0.1.0"
