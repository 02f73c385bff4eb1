"""Orientation conversions for reporting: the thesis' Z-Y-Z Euler angles (thesis 2.7).

bhgrasp integrates orientations on SO(3) (quaternions in ``q``, no singularity); these functions only convert for
display and comparison with the thesis.  Convention: ``R = Rz(phi) Ry(theta) Rz(psi)`` (intrinsic Z-Y-Z), with
``theta`` in [0, pi].  At the gimbal singularity (theta = 0 or pi, the thesis' own initial orientation, where its
(2.44) divides by sin(theta)) only phi + psi (or phi - psi) is defined: we return psi = 0.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from bhgrasp._validation import as_array, as_vector

_SINGULAR = 1e-9


def zyz_from_rotation(rotation: Any) -> np.ndarray:
    """Z-Y-Z Euler angles (phi, theta, psi) [rad] of a rotation matrix, theta in [0, pi]."""
    r = as_array(rotation, "rotation", (3, 3))
    theta = float(np.arctan2(np.hypot(r[0, 2], r[1, 2]), r[2, 2]))
    if np.sin(theta) > _SINGULAR:
        return np.array([np.arctan2(r[1, 2], r[0, 2]), theta, np.arctan2(r[2, 1], -r[2, 0])])
    if r[2, 2] > 0:  # theta = 0: R = Rz(phi + psi)
        return np.array([np.arctan2(r[1, 0], r[0, 0]), 0.0, 0.0])
    return np.array([np.arctan2(-r[1, 0], -r[0, 0]), np.pi, 0.0])  # theta = pi: R = Rz(phi - psi) Ry(pi)


def rotation_from_zyz(angles: Any) -> np.ndarray:
    """Rotation matrix ``Rz(phi) Ry(theta) Rz(psi)`` of Z-Y-Z Euler angles [rad]."""
    phi, theta, psi = as_vector(angles, "angles", 3)
    return _rz(phi) @ _ry(theta) @ _rz(psi)


def _rz(angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _ry(angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])
