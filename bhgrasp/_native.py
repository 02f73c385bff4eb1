"""The compiled extension ``bhgrasp._core``, when it loads: one loader for the kernels that have a Python twin.

A module of its own, outside :mod:`bhgrasp.sim`, so that the model, grasp and controller modules use the compiled
kernels without importing the simulator (DESIGN.md: controllers never import the simulator).
"""

from __future__ import annotations

from types import ModuleType


def optional_core() -> ModuleType | None:
    """``bhgrasp._core``, or ``None`` when it does not load (the callers then run their Python twins)."""
    try:
        from bhgrasp import _core
    except ImportError:
        return None
    return _core


__all__ = ["optional_core"]
