"""Free-body rotation for the integrators: the gyroscopic torque and its implicit-midpoint form.

A free body turns under ``I w_dot + w x I w = tau`` (body frame).  The explicit ``w x I w`` gains energy at every
step; :func:`spin_midpoint` solves the implicit-midpoint step of torque-free spin, which keeps the kinetic energy and
``|I w|`` exactly at any step.  The Simulator's implicit and semi-implicit steps use the torque at that midpoint
(``src/integrators.cpp`` mirrors both functions).
"""

from __future__ import annotations

import numpy as np


def gyroscopic_torque(moments: tuple[float, float, float], w: np.ndarray) -> np.ndarray:
    """``w x I w`` [N m] in the principal axes, ``I = diag(moments)``."""
    a, b, c = moments
    w0, w1, w2 = w
    return np.array([(c - b) * w1 * w2, (a - c) * w2 * w0, (b - a) * w0 * w1])


def spin_midpoint(moments: tuple[float, float, float], w: np.ndarray, h: float) -> np.ndarray:
    """The midpoint ``m`` of an implicit-midpoint step of torque-free spin: ``I m + h m x I m = I w``, ``h = dt/2``.

    Newton from ``m = w`` in the principal axes (``I = diag(moments)``), with the 3x3 solve by Cramer's rule:
    plain floats, as this runs every step for every free body.  Converges in 2-4 iterations at ``|w| dt < 1``.
    """
    a, b, c = moments
    w0, w1, w2 = (float(x) for x in w)
    m0, m1, m2 = w0, w1, w2
    p, q, r = h * (c - b), h * (a - c), h * (b - a)
    for _ in range(30):
        f0 = a * (m0 - w0) + p * m1 * m2
        f1 = b * (m1 - w1) + q * m2 * m0
        f2 = c * (m2 - w2) + r * m0 * m1
        j01, j02, j10, j12, j20, j21 = p * m2, p * m1, q * m2, q * m0, r * m1, r * m0
        c0, c1, c2 = b * c - j12 * j21, j12 * j20 - j10 * c, j10 * j21 - b * j20  # cofactors of row 0
        det = a * c0 + j01 * c1 + j02 * c2
        d0 = (f0 * c0 + j01 * (j12 * f2 - f1 * c) + j02 * (f1 * j21 - b * f2)) / det
        d1 = (a * (f1 * c - j12 * f2) + f0 * c1 + j02 * (j10 * f2 - f1 * j20)) / det
        d2 = (a * (b * f2 - f1 * j21) + j01 * (f1 * j20 - j10 * f2) + f0 * c2) / det
        m0, m1, m2 = m0 - d0, m1 - d1, m2 - d2
        if max(abs(d0), abs(d1), abs(d2)) <= 1e-16 * (1.0 + max(abs(m0), abs(m1), abs(m2))):
            break
    return np.array([m0, m1, m2])


Spinning = tuple[tuple[slice, np.ndarray, tuple[float, float, float]], ...]  # SceneLayout.spinning_bodies


def implicit_gyroscopic(bias: np.ndarray, v: np.ndarray, spinning: Spinning, dt: float) -> None:
    """Replace each free body's explicit gyroscopic torque ``w x I w`` in ``bias`` by the implicit midpoint one.

    The torque-free spin over the step solves ``I (w+ - w) / dt + m x I m = 0`` with ``m = (w + w+) / 2``
    (Newton, to round-off); dotting with ``m`` and ``I m`` shows that it keeps the kinetic energy
    ``w.I w / 2`` and the body angular momentum's length ``|I w|`` exactly, at any step (explicit ``w x I w``
    gains energy at every step).  The step then uses ``m x I m`` as the body's gyroscopic torque.  ``spinning``:
    each free body's angular velocity slice, principal axes (columns) and moments.
    """
    for angular, axes, moments in spinning:
        w = axes.T @ v[angular]  # in the principal axes
        if moments[0] == moments[1] == moments[2] or not w.any():
            continue  # a sphere's (or a resting body's) gyroscopic torque is 0
        explicit = gyroscopic_torque(moments, w)
        middle = spin_midpoint(moments, w, 0.5 * dt)
        bias[angular] += axes @ (gyroscopic_torque(moments, middle) - explicit)


def increment_rate(increment: np.ndarray, v: np.ndarray, spinning: Spinning) -> np.ndarray:
    """Rate of the increment ``theta`` in ``q (+) theta`` at velocity ``v``.

    A body's rotation ``R exp(theta)`` turns at body rate ``w`` when ``theta`` changes at
    ``dexp^-1_{-theta}(w) = w + theta x w / 2 + theta x (theta x w) / 12`` (to O(theta^3), enough for RK4); hand
    joints and translations are vector spaces, whose increments change at ``v``.
    """
    rate = v.copy()
    for angular, _, _ in spinning:
        theta, w = increment[angular], v[angular]
        half = np.cross(theta, w)
        rate[angular] = w + 0.5 * half + np.cross(theta, half) / 12.0
    return rate


__all__ = ["gyroscopic_torque", "implicit_gyroscopic", "increment_rate", "spin_midpoint"]
