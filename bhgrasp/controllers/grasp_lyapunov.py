"""The Lyapunov function of the SMC-adaptive grasp, thesis (5.63), evaluated from a run.

Its object part, for a law with sliding error s_o = X_dot - v_r (world twist at the COM) and estimate error
Delta sigma = sigma_hat - sigma over the parameters it learns,

    V_o = 1/2 s_o^T M_o s_o + 1/2 Delta sigma^T P^-1 Delta sigma,       M_o = diag(m I_3, R I R^T),

with P^-1 = Gamma_o^-1 for the thesis' law (5.52) and the growing information of the composite law
(:mod:`bhgrasp.controllers.object_identification`).  When the object receives exactly the commanded wrench F_do,
V_o_dot = -s_o^T k_o s_o (- 1/2 |W Delta sigma|_Q^2 for the composite law).  In a grasp it receives the contacts'
wrench F_c, and V_o_dot gains s_o^T (F_c - F_do), the power of the wrench the fingers fail to deliver, which the
thesis' proof drops (its (5.61) keeps it as Delta F_o).

Only the object part is evaluated: the finger part of (5.63), 1/2 s_f^T M_f s_f + 1/2 eta^T h_o eta (+ the hand
parameters' term), needs the force integrals eta, which the compiled law keeps to itself.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from bhgrasp.controllers.object_regressors import object_parameters


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


__all__ = ["object_inertia_matrix", "object_lyapunov"]
