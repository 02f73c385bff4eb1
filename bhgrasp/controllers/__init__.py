"""Controllers: joint space (PD + gravity, computed torque), fingertip space, sliding mode and its higher orders."""

from bhgrasp.controllers.base import Controller, JointTracking, inertia_gain
from bhgrasp.controllers.design import SlidingGains, sliding_gains
from bhgrasp.controllers.grasping import GraspForceController
from bhgrasp.controllers.hosm import QuasiContinuousA, SuperTwisting, TwistingB, hosm
from bhgrasp.controllers.joint import ComputedTorque, PDGravity
from bhgrasp.controllers.sliding import AdaptiveSlidingMode, SlidingMode, SlidingSurface, lyapunov, parameter_scales
from bhgrasp.controllers.workspace import WorkspaceComputedTorque, WorkspaceDynamics, workspace_dynamics

__all__ = [
    "AdaptiveSlidingMode",
    "ComputedTorque",
    "Controller",
    "GraspForceController",
    "JointTracking",
    "PDGravity",
    "QuasiContinuousA",
    "SlidingGains",
    "SlidingMode",
    "SlidingSurface",
    "SuperTwisting",
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
