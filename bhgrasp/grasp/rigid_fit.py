"""The rigid motion that best carries one set of points onto another, and how far a point set is from a line."""

from __future__ import annotations

import numpy as np


def rigid_fit(before: np.ndarray, after: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(A, b) minimising sum |A before_i + b - after_i|^2 over rotations A (Kabsch: SVD of the cross-covariance).

    ``before``, ``after``: (n, 3) points [m], n >= 3 and not on one line.
    """
    centre_a, centre_b = before.mean(axis=0), after.mean(axis=0)
    u, _, vt = np.linalg.svd((after - centre_b).T @ (before - centre_a))
    sign = np.sign(np.linalg.det(u @ vt)) or 1.0  # a proper rotation, never a reflection
    rotation = u @ np.diag((1.0, 1.0, sign)) @ vt
    return rotation, centre_b - rotation @ centre_a


def span(points: np.ndarray) -> float:
    """The least distance [m] of a point from the line through the two farthest apart (0 for fewer than 3)."""
    if len(points) < 3:
        return 0.0
    gaps = np.linalg.norm(points[:, None] - points[None], axis=-1)
    i, j = np.unravel_index(np.argmax(gaps), gaps.shape)
    axis = (points[j] - points[i]) / max(gaps[i, j], 1e-300)
    offsets = points - points[i]
    off_line = offsets - np.outer(offsets @ axis, axis)
    others = [k for k in range(len(points)) if k not in (i, j)]
    return float(np.max(np.linalg.norm(off_line[others], axis=1)))


__all__ = ["rigid_fit", "span"]
