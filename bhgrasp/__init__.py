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
    NotSettled,
    SimulationDiverged,
    SolverFailed,
    UnreachableError,
)

# public name -> the module that defines it
_EXPORTS = {
    "BarrettActuation": "bhgrasp.sim.actuation",
    "BarrettHand": "bhgrasp.model.barrett_hand",
    "Box": "bhgrasp.model.objects",
    "Capsule": "bhgrasp.model.objects",
    "Contact": "bhgrasp.data.contacts",
    "ContactForceQP": "bhgrasp.grasp",
    "ContactForceResult": "bhgrasp.grasp",
    "Cylinder": "bhgrasp.model.objects",
    "FingerIKResult": "bhgrasp.model.ik",
    "FixedBox": "bhgrasp.model.objects",
    "FullyActuated": "bhgrasp.sim.actuation",
    "GraspQuality": "bhgrasp.grasp",
    "Hand": "bhgrasp.model.hand",
    "IKResult": "bhgrasp.model.hand_ik",
    "Mesh": "bhgrasp.model.mesh_object",
    "Plane": "bhgrasp.model.objects",
    "Scene": "bhgrasp.sim.scene",
    "Simulator": "bhgrasp.sim.simulator",
    "SimulatorSettings": "bhgrasp.sim.settings",
    "Sphere": "bhgrasp.model.objects",
    "SpringDamper": "bhgrasp.sim.contact_law",
    "SpringMounted": "bhgrasp.model.spring_mounted",
    "State": "bhgrasp.data.state",
    "Trajectory": "bhgrasp.data.trajectory",
    "Workspace": "bhgrasp.model.ik",
    "barrett_urdf_path": "bhgrasp.model.resources",
    "example_robot_data_dir": "bhgrasp.model.resources",
    "example_robot_data_urdf": "bhgrasp.model.resources",
    "ferrari_canny": "bhgrasp.grasp",
    "finger_ik": "bhgrasp.model.ik",
    "grasp_map": "bhgrasp.grasp",
    "grasp_quality": "bhgrasp.grasp",
    "hand_jacobian": "bhgrasp.grasp",
    "household": "bhgrasp.model.household_objects",
    "ik": "bhgrasp.model.hand_ik",
    "internal_forces": "bhgrasp.grasp",
    "is_force_closure": "bhgrasp.grasp",
    "planar_finger": "bhgrasp.model.planar",
    "pseudo_inverse_forces": "bhgrasp.grasp",
    "rotation_from_zyz": "bhgrasp.model.orientation",
    "table": "bhgrasp.model.objects",
    "thesis_impedance_finger": "bhgrasp.model.planar",
    "thesis_one_link_finger": "bhgrasp.model.planar",
    "thesis_two_link_finger": "bhgrasp.model.planar",
    "wall": "bhgrasp.model.objects",
    "workspace": "bhgrasp.model.ik",
    "zyz_from_rotation": "bhgrasp.model.orientation",
}
_SUBMODULES = ("controllers", "metrics", "motion", "tuning")


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
    "Mesh",
    "ModelError",
    "NotSettled",
    "Plane",
    "Scene",
    "SimulationDiverged",
    "Simulator",
    "SimulatorSettings",
    "SolverFailed",
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
    "household",
    "ik",
    "internal_forces",
    "is_force_closure",
    "metrics",
    "motion",
    "planar_finger",
    "pseudo_inverse_forces",
    "rotation_from_zyz",
    "table",
    "thesis_impedance_finger",
    "thesis_one_link_finger",
    "thesis_two_link_finger",
    "tuning",
    "wall",
    "workspace",
    "zyz_from_rotation",
]

if TYPE_CHECKING:  # for type checkers and IDEs: the names as if imported here
    from bhgrasp import controllers, metrics, motion, tuning
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
    from bhgrasp.model.barrett_hand import BarrettHand
    from bhgrasp.model.hand import Hand
    from bhgrasp.model.hand_ik import IKResult, ik
    from bhgrasp.model.household_objects import household
    from bhgrasp.model.ik import FingerIKResult, Workspace, finger_ik, workspace
    from bhgrasp.model.mesh_object import Mesh
    from bhgrasp.model.objects import Box, Capsule, Cylinder, FixedBox, Plane, Sphere, table, wall
    from bhgrasp.model.orientation import rotation_from_zyz, zyz_from_rotation
    from bhgrasp.model.planar import (
        planar_finger,
        thesis_impedance_finger,
        thesis_one_link_finger,
        thesis_two_link_finger,
    )
    from bhgrasp.model.resources import barrett_urdf_path, example_robot_data_dir, example_robot_data_urdf
    from bhgrasp.model.spring_mounted import SpringMounted
    from bhgrasp.sim.actuation import BarrettActuation, FullyActuated
    from bhgrasp.sim.contact_law import SpringDamper
    from bhgrasp.sim.scene import Scene
    from bhgrasp.sim.settings import SimulatorSettings
    from bhgrasp.sim.simulator import Simulator

__version__ = "0.1.0"
