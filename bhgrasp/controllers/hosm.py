"""Second-order sliding-mode controllers A (3.58), B (3.59), super-twisting C (3.60)-(3.62), and HOSMA (3.63).

HOSMA is the adaptive version of each (``adaptation_gain``).

All share :class:`~bhgrasp.controllers.sliding.SlidingSurface`'s model term (nominal, or adaptive Y theta_hat)
and linear sliding gain; the higher-order term replaces SMC's -K sign(s), per joint:

* A (Levant's quasi-continuous 2-sliding law): u = -alpha (e_dot + |e|^1/2 sign e) / (|e_dot| + |e|^1/2), on the
  position error e (relative degree 2, as the thesis defines s for A and B); continuous except at e = e_dot = 0.
* B: u = -alpha sign(e_dot + |e|^1/2 sign e) (the thesis prints the fraction inside the sign; only its sign matters).
* C, super-twisting on s = e_dot + lambda e (relative degree 1): u = u1 + u2 with
  u1_dot = -u if |u| > u_M (anti-windup) else -W sign(s), and
  u2 = -lambda_s |s|^rho sign(s) for |s| <= eps_0, -lambda_s eps_0^rho sign(s) beyond (Levant 1993).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from bhgrasp._validation import as_positive
from bhgrasp.controllers.base import gain_vector, inertia_gain
from bhgrasp.controllers.sliding import SlidingSurface
from bhgrasp.data import State
from bhgrasp.errors import InputError
from bhgrasp.model.hand import Hand
from bhgrasp.motion.trajectories import Reference


class QuasiContinuousA(SlidingSurface):
    """Second-order sliding controller A (3.58); HOSMA with ``adaptation_gain`` (3.63)."""

    def __init__(
        self,
        nominal: Hand,
        reference: Reference,
        alpha: Any = None,
        lam: Any = 8.0,
        k_s: Any = None,
        adaptation_gain: Any = None,
        leakage: float = 0.0,
    ) -> None:
        """Set the gains.

        Args:
            alpha: The 2-sliding gain [N m], scalar or per joint (default 60 [rad/s^2] x diag M; the thesis' 2.1 is
                for its own model).
            lam, k_s, adaptation_gain, leakage: As :class:`SlidingSurface` (thesis F3: lambda = 8, Gamma = 2).
        """
        super().__init__(nominal, reference, lam, k_s, adaptation_gain, leakage)
        self.alpha = inertia_gain(nominal, 60.0) if alpha is None else gain_vector(alpha, nominal.nv, "alpha")

    def robust(self, e, e_dot, s, dt) -> np.ndarray:  # noqa: D102
        root = np.sqrt(np.abs(e))
        numerator = e_dot + root * np.sign(e)
        denominator = np.abs(e_dot) + root
        ratio = np.divide(numerator, denominator, out=np.zeros_like(e), where=denominator > 0.0)
        return -self.alpha * ratio


class TwistingB(QuasiContinuousA):
    """Second-order sliding controller B (3.59): the sign of A's surface; HOSMA with ``adaptation_gain``."""

    def robust(self, e, e_dot, s, dt) -> np.ndarray:  # noqa: D102
        return -self.alpha * np.sign(e_dot + np.sqrt(np.abs(e)) * np.sign(e))


class SuperTwisting(SlidingSurface):
    """Super-twisting controller C (3.60)-(3.62) with its anti-windup bound; HOSMA with ``adaptation_gain``."""

    def __init__(
        self,
        nominal: Hand,
        reference: Reference,
        w: Any = None,
        u_max: Any = None,
        rho: float = 0.5,
        lambda_s: Any = None,
        eps_0: float = 0.1,
        lam: Any = 8.0,
        k_s: Any = None,
        adaptation_gain: Any = None,
        leakage: float = 0.0,
    ) -> None:
        """Set the gains (defaults scale with each joint's inertia M; thesis values are for its own model).

        Args:
            w: W [N m/s], the integral term's rate (default 600 [rad/s^3] x M; thesis 0.0015).
            u_max: u_M [N m], the anti-windup bound (default 60 [rad/s^2] x M; thesis 1).
            rho: Exponent, 0 < rho <= 0.5 (Levant; the thesis uses 0.1 and writes 0 < rho < 0.2).
            lambda_s: lambda_s [N m (s/rad)^rho] (default 1.5 sqrt(M W), Levant's rule; thesis 2).
            eps_0: Boundary eps_0 [rad/s] beyond which u2 saturates (thesis 0.001).
            lam, k_s, adaptation_gain, leakage: As :class:`SlidingSurface`.
        """
        super().__init__(nominal, reference, lam, k_s, adaptation_gain, leakage)
        n = nominal.nv
        self.w = inertia_gain(nominal, 600.0) if w is None else gain_vector(w, n, "w")
        self.u_max = inertia_gain(nominal, 60.0) if u_max is None else gain_vector(u_max, n, "u_max")
        self.rho = as_positive(rho, "rho")
        if self.rho > 0.5:
            raise InputError(f"`rho` must be in (0, 0.5] for the super-twisting algorithm, got {rho}")
        if lambda_s is None:
            self.lambda_s = 1.5 * np.sqrt(inertia_gain(nominal, 1.0) * self.w)
        else:
            self.lambda_s = gain_vector(lambda_s, n, "lambda_s")
        self.eps_0 = as_positive(eps_0, "eps_0")
        self.u1 = np.zeros(n)
        self._u = np.zeros(n)

    def reset(self, state: State) -> None:
        """Also clear the integral term u1."""
        super().reset(state)
        self.u1 = np.zeros(self.nominal.nv)
        self._u = np.zeros(self.nominal.nv)

    def robust(self, e, e_dot, s, dt) -> np.ndarray:  # noqa: D102
        rate = np.where(np.abs(self._u) > self.u_max, -self._u, -self.w * np.sign(s))
        self.u1 = self.u1 + dt * rate  # explicit Euler, with the switching decided on the previous sample's u
        magnitude = np.where(np.abs(s) <= self.eps_0, np.abs(s), self.eps_0) ** self.rho
        u2 = -self.lambda_s * magnitude * np.sign(s)
        self._u = self.u1 + u2
        self.log["u1"] = self.u1.copy()
        return self._u.copy()


def hosm(law: str, nominal: Hand, reference: Reference, adaptive: bool = False, **gains: Any) -> SlidingSurface:
    """The thesis' HOSM (``adaptive=False``) or HOSMA controller ``law`` "A", "B" or "C" with ``gains``.

    HOSMA uses ``adaptation_gain`` from ``gains`` (default 3000, as :class:`AdaptiveSlidingMode`).
    """
    classes = {"A": QuasiContinuousA, "B": TwistingB, "C": SuperTwisting}
    if law not in classes:
        raise InputError(f"`law` must be one of {sorted(classes)}, got {law!r}")
    if adaptive:
        gains.setdefault("adaptation_gain", 3000.0)
    elif gains.get("adaptation_gain") is not None:
        raise InputError("`adaptation_gain` given with adaptive=False; pass adaptive=True for HOSMA")
    return classes[law](nominal, reference, **gains)


__all__ = ["QuasiContinuousA", "SuperTwisting", "TwistingB", "hosm"]
