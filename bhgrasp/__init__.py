"""bhgrasp: model, simulate and control a multi-fingered robot hand (the Barrett BH8-280 first, any URDF hand after).

The public API is re-exported here, each name imported when first used (PEP 562): ``import bhgrasp`` loads no
simulator, ``import bhgrasp.controllers`` loads no simulator, and ``import bhgrasp`` never imports matplotlib or
meshcat.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

from bhgrasp.errors import (
    BhgraspError,
    CompiledEngineUnavailable,
    FrozenSettingError,
    InputError,
    ModelError,
    SimulationDiverged,
    UnreachableError,
)
from bhgrasp.ik import ik  # (a name its own module shares: bound now, or importing the module would rebind it)

# public name -> the module that defines it
_EXPORTS = {
    "BarrettActuation": "bhgrasp.sim.actuation",
    "BarrettHand": "bhgrasp.hand",
    "Box": "bhgrasp.objects",
    "Capsule": "bhgrasp.objects",
    "Contact": "bhgrasp.data.contacts",
    "ContactForceQP": "bhgrasp.grasp",
    "ContactForceResult": "bhgrasp.grasp",
    "Cylinder": "bhgrasp.objects",
    "FingerIKResult": "bhgrasp.ik",
    "FixedBox": "bhgrasp.objects",
    "FullyActuated": "bhgrasp.sim.actuation",
    "GraspQuality": "bhgrasp.grasp",
    "Hand": "bhgrasp.hand",
    "IKResult": "bhgrasp.ik",
    "Plane": "bhgrasp.objects",
    "Scene": "bhgrasp.sim.scene",
    "Simulator": "bhgrasp.sim.simulator",
    "SimulatorSettings": "bhgrasp.sim.settings",
    "Sphere": "bhgrasp.objects",
    "SpringDamper": "bhgrasp.sim.contact_law",
    "SpringMounted": "bhgrasp.objects",
    "State": "bhgrasp.data.state",
    "Trajectory": "bhgrasp.data.trajectory",
    "Workspace": "bhgrasp.ik",
    "barrett_urdf_path": "bhgrasp.resources",
    "example_robot_data_dir": "bhgrasp.resources",
    "example_robot_data_urdf": "bhgrasp.resources",
    "ferrari_canny": "bhgrasp.grasp",
    "finger_ik": "bhgrasp.ik",
    "grasp_map": "bhgrasp.grasp",
    "grasp_quality": "bhgrasp.grasp",
    "hand_jacobian": "bhgrasp.grasp",
    "internal_forces": "bhgrasp.grasp",
    "is_force_closure": "bhgrasp.grasp",
    "planar_finger": "bhgrasp.planar",
    "pseudo_inverse_forces": "bhgrasp.grasp",
    "rotation_from_zyz": "bhgrasp.orientation",
    "table": "bhgrasp.objects",
    "thesis_impedance_finger": "bhgrasp.planar",
    "thesis_one_link_finger": "bhgrasp.planar",
    "thesis_two_link_finger": "bhgrasp.planar",
    "wall": "bhgrasp.objects",
    "workspace": "bhgrasp.ik",
    "zyz_from_rotation": "bhgrasp.orientation",
}
_SUBMODULES = ("controllers", "metrics", "trajectories", "tuning")


def __getattr__(name: str) -> Any:
    """Import a public name (or one of the re-exported submodules) on first use."""
    if name in _SUBMODULES:
        return importlib.import_module(f"bhgrasp.{name}")
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'bhgrasp' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(__all__)


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
    "FrozenSettingError",
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
    "SimulatorSettings",
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

if TYPE_CHECKING:  # for type checkers and IDEs: the names as if imported here
    from bhgrasp import controllers, metrics, trajectories, tuning
    from bhgrasp.data.contacts import Contact
    from bhgrasp.data.state import State
    from bhgrasp.data.trajectory import Trajectory
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
    from bhgrasp.sim.actuation import BarrettActuation, FullyActuated
    from bhgrasp.sim.contact_law import SpringDamper
    from bhgrasp.sim.scene import Scene
    from bhgrasp.sim.settings import SimulatorSettings
    from bhgrasp.sim.simulator import Simulator

__version__ = "0.1.0"
