"""Moved to :mod:`bhgrasp.grasp.kinematics` (P, P_dot) and :mod:`bhgrasp.grasp.dynamics`; re-exports their names."""

from bhgrasp.grasp.dynamics import GraspDynamics, grasp_dynamics, grasp_mobility
from bhgrasp.grasp.kinematics import (
    GraspKinematics,
    ObjectState,
    contact_kinematics,
    contact_kinematics_python,
    grasp_kinematics,
    parent_joints,
)

__all__ = [
    "GraspDynamics",
    "GraspKinematics",
    "ObjectState",
    "contact_kinematics",
    "contact_kinematics_python",
    "grasp_dynamics",
    "grasp_kinematics",
    "grasp_mobility",
    "parent_joints",
]
