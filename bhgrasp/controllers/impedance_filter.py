"""The impedance filter M_I dx_dd + B_I dx_d + K_I dx = f (thesis (4.13), (4.20), (4.22)), continuous and Tustin.

``dx`` is the impedance error Delta X = X_d - X_c [m] and ``f`` its driving force [N] (the contact force for
position-based impedance, the force error f - f_d for force-based).  Both filters act per component on vectors of
any size and return (dx, dx_dot, dx_ddot).

* :class:`ImpedanceFilter`: the continuous filter integrated by implicit Euler (unconditionally stable for any
  positive M_I, B_I, K_I and step).
* :class:`TustinImpedanceFilter`: the thesis' bilinear discretisation (4.45)-(4.48) at a fixed period T:
  H(z) = T^2 (z + 1)^2 / (w1 z^2 + w2 z + w3), w1 = 4M + 2BT + KT^2, w2 = 2KT^2 - 8M, w3 = 4M + KT^2 - 2BT,
  i.e. E(n) = (T^2 (F(n) + 2F(n-1) + F(n-2)) - w2 E(n-1) - w3 E(n-2)) / w1; rates by backward differences.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from bhgrasp._validation import as_positive, as_real, as_vector
from bhgrasp.errors import InputError


def critical_damping(mass: float, stiffness: float, environment_stiffness: float = 0.0, ratio: float = 1.0) -> float:
    """B_I [N s/m] giving damping ``ratio`` to the contact loop M_I e'' + B_I e' + (K_I + k_e) e = 0.

    With k_e = 0 this is (4.16): B_I = 2 zeta sqrt(M_I K_I).  In contact the force-error dynamics (4.24) have the
    stiffness K_I + k_e, so a response without overshoot needs B_I >= 2 sqrt(M_I (K_I + k_e)); the thesis' damping
    condition (4.19) is garbled in print and is replaced by this.
    """
    mass, stiffness = as_positive(mass, "mass"), as_positive(stiffness, "stiffness")
    environment_stiffness = as_real(environment_stiffness, "environment_stiffness")
    return 2.0 * as_positive(ratio, "ratio") * float(np.sqrt(mass * (stiffness + environment_stiffness)))


class ImpedanceFilter:
    """Continuous impedance filter, implicit Euler.  Call :meth:`step` once per control period."""

    def __init__(self, mass: float, damping: float, stiffness: float, size: int = 3) -> None:
        """Args: ``mass`` M_I [kg] > 0, ``damping`` B_I [N s/m] >= 0, ``stiffness`` K_I [N/m] > 0, vector ``size``."""
        self.mass = as_positive(mass, "mass")
        self.damping = as_real(damping, "damping")
        self.stiffness = as_positive(stiffness, "stiffness")
        if int(size) < 1:
            raise InputError(f"`size` must be >= 1, got {size!r}")
        self.size = int(size)
        self.reset()

    def reset(self) -> None:
        """Back to rest: dx = dx_dot = 0."""
        self.dx = np.zeros(self.size)
        self.dx_dot = np.zeros(self.size)
        self.dx_ddot = np.zeros(self.size)

    def step(self, force: Any, dt: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Advance ``dt`` [s] under ``force`` [N] held constant; return (dx [m], dx_dot [m/s], dx_ddot [m/s^2])."""
        force = as_vector(force, "force", self.size)
        dt = as_real(dt, "dt")
        if dt > 0.0:
            m, b, k = self.mass, self.damping, self.stiffness
            velocity = (self.dx_dot + dt / m * (force - k * self.dx)) / (1.0 + dt * b / m + dt * dt * k / m)
            self.dx = self.dx + dt * velocity
            self.dx_dot = velocity
        self.dx_ddot = (force - self.damping * self.dx_dot - self.stiffness * self.dx) / self.mass
        return self.dx.copy(), self.dx_dot.copy(), self.dx_ddot.copy()


class TustinImpedanceFilter:
    """The bilinear-discretised filter (4.48) at period ``period``; :meth:`step` must be called every period."""

    def __init__(self, mass: float, damping: float, stiffness: float, period: float, size: int = 3) -> None:
        """Args as :class:`ImpedanceFilter` plus the sampling ``period`` T [s]."""
        self.mass = as_positive(mass, "mass")
        self.damping = as_real(damping, "damping")
        self.stiffness = as_positive(stiffness, "stiffness")
        self.period = as_positive(period, "period")
        if int(size) < 1:
            raise InputError(f"`size` must be >= 1, got {size!r}")
        self.size = int(size)
        self.reset()

    def coefficients(self) -> tuple[np.ndarray, np.ndarray]:
        """(numerator, denominator) of H(z) in powers z^0, z^-1, z^-2, normalised so denominator[0] = 1."""
        m, b, k, t = self.mass, self.damping, self.stiffness, self.period
        w1, w2, w3 = 4 * m + 2 * b * t + k * t * t, 2 * k * t * t - 8 * m, 4 * m + k * t * t - 2 * b * t
        return np.array([t * t, 2 * t * t, t * t]) / w1, np.array([1.0, w2 / w1, w3 / w1])

    def reset(self) -> None:
        """Zero input and output history."""
        zero = [0.0] * self.size
        # per component, as floats (a few scalar operations cost less than as many on 3-vectors; the same IEEE ones)
        self._inputs = (zero, zero)  # F(n-1), F(n-2)
        self._outputs = (zero, zero, zero)  # E(n-1), E(n-2), E(n-3)
        self._cached: tuple[tuple[float, ...], tuple[float, ...], tuple[float, ...]] | None = None

    def _coefficients(self) -> tuple[tuple[float, ...], tuple[float, ...]]:
        """:meth:`coefficients` as floats, recomputed only when M_I, B_I, K_I or T changed."""
        key = (self.mass, self.damping, self.stiffness, self.period)
        if self._cached is None or self._cached[0] != key:
            numerator, denominator = self.coefficients()
            self._cached = (key, tuple(map(float, numerator)), tuple(map(float, denominator)))
        return self._cached[1], self._cached[2]

    def step(self, force: Any, dt: float | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Next sample E(n) for input F(n) [N], as (dx, dx_dot, dx_ddot) with backward-difference rates.

        ``dt`` (if given) must equal the period: a different step would silently change the filter.
        """
        force = as_vector(force, "force", self.size)
        if dt is not None and abs(float(dt) - self.period) > 1e-9 * max(1.0, self.period):
            if float(dt) == 0.0:  # the first call after a reset: no time has passed, nothing to advance
                return self._state()
            raise InputError(f"TustinImpedanceFilter runs at period T = {self.period} s, called with dt = {dt}")
        (b0, b1, b2), (_, a1, a2) = self._coefficients()
        f0, (f1, f2), (e1, e2, _) = force.tolist(), self._inputs, self._outputs
        e0 = [b0 * x0 + b1 * x1 + b2 * x2 - a1 * y1 - a2 * y2 for x0, x1, x2, y1, y2 in zip(f0, f1, f2, e1, e2)]
        self._inputs, self._outputs = (f0, f1), (e0, e1, e2)  # the histories shifted
        return self._state()

    def _state(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        e0, e1, e2 = self._outputs
        t = self.period
        tt = t * t
        return (
            np.array(e0),
            np.array([(x0 - x1) / t for x0, x1 in zip(e0, e1)]),
            np.array([(x0 - 2.0 * x1 + x2) / tt for x0, x1, x2 in zip(e0, e1, e2)]),
        )


__all__ = ["ImpedanceFilter", "TustinImpedanceFilter", "critical_damping"]
