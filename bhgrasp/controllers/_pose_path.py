"""A pose reference as the compiled core takes it (``bhgrasp._core.PosePath``, ``src/pose_path.cpp``).

A :class:`~bhgrasp.motion.pose_references.PoseMotion` or :class:`~bhgrasp.motion.pose_references.PosePath`.  The
compiled path evaluates what the Python reference evaluates, operation for operation (the blend, the position, the
twist and its derivative to the bit), except the rotation exp(b dtheta) R_0, whose 3 x 3 product Eigen sums where
NumPy's matmul calls BLAS: the two agree to round-off.  The wrist servo and the compiled SMC law read it.
"""

from __future__ import annotations

from types import ModuleType
from typing import Any

import numpy as np

from bhgrasp.motion.pose_references import PoseMotion, PosePath


def pose_moves(reference: Any) -> list[PoseMotion] | None:
    """The moves of a plain ``PoseMotion`` (one) or ``PosePath`` (its segments); ``None`` for any other reference."""
    if type(reference) is PosePath:
        return list(reference.segments)
    if type(reference) is PoseMotion:
        return [reference]
    return None


def path_arguments(moves: list[PoseMotion]) -> dict[str, Any]:
    """The moves as the compiled path's (and wrist servo's) keyword arguments: one list or array row per move."""
    return {
        "rotations": [np.array(move.start.rotation) for move in moves],
        "translations": [np.array(move.start.translation) for move in moves],
        "offsets": np.array([move.offset for move in moves]).reshape(len(moves), 6),
        "durations": [move.duration for move in moves],
        "delays": [move.delay for move in moves],
    }


def compiled_path(core: ModuleType, reference: Any) -> Any | None:
    """``core.PosePath`` of ``reference`` (``sample(t)``: rotation, position, twist, derivative), or ``None``.

    ``None`` when it is neither a plain ``PoseMotion`` nor a ``PosePath`` (a subclass may sample otherwise).
    """
    moves = pose_moves(reference)
    return None if moves is None else core.PosePath(**path_arguments(moves))


__all__ = ["compiled_path", "path_arguments", "pose_moves"]
