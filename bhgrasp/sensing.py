"""Moved to :mod:`bhgrasp.grasp.sensing` (per-finger contacts); this module re-exports its public names."""

from bhgrasp.grasp.sensing import ContactSensing, FingerContact

__all__ = ["ContactSensing", "FingerContact"]
