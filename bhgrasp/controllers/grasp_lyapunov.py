"""The Lyapunov function of the SMC-adaptive grasp, thesis (5.63), evaluated from a run.

Its object part, for a law with sliding error s_o = X_dot - v_r (world twist at the COM) and estimate error
Delta sigma = sigma_hat - sigma over the parameters it learns,

    V_o = 1/2 s_o^T M_o s_o + 1/2 Delta sigma^T P^-1 Delta sigma,       M_o = diag(m I_3, R I R^T),

with P^-1 = Gamma_o^-1 for the thesis' law (5.52) and the growing information of the composite law
(:mod:`bhgrasp.controllers.object_identification`).  When the object receives exactly the commanded wrench F_do,
V_o_dot = -s_o^T k_o s_o (- 1/2 |W Delta sigma|_Q^2 for the composite law).  In a grasp it receives the contacts'
wrench F_c, and V_o_dot gains s_o^T (F_c - F_do), the power of the wrench the fingers fail to deliver, which the
thesis' proof drops (its (5.61) keeps it as Delta F_o).

Its finger part, 1/2 s_f^T M_f s_f + 1/2 h |eta|^2 (+ 1/2 Delta sigma_f^T Gamma_f^-1 Delta sigma_f, constant
without hand adaptation), with c and h the force gains of (5.57) and eta the integrals of the contact force errors
e_fc, rebuilt from the law's log (:func:`force_integrals`).  Under the proof's premises: rigid rolling contacts
(J_h q_dot = G^T X_dot), J_h J_h^+ the identity on e_fc, eta and G^T v_r, an exact hand model, a q_dd_r that also
differentiates J_h^+ (c e_fc + h eta) (the law leaves it out), all three force components fed back
(``force_error="full"``) and contact forces whose wrench G F_dc is F_do, (5.62) (whose J^T G e_fc is J_h^T e_fc)
gives V_f_dot = s_o^T G e_fc - c |e_fc|^2 - s_f^T k_f s_f; its first term cancels the object part's s_o^T (F_c -
F_do) = -s_o^T G e_fc, and V_dot = -s_o^T k_o s_o - s_f^T k_f s_f - c |e_fc|^2 <= 0, the corrected (5.65).  A
contact simulation meets none of these exactly.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from bhgrasp.controllers.object_regressors import object_parameters
from bhgrasp.errors import InputError


def object_inertia_matrix(mass: float, inertia: Any, rotation: Any) -> np.ndarray:
    """M_o (6, 6) = diag(m I_3, R I R^T) [kg, kg m^2]: the object's inertia at its COM, world axes."""
    rotation = np.asarray(rotation, dtype=float)
    matrix = np.zeros((6, 6))
    matrix[:3, :3] = mass * np.eye(3)
    matrix[3:, 3:] = rotation @ np.asarray(inertia, dtype=float) @ rotation.T
    return matrix


def object_lyapunov(
    mass: float, inertia: Any, rotation: Any, sliding: Any, estimate: Any, information: Any
) -> tuple[float, float]:
    """(1/2 s_o^T M_o s_o [J], 1/2 Delta sigma^T P^-1 Delta sigma): V_o's two terms at one instant.

    Args:
        mass, inertia: The object's true mass [kg] and body inertia about its COM [kg m^2].
        rotation: Its orientation (world <- body).
        sliding: s_o (6,) [m/s, rad/s].
        estimate: sigma_hat (7,).
        information: P^-1 (7, 7) (zero rows and columns for the parameters held fixed).
    """
    sliding = np.asarray(sliding, dtype=float)
    kinetic = 0.5 * sliding @ object_inertia_matrix(mass, inertia, rotation) @ sliding
    error = np.asarray(estimate, dtype=float) - object_parameters(mass, inertia)
    return float(kinetic), float(0.5 * error @ np.asarray(information, dtype=float) @ error)


def force_integrals(desired_force: Any, force_error: Any, dt: Any) -> np.ndarray:
    """The force integrals eta (N, F, 3) [N s] per sample and finger, integrated as the SMC-adaptive law does.

    From its log (``desired_force`` and ``force_error``, (N, F, 3) per finger, zero rows for fingers not touching)
    of a trajectory recorded every control cycle (``dt`` (N,) [s] the cycles' lengths, 0 for the first after the
    law's reset): eta_k = eta_(k-1) + dt_k e_k for a finger touching (a nonzero desired force: the law asks a
    touching finger for at least its ``min_normal_force``); a finger not touching loses its integral.
    """
    desired, error = np.asarray(desired_force, dtype=float), np.asarray(force_error, dtype=float)
    if desired.ndim != 3 or desired.shape != error.shape or desired.shape[2] != 3:
        raise InputError(
            f"`desired_force` and `force_error` must both be (N, F, 3), got {desired.shape}, {error.shape}"
        )
    steps = np.broadcast_to(np.asarray(dt, dtype=float), desired.shape[:1])
    integrals, current = np.zeros_like(error), np.zeros(error.shape[1:])
    for k in range(len(error)):
        touching = np.any(desired[k] != 0.0, axis=1)[:, None]
        current = np.where(touching, current + steps[k] * error[k], 0.0)
        integrals[k] = current
    return integrals


def finger_lyapunov(mass_matrix: Any, sliding: Any, integrals: Any, force_integral: float) -> tuple[float, float]:
    """(1/2 s_f^T M_f s_f [J], 1/2 h |eta|^2 [J]): the finger part of V (5.63) at one instant.

    Args:
        mass_matrix: M_f (nv, nv) of the true hand at q [kg m^2].
        sliding: s_f (nv,) [rad/s].
        integrals: eta (F, 3) [N s] (:func:`force_integrals`).
        force_integral: h [m/s / (N s)] of (5.57).
    """
    sliding = np.asarray(sliding, dtype=float)
    kinetic = 0.5 * sliding @ np.asarray(mass_matrix, dtype=float) @ sliding
    return float(kinetic), float(0.5 * force_integral * np.sum(np.square(integrals)))


__all__ = ["finger_lyapunov", "force_integrals", "object_inertia_matrix", "object_lyapunov"]
