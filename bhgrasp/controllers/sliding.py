"""Sliding-mode control (thesis (3.39)) and adaptive sliding-mode control (Slotine-Li, thesis (3.40)-(3.43)).

Common structure (e = q - q_d, thesis (3.33)-(3.38)), per joint with diagonal gains:

    s = e_dot + lambda e,   qd_r = qd_d - lambda e,   qdd_r = qdd_d - lambda e_dot   (so s = qd - qd_r)
    tau = M_hat qdd_r + C_hat(q, qd) qd_r + G_hat - K_s s + u_robust

The model term uses the controller's nominal hand (:meth:`~bhgrasp.model.hand.Hand.slotine_li_torque`) or, when
adaptive, the regressor form Y(q, qd, qd_r, qdd_r) theta_hat with the gradient update
theta_hat_dot = -Gamma^-1 Y^T s.  The thesis prints +Gamma^-1 Y^T s (3.43); with its own s = qd - qd_r and
tau = Y sigma - K s that sign makes the Lyapunov function of A.1 grow, so we use the minus sign (Slotine & Li 1987).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from bhgrasp._validation import as_real, as_vector
from bhgrasp.controllers.base import JointTracking, gain_vector, inertia_gain
from bhgrasp.data import State
from bhgrasp.errors import InputError
from bhgrasp.model.hand import Hand
from bhgrasp.motion.trajectories import Reference


def parameter_scales(hand: Hand) -> np.ndarray:
    """Natural magnitude of each inertial parameter (m, m c, I at the joint origin) of ``hand``, shape (10 n_bodies,).

    Per body of mass m and gyration length l = sqrt(trace(I_origin) / (2 m)): m, three times m l, six times m l^2.
    Adaptation gains are given relative to these, so one number suits heavy and light links alike.
    """
    params = hand.inertial_parameters().reshape(-1, 10)
    mass = np.maximum(params[:, 0], 1e-9)
    length = np.sqrt(np.maximum(params[:, [4, 6, 9]].sum(axis=1), 1e-18) / (2.0 * mass))
    scales = np.empty_like(params)
    scales[:, 0] = mass
    scales[:, 1:4] = (mass * length)[:, None]
    scales[:, 4:] = (mass * length**2)[:, None]
    return scales.ravel()


class SlidingSurface(JointTracking):
    """The sliding-variable machinery shared by SMC, ASMC and the higher-order sliding controllers.

    Subclasses add :meth:`robust`, the discontinuous or higher-order term.  Logged: ``s`` (sliding variable),
    ``u_robust`` and, when adaptive, ``theta`` (parameter estimates).
    """

    def __init__(
        self,
        nominal: Hand,
        reference: Reference,
        lam: Any,
        k_s: Any,
        adaptation_gain: Any = None,
        leakage: float = 0.0,
    ) -> None:
        """Set the surface, the linear gain and, optionally, the adaptation.

        Args:
            nominal: The controller's model; its inertial parameters are the estimates' start (thesis sigma(0) = 1).
            reference: Joint reference of size nv.
            lam: Sliding-surface slope lambda [1/s], scalar or per joint.
            k_s: Linear sliding gain K_s [N m s/rad], scalar or per joint (may be 0); ``None``: 40 [1/s] x diag M.
            adaptation_gain: ``None`` (no adaptation), a number gamma [1/(N m rad)] applied relative to
                :func:`parameter_scales` (Gamma^-1 = gamma diag(scale^2)), or the full diagonal of Gamma^-1.
            leakage: sigma-modification rate [1/s] pulling estimates back to the nominal ones (0 = pure gradient,
                for which the Lyapunov function is non-increasing; > 0 bounds estimates under noise).
        """
        super().__init__(nominal, reference)
        n = nominal.nv
        self.lam = gain_vector(lam, n, "lam")
        self.k_s = inertia_gain(nominal, 40.0) if k_s is None else gain_vector(k_s, n, "k_s", allow_zero=True)
        self.theta0 = nominal.inertial_parameters()
        self.adaptive = adaptation_gain is not None
        if self.adaptive:
            size = len(self.theta0)
            if np.ndim(adaptation_gain) == 0:
                gamma = as_real(adaptation_gain, "adaptation_gain")
                if gamma <= 0.0:
                    raise InputError(f"`adaptation_gain` must be positive, got {adaptation_gain!r}")
                self.gamma_inv = gamma * parameter_scales(nominal) ** 2
            else:
                self.gamma_inv = gain_vector(adaptation_gain, size, "adaptation_gain", allow_zero=True)
        self.leakage = as_real(leakage, "leakage")
        self.theta = self.theta0.copy()
        self._rate = np.zeros_like(self.theta0)

    def reset(self, state: State) -> None:
        """Restart the estimates at the nominal parameters and clear the robust term's memory."""
        super().reset(state)
        self.theta = self.theta0.copy()
        self._rate = np.zeros_like(self.theta0)

    def torque(self, q, v, q_d, v_d, a_d, dt) -> np.ndarray:  # noqa: D102
        e, e_dot = q - q_d, v - v_d
        v_r = v_d - self.lam * e
        a_r = a_d - self.lam * e_dot
        s = v - v_r
        if self.adaptive:
            self.theta = self.theta + dt * self._rate  # explicit Euler with the rate from the previous sample
            regressor = self.nominal.slotine_li_regressor(q, v, v_r, a_r)
            model = regressor @ self.theta
            self._rate = -self.gamma_inv * (regressor.T @ s) - self.leakage * (self.theta - self.theta0)
            self.log["theta"] = self.theta.copy()
        else:
            model = self.nominal.slotine_li_torque(q, v, v_r, a_r)
        robust = self.robust(e, e_dot, s, dt)
        self.log["s"], self.log["u_robust"] = s, robust
        return model - self.k_s * s + robust

    def robust(self, e: np.ndarray, e_dot: np.ndarray, s: np.ndarray, dt: float) -> np.ndarray:
        """The robust term u_robust [N m] (none here)."""
        return np.zeros_like(s)


class SlidingMode(SlidingSurface):
    """Sliding-mode control (thesis (3.39)): u_robust = -K sign(s), or -K sat(s / phi) inside a boundary layer."""

    def __init__(
        self,
        nominal: Hand,
        reference: Reference,
        lam: Any = 17.0,
        k_s: Any = None,
        k: Any = None,
        boundary_layer: Any = None,
    ) -> None:
        """Set the gains.

        Args:
            lam: lambda [1/s] (thesis Barrett value 17).
            k_s: K_s [N m s/rad] (default 40 [1/s] x diag M).
            k: Switching gain K [N m], scalar or per joint; it must exceed the model error it has to dominate
                (:func:`~bhgrasp.controllers.design.sliding_gains` sizes it from a model-error bound).  Default
                60 [rad/s^2] x diag M: the thesis' K = 220 N m is far beyond the BH8-280's joint torques.
            boundary_layer: ``None`` for sign(s), or the layer width phi [rad/s] (scalar or per joint) of sat(s/phi).
        """
        super().__init__(nominal, reference, lam, k_s)
        n = nominal.nv
        self.k = inertia_gain(nominal, 60.0) if k is None else gain_vector(k, n, "k")
        self.boundary_layer = None if boundary_layer is None else gain_vector(boundary_layer, n, "boundary_layer")

    def robust(self, e, e_dot, s, dt) -> np.ndarray:  # noqa: D102
        if self.boundary_layer is None:
            return -self.k * np.sign(s)
        return -self.k * np.clip(s / self.boundary_layer, -1.0, 1.0)


class AdaptiveSlidingMode(SlidingSurface):
    """Adaptive sliding-mode control (thesis (3.42)-(3.43)).

    tau = Y(q, qd, qd_r, qdd_r) theta_hat - K_s s,   theta_hat_dot = -Gamma^-1 Y^T s.
    """

    def __init__(
        self,
        nominal: Hand,
        reference: Reference,
        lam: Any = 17.0,
        k_s: Any = None,
        adaptation_gain: Any = 3000.0,
        leakage: float = 0.0,
    ) -> None:
        """Args as :class:`SlidingSurface`.

        The default gamma = 3000 [1/(N m rad)] (relative to :func:`parameter_scales`) adapts a 30 % mass error of
        the BH8-280 within about a second; the thesis' Gamma = 3.3 is in its own parameter units.
        """
        if adaptation_gain is None:
            raise InputError("`adaptation_gain` is required for adaptive control (use SlidingMode without it)")
        super().__init__(nominal, reference, lam, k_s, adaptation_gain, leakage)


def lyapunov(plant: Hand, controller: SlidingSurface, q: Any, s: Any, theta: Any) -> float:
    """V = 1/2 s^T M(q) s + 1/2 (theta_hat - theta)^T Gamma (theta_hat - theta) (thesis (A.6) plus adaptation).

    ``plant`` supplies the true M and parameters theta; for a non-adaptive controller the second term is 0.
    """
    s = as_vector(s, "s", plant.nv)
    value = 0.5 * s @ plant.mass_matrix(q) @ s
    if controller.adaptive:
        error = as_vector(theta, "theta", len(controller.theta0)) - plant.inertial_parameters()
        active = controller.gamma_inv > 0.0
        value += 0.5 * np.sum(error[active] ** 2 / controller.gamma_inv[active])
    return float(value)


__all__ = ["AdaptiveSlidingMode", "SlidingMode", "SlidingSurface", "lyapunov", "parameter_scales"]
