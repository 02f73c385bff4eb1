"""Moved to :mod:`bhgrasp.grasp.metrics` (finger forces, slip events); this module re-exports its public names."""

from bhgrasp.grasp.metrics import finger_normal_forces, finger_of, slip_events

__all__ = ["finger_normal_forces", "finger_of", "slip_events"]
