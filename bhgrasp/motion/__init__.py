"""Motion references.

Joint and Cartesian references (:mod:`~bhgrasp.motion.trajectories`), SE(3) paths (:mod:`~bhgrasp.motion.paths`),
persistent excitation (:mod:`~bhgrasp.motion.excitation`) and the wrist's reference in mount coordinates
(:mod:`~bhgrasp.motion.wrist`).
"""

from bhgrasp.motion.excitation import PoseExcitation
from bhgrasp.motion.fingertip_reference import CartesianReference
from bhgrasp.motion.paths import PoseCircle, PoseWaypoints
from bhgrasp.motion.pose_references import PoseMotion, PosePath
from bhgrasp.motion.trajectories import Constant, Quintic, Reference, Sample, Sinusoid, SmoothStep, exponential_approach
from bhgrasp.motion.wrist import MountReference

__all__ = [
    "CartesianReference",
    "Constant",
    "MountReference",
    "PoseCircle",
    "PoseExcitation",
    "PoseMotion",
    "PosePath",
    "PoseWaypoints",
    "Quintic",
    "Reference",
    "Sample",
    "Sinusoid",
    "SmoothStep",
    "exponential_approach",
]
