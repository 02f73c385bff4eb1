"""Friction cones of frictional point contacts (thesis (5.6)) and the pyramids inscribed in them.

The finger's force on the object in contact i's frame, ``f_i = (f_t1, f_t2, f_n)`` [N]
(:mod:`~bhgrasp.grasp.frames`), must lie in the friction cone ``FC_i = {sqrt(f_t1^2 + f_t2^2) <= mu f_n}``.  Force
closure (:mod:`~bhgrasp.grasp.quality`) and the contact-force QP (:mod:`~bhgrasp.grasp.forces`) replace each cone by
the pyramid with ``facets`` edges inscribed in it, which is conservative: a force inside the pyramid is inside the
cone.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from bhgrasp._validation import as_real, as_vector
from bhgrasp.errors import InputError


def friction_cone_edges(mu: float, facets: int = 8) -> np.ndarray:
    """Unit edges of the pyramid inscribed in the friction cone, contact frame, shape (facets, 3).

    Edge j is ``(mu cos th_j, mu sin th_j, 1) / sqrt(1 + mu^2)`` with ``th_j = 2 pi j / facets``: every edge lies
    on the exact cone, so the pyramid is inside it (conservative).  For ``mu = 0`` all edges are the normal.

    Raises:
        InputError: ``mu`` not finite and >= 0, or ``facets`` not an integer >= 3.
    """
    mu, facets = _mu(mu), _facets(facets)
    angles = 2.0 * np.pi * np.arange(facets) / facets
    edges = np.column_stack([mu * np.cos(angles), mu * np.sin(angles), np.ones(facets)])
    return edges / math.sqrt(1.0 + mu * mu)


def friction_pyramid(mu: float, facets: int = 8) -> tuple[np.ndarray, np.ndarray]:
    """Half-space form ``A f <= b`` (``b = 0``) of the pyramid of :func:`friction_cone_edges`, contact frame.

    Facet j joins edges j and j+1: ``d_j . f_t <= mu cos(pi / facets) f_n`` with ``d_j`` the unit tangent at the
    mid-angle ``2 pi (j + 1/2) / facets``; rows of ``A`` are normalised, so ``A f`` is the signed distance [N]
    of ``f`` to each facet plane.  For ``mu > 0`` the rows imply ``f_n >= 0`` (they sum to a negative multiple of
    ``f_n``); for ``mu = 0`` they only give ``f_t = 0``, and ``f_n >= 0`` must be added by the caller.

    Returns:
        ``(A, b)``: ``A`` (facets, 3) and ``b`` (facets,) zeros.
    """
    mu, facets = _mu(mu), _facets(facets)
    angles = 2.0 * np.pi * (np.arange(facets) + 0.5) / facets
    rows = np.column_stack([np.cos(angles), np.sin(angles), np.full(facets, -mu * math.cos(math.pi / facets))])
    return rows / np.linalg.norm(rows, axis=1, keepdims=True), np.zeros(facets)


def in_friction_cone(f: Any, mu: float, margin: float = 0.0) -> bool:
    """Whether a contact force lies in the exact (second-order) friction cone.

    Tests ``f_n >= 0`` and ``sqrt(f_t1^2 + f_t2^2) <= mu f_n - margin``.

    Args:
        f: Contact force ``(f_t1, f_t2, f_n)`` [N] in the contact frame, shape (3,).
        mu: Friction coefficient, finite and >= 0.
        margin: Required clearance [N] (> 0: strictly inside by that much; < 0: a tolerance).
    """
    f = as_vector(f, "f", 3)
    mu, margin = _mu(mu), as_real(margin, "margin", nonnegative=False)
    return bool(f[2] >= 0.0 and math.hypot(f[0], f[1]) <= mu * f[2] - margin)


def _mu(value: Any) -> float:
    return as_real(value, "mu")


def _facets(value: Any) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 3:
        raise InputError(f"`facets` must be an integer >= 3, got {value!r}")
    return int(value)


__all__ = ["friction_cone_edges", "friction_pyramid", "in_friction_cone"]
