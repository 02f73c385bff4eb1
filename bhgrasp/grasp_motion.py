"""Moved to :mod:`bhgrasp.grasp.manipulability` (the manipulable space); this module re-exports its public names."""

from bhgrasp.grasp.manipulability import (  # noqa: F401  (the tolerances, as before)
    RANK_TOLERANCE,
    SLIDE_TOLERANCE,
    ManipulableSpace,
    describe,
    manipulable_space,
)

__all__ = ["ManipulableSpace", "describe", "manipulable_space"]
