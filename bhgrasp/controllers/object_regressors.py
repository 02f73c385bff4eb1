"""The grasped object's dynamics, linear in its parameters sigma_o = (m, I_xx, I_xy, I_xz, I_yy, I_yz, I_zz).

sigma_o holds the mass [kg] and the body-frame inertia about the COM [kg m^2].  Two regressors, world axes at the COM:

- :func:`object_regressor`: Y_o with Y_o sigma_o = M_o a_r + C_o(omega) v_r + N_o, the wrench of thesis (5.50) with
  the Coriolis form C(omega, I_w) = (skew(omega) I_w - I_w skew(omega) - skew(I_w omega)) / 2, for which
  M_o_dot - 2 C_o is skew-symmetric (the Lyapunov argument (5.63) needs it);
- :func:`momentum_regressor`: H with H sigma_o = (m v, I_w omega), the momentum, whose time derivative (plus -m g) is
  the wrench on the object (the composite law of :mod:`bhgrasp.controllers.object_identification` filters it).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pinocchio as pin

from bhgrasp._native import default_core

# Body-frame inertia basis B_k matching sigma_o[1:] = (I_xx, I_xy, I_xz, I_yy, I_yz, I_zz).
_INERTIA_BASIS = np.zeros((6, 3, 3))
for _k, (_i, _j) in enumerate([(0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2)]):
    _INERTIA_BASIS[_k, _i, _j] = _INERTIA_BASIS[_k, _j, _i] = 1.0


def object_parameters(mass: float, inertia: Any) -> np.ndarray:
    """sigma_o = (m, I_xx, I_xy, I_xz, I_yy, I_yz, I_zz) from a mass [kg] and a body inertia [kg m^2]."""
    inertia = np.asarray(inertia, dtype=float)
    return np.array([mass, inertia[0, 0], inertia[0, 1], inertia[0, 2], inertia[1, 1], inertia[1, 2], inertia[2, 2]])


def object_regressor(rotation: Any, twist: Any, v_r: Any, a_r: Any, gravity: Any) -> np.ndarray:
    """Y_o (6, 7) with Y_o sigma_o = M_o a_r + C_o(omega) v_r + N_o at the COM (world; see the module docstring).

    Computed by the compiled kernel (``src/sensing.cpp``) on the default engine (:mod:`bhgrasp._native`), by
    its readable twin :func:`object_regressor_python` (the same sums; tests/test_sensing_kernels.py holds them
    together).
    """
    rotation, omega = np.asarray(rotation, dtype=float), np.asarray(twist, dtype=float)[3:]
    v_r, a_r = np.asarray(v_r, dtype=float), np.asarray(a_r, dtype=float)
    core = default_core()
    if core is None:
        return object_regressor_python(rotation, twist, v_r, a_r, gravity)
    return core.object_regressor(rotation, omega, v_r, a_r, np.asarray(gravity, dtype=float))


def object_regressor_python(rotation: Any, twist: Any, v_r: Any, a_r: Any, gravity: Any) -> np.ndarray:
    """:func:`object_regressor` in NumPy (the readable twin of the compiled kernel)."""
    rotation, omega = np.asarray(rotation, dtype=float), np.asarray(twist, dtype=float)[3:]
    v_r, a_r = np.asarray(v_r, dtype=float), np.asarray(a_r, dtype=float)
    regressor = np.zeros((6, 7))
    regressor[:3, 0] = a_r[:3] - np.asarray(gravity, dtype=float)
    inertias = np.einsum("ij,kjl,ml->kim", rotation, _INERTIA_BASIS, rotation)  # R B_k R^T, (6, 3, 3)
    w, alpha = v_r[3:], a_r[3:]
    # column k: I_k alpha + C_k w with C_k = (skew(omega) I_k - I_k skew(omega) - skew(I_k omega)) / 2
    omega_skew = pin.skew(omega)
    coriolis = (inertias @ w) @ omega_skew.T - inertias @ (omega_skew @ w) + (inertias @ omega) @ pin.skew(w).T
    regressor[3:, 1:] = (inertias @ alpha + 0.5 * coriolis).T
    return regressor


def momentum_regressor(rotation: Any, twist: Any) -> np.ndarray:
    """H (6, 7) with H sigma_o = (m v, I_w omega): the object's momentum [kg m/s, kg m^2/s] (world, COM)."""
    rotation, twist = np.asarray(rotation, dtype=float), np.asarray(twist, dtype=float)
    momentum = np.zeros((6, 7))
    momentum[:3, 0] = twist[:3]
    momentum[3:, 1:] = rotation @ (_INERTIA_BASIS @ (rotation.T @ twist[3:])).T
    return momentum


__all__ = ["momentum_regressor", "object_parameters", "object_regressor", "object_regressor_python"]
