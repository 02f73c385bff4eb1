"""Controllers: each a callable ``(t, state) -> u`` that knows a nominal hand and never the simulator.

Joint space (PD + gravity, computed torque), fingertip space, sliding mode and its higher orders, force impedance,
object-space and grasp laws (the SMC-adaptive grasp, object identification), the grasp supervisor and the wrist servo.
"""

from bhgrasp.controllers.adaptive_grasp import SMCAdaptiveGrasp
from bhgrasp.controllers.adaptive_impedance import AdaptiveForceImpedance
from bhgrasp.controllers.base import Controller, JointTracking, inertia_gain
from bhgrasp.controllers.design import SlidingGains, sliding_gains
from bhgrasp.controllers.grasp_force import GraspForceController
from bhgrasp.controllers.grasp_options import GraspOptions
from bhgrasp.controllers.grasping import ObjectGraspController
from bhgrasp.controllers.hosm import QuasiContinuousA, SuperTwisting, TwistingB, hosm
from bhgrasp.controllers.impedance import (
    ForceImpedance,
    ImpedanceLaw,
    PositionImpedance,
)
from bhgrasp.controllers.impedance_controller import ImpedanceController
from bhgrasp.controllers.impedance_filter import ImpedanceFilter, TustinImpedanceFilter
from bhgrasp.controllers.joint import ComputedTorque, PDGravity
from bhgrasp.controllers.motor_commands import MotorCommands
from bhgrasp.controllers.mount import MountServo
from bhgrasp.controllers.object_identification import ObjectIdentification
from bhgrasp.controllers.object_space import ObjectSpaceController
from bhgrasp.controllers.sliding import AdaptiveSlidingMode, SlidingMode, SlidingSurface, lyapunov, parameter_scales
from bhgrasp.controllers.supervisor import GraspSupervisor
from bhgrasp.controllers.supervisor_options import Approach, Planning
from bhgrasp.controllers.workspace import WorkspaceComputedTorque, WorkspaceDynamics, workspace_dynamics

__all__ = [
    "AdaptiveForceImpedance",
    "AdaptiveSlidingMode",
    "Approach",
    "ComputedTorque",
    "Controller",
    "ForceImpedance",
    "GraspForceController",
    "GraspOptions",
    "GraspSupervisor",
    "ImpedanceController",
    "ImpedanceFilter",
    "ImpedanceLaw",
    "JointTracking",
    "MotorCommands",
    "MountServo",
    "ObjectGraspController",
    "ObjectIdentification",
    "ObjectSpaceController",
    "PDGravity",
    "Planning",
    "PositionImpedance",
    "QuasiContinuousA",
    "SMCAdaptiveGrasp",
    "SlidingGains",
    "SlidingMode",
    "SlidingSurface",
    "SuperTwisting",
    "TustinImpedanceFilter",
    "TwistingB",
    "WorkspaceComputedTorque",
    "WorkspaceDynamics",
    "hosm",
    "inertia_gain",
    "lyapunov",
    "parameter_scales",
    "sliding_gains",
    "workspace_dynamics",
]
