"""Sizing robust gains from a model-error bound: the switching gain must dominate what the model gets wrong.

If the true inertial parameters differ from the nominal ones by at most a fraction ``model_error`` (a mass/inertia
scale error), the torque the nominal model misses along a reference is bounded by
Delta = model_error / (1 - model_error) max_t |tau_hat(q_d, qd_d, qdd_d)| per joint, and its rate by
Phi = model_error / (1 - model_error) max_t |d tau_hat / dt|.  SMC's K and HOSM's alpha are ``margin`` x Delta;
the super-twisting gains follow Levant's rule (W > Phi, lambda_s = 1.5 sqrt(M W)), with W also large enough for
the integral term to build up Delta quickly.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bhgrasp._validation import as_positive
from bhgrasp.errors import InputError
from bhgrasp.model.hand import Hand
from bhgrasp.motion.trajectories import Reference


@dataclass(frozen=True)
class SlidingGains:
    """Per-joint robust gains for the sliding-mode family (all (nv,)).

    Attributes:
        delta: Bound on the model's torque error along the reference [N m].
        phi: Bound on its rate [N m/s].
        k: SMC switching gain K [N m].
        alpha: HOSM A/B gain [N m].
        w: Super-twisting integral rate W [N m/s].
        u_max: Super-twisting anti-windup bound u_M [N m].
        lambda_s: Super-twisting proportional gain [N m (s/rad)^1/2].
    """

    delta: np.ndarray
    phi: np.ndarray
    k: np.ndarray
    alpha: np.ndarray
    w: np.ndarray
    u_max: np.ndarray
    lambda_s: np.ndarray


def sliding_gains(
    nominal: Hand,
    reference: Reference,
    duration: float,
    model_error: float = 0.3,
    margin: float = 2.0,
    samples: int = 501,
    build_up: float = 0.2,
) -> SlidingGains:
    """Robust gains that dominate a ``model_error`` scale error of ``nominal`` along ``reference`` over [0, duration].

    Args:
        nominal: The controller's model.
        reference: Joint reference (size nv).
        duration: Time span [s] of the reference to bound.
        model_error: Relative inertial-parameter error, in [0, 1).
        margin: Factor > 1 on Delta for K, alpha and u_M.
        samples: Time samples of the reference.
        build_up: Time [s] in which the super-twisting integral can build up Delta (W >= Delta / build_up).
    """
    duration = as_positive(duration, "duration")
    if not 0.0 <= float(model_error) < 1.0:
        raise InputError(f"`model_error` must be in [0, 1), got {model_error!r}")
    margin = as_positive(margin, "margin")
    if margin <= 1.0 or int(samples) < 3:
        raise InputError(f"`margin` must exceed 1 and `samples` be >= 3, got {margin}, {samples}")
    times = np.linspace(0.0, duration, int(samples))
    torques = np.array([nominal.inverse_dynamics(*reference(t)) for t in times])
    ratio = float(model_error) / (1.0 - float(model_error))
    delta = ratio * np.abs(torques).max(axis=0)
    phi = ratio * np.abs(np.gradient(torques, times, axis=0)).max(axis=0)
    w = 1.1 * phi + delta / as_positive(build_up, "build_up")  # W > Phi, and u1 reaches Delta in build_up
    inertia = np.diag(nominal.mass_matrix(reference(duration)[0]))
    floor = 1e-9 * max(float(np.max(delta)), 1e-12)  # a joint with no load still needs positive gains
    k = np.maximum(margin * delta, floor)
    return SlidingGains(delta, phi, k, k.copy(), np.maximum(w, floor), k.copy(), 1.5 * np.sqrt(inertia * w) + floor)


__all__ = ["SlidingGains", "sliding_gains"]
