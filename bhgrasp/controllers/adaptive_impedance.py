"""Adaptive force-based impedance (thesis (4.31)-(4.41)): FIM with the environment's k_e and x_e estimated online.

The derivation, and where it departs from the thesis' printed law: :mod:`bhgrasp.controllers.impedance`.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from bhgrasp._validation import as_positive, as_real, as_vector
from bhgrasp.controllers.impedance import ForceImpedance, Sample
from bhgrasp.errors import InputError
from bhgrasp.motion.trajectories import Reference

_SEARCH_BAND = 5e-3  # [m] a fingertip this close to its target without contact makes the surface estimate advance
_SURFACE_UNCERTAINTY = 0.05  # [m] prior scale of x_e for the least-squares estimator ...
_PRIOR_SCALE = 10.0  # ... and the prior's weakness: standard deviations of 10 k_e(0) and 10 k_e(0) x 5 cm


class AdaptiveForceImpedance(ForceImpedance):
    """Adaptive FIM (4.31)-(4.41): k_e and x_e estimated online from the sensed force and fingertip position."""

    def __init__(
        self,
        reference: Reference,
        normal: Any,
        force: float,
        surface_estimate: Any,
        stiffness_estimate: float,
        gamma: tuple[float, float] = (1.0, 0.5),
        estimator: str = "least-squares",
        mass: float = 0.1,
        damping: float | None = None,
        stiffness: float = 200.0,
        period: float | None = None,
        search_speed: float = 0.02,
        min_stiffness: float = 1.0,
        quasi_static_speed: float = 5e-3,
    ) -> None:
        """Set up the adaptive force loop.

        Args:
            surface_estimate, stiffness_estimate: Initial x_e [m] (a point) and k_e [N/m] estimates.
            gamma: (gamma_1, gamma_2): gradient-law rates of k_e and of k_e x_e (thesis planar 1, 0.5), scaled by the
                initial k_e estimate so that one pair suits soft and hard environments: Gamma = diag(gamma k0).
            estimator: ``"gradient"`` (the thesis' law (4.40), corrected) or ``"least-squares"`` (recursive least
                squares on the same regressor, centred on the initial surface estimate: it identifies k_e and x_e
                from any two force levels, where the gradient law with a constant f_d only learns the one
                operating point f = f_d).
            search_speed: Speed [m/s] at which the estimated surface advances while there is no contact.
            min_stiffness: Floor [N/m] of the k_e estimate (it divides f_d).
            quasi_static_speed: Fingertip normal speed [m/s] above which samples are not used for estimation
                (impacts and fast transients, where damping and inertia break f = k_e (x - x_e)).
            reference, normal, force, mass, damping, stiffness, period: As :class:`ForceImpedance` (damping
                ``None`` is critical for the *estimated* k_e at start).
        """
        super().__init__(
            reference, normal, force, surface_estimate, stiffness_estimate, mass, damping, stiffness, period
        )
        gains = as_vector(gamma, "gamma", 2)
        if np.any(gains <= 0.0):
            raise InputError(f"`gamma` must be two positive rates, got {gamma!r}")
        self.gamma = gains * self.environment_stiffness
        if estimator not in ("gradient", "least-squares"):
            raise InputError(f"`estimator` must be 'gradient' or 'least-squares', got {estimator!r}")
        self.estimator = estimator
        self.search_speed = as_real(search_speed, "search_speed")
        self.min_stiffness = as_positive(min_stiffness, "min_stiffness")
        self.quasi_static_speed = as_positive(quasi_static_speed, "quasi_static_speed")
        self._initial = (self.environment_stiffness, self.surface)
        self._centre = self.surface  # regressor phi = (x - centre, -1): well conditioned for any surface position
        self.reset()

    def reset(self) -> None:
        """Restart the estimates at their initial values."""
        super().reset()
        self.environment_stiffness, self.surface = self._initial
        k0 = self.environment_stiffness
        self.theta = np.array([k0, k0 * (self.surface - self._centre)])  # theta = (k_e, k_e (x_e - centre))
        self._rate = np.zeros(2)
        self._covariance = np.diag([(_PRIOR_SCALE * k0) ** 2, (_PRIOR_SCALE * k0 * _SURFACE_UNCERTAINTY) ** 2])
        self._last_x: np.ndarray | None = None

    def command(self, t, x, contact, dt) -> Sample:  # noqa: D102
        along = float(self.normal @ x)
        self.theta = self.theta + dt * self._rate  # explicit Euler with the previous sample's rate (gradient law)
        self._rate = np.zeros(2)
        speed = abs(float(self.normal @ (x - self._last_x))) / dt if dt > 0.0 and self._last_x is not None else 0.0
        self._last_x = np.array(x, dtype=float)
        if contact.touching and speed <= self.quasi_static_speed:
            measured = float(self.normal @ contact.force)
            regressor = np.array([along - self._centre, -1.0])
            predicted = float(regressor @ self.theta)
            if self.estimator == "gradient":
                self._rate = -self.gamma * regressor * (predicted - measured)
            else:
                gain = self._covariance @ regressor / (1.0 + regressor @ self._covariance @ regressor)
                self.theta = self.theta + gain * (measured - predicted)
                self._covariance = self._covariance - np.outer(gain, regressor @ self._covariance)
            self.log["force_estimate"] = predicted
        elif not contact.touching:
            if along >= self.target() - _SEARCH_BAND:  # at the estimated surface + f_d/k_e, no contact: search on
                self.theta[1] += dt * self.search_speed * self.theta[0]
            self.log["force_estimate"] = 0.0
        else:
            self.log["force_estimate"] = float(np.array([along - self._centre, -1.0]) @ self.theta)
        self.theta[0] = max(self.theta[0], self.min_stiffness)
        self.environment_stiffness = float(self.theta[0])
        self.surface = self._centre + float(self.theta[1] / self.theta[0])
        self.log["stiffness_estimate"], self.log["surface_estimate"] = self.environment_stiffness, self.surface
        return super().command(t, x, contact, dt)


__all__ = ["AdaptiveForceImpedance"]
