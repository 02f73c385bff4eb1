"""Grasp analysis (thesis chapter 5): contact geometry, closure and quality, contact forces, grasp dynamics, sensing.

Modules, one concept each: :mod:`~bhgrasp.grasp.frames` (contact frames, the grasp map G, the hand Jacobian J_h, the
grasp constraint and the conventions they share), :mod:`~bhgrasp.grasp.cones` (friction cones and their inscribed
pyramids), :mod:`~bhgrasp.grasp.quality` (force closure, Ferrari-Canny epsilon, grasp wrench space volume),
:mod:`~bhgrasp.grasp.forces` (the contact-force QP; its Python twin of the compiled solver is the private
``_force_qp``), :mod:`~bhgrasp.grasp.hold_torque` (the least joint torque with which a grasp can hold a wrench),
:mod:`~bhgrasp.grasp.kinematics` (P = J_h^+ G^T and its rate), :mod:`~bhgrasp.grasp.dynamics` (the reduced hand-object
dynamics, the object motions a grasp allows), :mod:`~bhgrasp.grasp.manipulability` (the manipulable
space: which offsets a grasp can make before anything is simulated), :mod:`~bhgrasp.grasp.clearance` (whether an
offset's path clears the support and other fixed shapes), :mod:`~bhgrasp.grasp.path_check` (the fingers followed along
an offset's path: links that meet the object beside the planned contacts, second order), :mod:`~bhgrasp.grasp.sensing`
(per-finger contact forces and reaction torques) and :mod:`~bhgrasp.grasp.metrics` (finger forces and slip events read
back from a trajectory).  Every public name is re-exported here (``from bhgrasp.grasp import grasp_map``).

``import bhgrasp.grasp`` does not import scipy: the force-closure LP, the hold-torque LP and the convex hull import it
when called.
"""

from bhgrasp.grasp.clearance import check_clearance, path_clearance
from bhgrasp.grasp.cones import friction_cone_edges, friction_pyramid, in_friction_cone
from bhgrasp.grasp.dynamics import GraspDynamics, grasp_dynamics, grasp_mobility
from bhgrasp.grasp.forces import (
    ContactForceQP,
    ContactForceResult,
    cone_violations,
    internal_forces,
    pseudo_inverse_forces,
)
from bhgrasp.grasp.frames import (
    TANGENT_SWITCH,
    ZERO_NORMAL,
    contact_frames,
    grasp_constraint_residual,
    grasp_map,
    hand_jacobian,
)
from bhgrasp.grasp.hold_torque import (
    HoldTorque,
    contact_maps,
    grasp_contacts,
    least_hold_torque,
    static_hold_torque,
)
from bhgrasp.grasp.kinematics import (
    GraspKinematics,
    ObjectState,
    contact_kinematics,
    contact_kinematics_python,
    grasp_kinematics,
    parent_joints,
)
from bhgrasp.grasp.manipulability import ManipulableSpace, describe, manipulable_space
from bhgrasp.grasp.metrics import finger_normal_forces, finger_of, slip_events
from bhgrasp.grasp.path_check import path_contacts, sensed_path_contacts
from bhgrasp.grasp.path_result import PathContacts, PathTouch
from bhgrasp.grasp.quality import (
    CLOSURE_TOLERANCE,
    LP_TOLERANCE,
    GraspQuality,
    default_torque_scale,
    ferrari_canny,
    force_closure_margin,
    grasp_quality,
    grasp_wrench_space_volume,
    is_force_closure,
    primitive_wrenches,
)
from bhgrasp.grasp.sensing import ContactSensing, FingerContact

__all__ = [
    "CLOSURE_TOLERANCE",
    "LP_TOLERANCE",
    "TANGENT_SWITCH",
    "ZERO_NORMAL",
    "ContactForceQP",
    "ContactForceResult",
    "ContactSensing",
    "FingerContact",
    "GraspDynamics",
    "GraspKinematics",
    "GraspQuality",
    "HoldTorque",
    "ManipulableSpace",
    "ObjectState",
    "PathContacts",
    "PathTouch",
    "check_clearance",
    "cone_violations",
    "contact_frames",
    "contact_kinematics",
    "contact_kinematics_python",
    "contact_maps",
    "default_torque_scale",
    "describe",
    "ferrari_canny",
    "finger_normal_forces",
    "finger_of",
    "force_closure_margin",
    "friction_cone_edges",
    "friction_pyramid",
    "grasp_constraint_residual",
    "grasp_contacts",
    "grasp_dynamics",
    "grasp_kinematics",
    "grasp_map",
    "grasp_mobility",
    "grasp_quality",
    "grasp_wrench_space_volume",
    "hand_jacobian",
    "in_friction_cone",
    "internal_forces",
    "is_force_closure",
    "least_hold_torque",
    "manipulable_space",
    "parent_joints",
    "path_clearance",
    "path_contacts",
    "primitive_wrenches",
    "pseudo_inverse_forces",
    "sensed_path_contacts",
    "slip_events",
    "static_hold_torque",
]
