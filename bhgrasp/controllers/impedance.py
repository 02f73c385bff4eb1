"""Impedance control of thesis chapter 4: position-based (PIM), force-based (FIM) and adaptive force impedance.

Each law is an *outer loop* per finger that turns the desired fingertip trajectory X_d and the sensed contact force into
a commanded trajectory X_c = X_d - Delta X; :class:`~bhgrasp.controllers.impedance_controller.ImpedanceController` feeds
the commands of one or several fingers to an inner fingertip computed-torque loop.  The derivations of (4.22)-(4.26)
assume the position loop is accurate (X = X_c).  Under a contact force F a computed-torque loop is a spring of stiffness
M_x Kp (tens of N/m for the light BH8-280 fingertips), so while a finger touches, the controller adds the *desired*
contact force as a feed-forward J^T f_d n: at the force set point the inner loop then has no error and X = X_c exactly.
(Cancelling the *measured* force instead is positive feedback through a one-sample delay and goes unstable on stiff
contacts.)

* :class:`PositionImpedance` (4.20)-(4.21): M_I dx'' + B_I dx' + K_I dx = F_c (the full force on the object).
* :class:`ForceImpedance` (4.22)-(4.26), (4.30): along the normal n, M_I dx'' + B_I dx' + K_I dx = f - f_d with
  f = n . F_c, and the reference's normal component set to x_e + f_d / k_e, which makes the steady force error 0.
* :class:`~bhgrasp.controllers.adaptive_impedance.AdaptiveForceImpedance`
  (4.31)-(4.41): the same with k_e and x_e estimated online.  The environment
  f = k_e (x - x_e) = [x, -1] . [k_e, k_e x_e] is linear in theta = (k_e, k_e x_e), so the gradient law
  theta_hat_dot = -Gamma [x, -1]^T (f_hat - f) makes V = theta~^T Gamma^-1 theta~ / 2 non-increasing
  (V_dot = -(f_hat - f)^2).  In (k_e, x_e) this is exactly (4.40) with gamma_1, gamma_2 on the two components; the
  thesis' (4.36) writes the error as linear in (Delta k_e, Delta x_e), which it is not, and (4.38)-(4.39) use
  f_hat - f_d where the estimator needs f_hat - f.  A recursive least-squares estimator on the same regressor is
  the default: with the gradient law and a constant f_d only the operating point f = f_d is learnt.  Like Seraji
  and Colbaugh's indirect adaptive scheme, estimates move only in contact, and here only while the contact is
  quasi-static (impacts violate f = k_e (x - x_e)); before contact the estimated surface advances at
  ``search_speed`` so that a too-near initial x_e still leads to contact.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from typing import Any

import numpy as np

from bhgrasp._validation import as_positive, as_real, as_unit, as_vector
from bhgrasp.controllers.impedance_filter import ImpedanceFilter, TustinImpedanceFilter, critical_damping
from bhgrasp.errors import InputError
from bhgrasp.grasp.sensing import FingerContact
from bhgrasp.motion.trajectories import Reference

Sample = tuple[np.ndarray, np.ndarray, np.ndarray]
MIN_CONTACT_DAMPING_RATIO = 0.5  # force-based impedance refuses a less damped contact loop (thesis (4.19)'s intent)


class ImpedanceLaw(ABC):
    """One finger's outer loop: desired fingertip trajectory + sensed contact -> commanded trajectory X_c.

    Attributes:
        feed_acceleration: Pass the filter's acceleration on, X_c'' = X_d'' - dx'' (thesis (4.20)-(4.21) as
            printed).  Off by default: see :meth:`_filtered`.
    """

    feed_acceleration: bool = False

    def __init__(
        self, reference: Reference, mass: float, damping: float | None, stiffness: float, period: float | None
    ) -> None:
        """Set up the filter.

        Args:
            reference: X_d (size 3, world [m]).
            mass, damping, stiffness: M_I [kg], B_I [N s/m] (``None``: critical, (4.16)), K_I [N/m].
            period: ``None`` for the continuous filter, else the period T [s] of the Tustin filter (4.48).
        """
        if not isinstance(reference, Reference) or reference.size != 3:
            raise InputError(f"`reference` must be a Reference of size 3 (fingertip position [m]), got {reference!r}")
        self.reference = reference
        self.mass = as_positive(mass, "mass")
        self.stiffness = as_positive(stiffness, "stiffness")
        self.damping = critical_damping(self.mass, self.stiffness) if damping is None else as_real(damping, "damping")
        if period is None:
            self.filter: ImpedanceFilter | TustinImpedanceFilter = ImpedanceFilter(
                self.mass, self.damping, self.stiffness
            )
        else:
            self.filter = TustinImpedanceFilter(self.mass, self.damping, self.stiffness, period)
        self.log: dict[str, Any] = {}

    def reset(self) -> None:
        """Rest the filter (and estimates)."""
        self.filter.reset()

    def feedforward(self, contact: FingerContact) -> np.ndarray:
        """Force [N] (world) the finger should exert on the object now; the inner loop adds J^T of it."""
        return np.zeros(3)

    @abstractmethod
    def command(self, t: float, x: np.ndarray, contact: FingerContact, dt: float) -> Sample:
        """X_c, its velocity and acceleration, for fingertip position ``x`` [m] and the finger's contacts."""

    def _filtered(self, desired: Sample, force: np.ndarray, dt: float) -> Sample:
        """X_c = X_d - dx and its velocity, with X_d's acceleration.

        The filter's acceleration is *not* passed on unless :attr:`feed_acceleration` is set: it is an algebraic
        function of the sensed force, and feeding it to the inner loop closes a force loop through a one-sample
        delay that rings on stiff contacts.
        """
        dx, dx_dot, dx_ddot = self.filter.step(force, dt)
        self.log["delta_x"] = dx
        return desired[0] - dx, desired[1] - dx_dot, desired[2] - dx_ddot if self.feed_acceleration else desired[2]


class PositionImpedance(ImpedanceLaw):
    """PIM (4.20)-(4.21): the contact force drives the impedance error; X_c = X_d - Delta X."""

    def __init__(
        self,
        reference: Reference,
        mass: float = 0.1,
        damping: float | None = None,
        stiffness: float = 200.0,
        period: float | None = None,
    ) -> None:
        """Set up the filter (args as :class:`ImpedanceLaw`).

        Defaults are ours for the BH8-280; the thesis' F3 values M_I = 15, B_I = 780, K_I = 5000 belong to its much
        heavier finger model.
        """
        super().__init__(reference, mass, damping, stiffness, period)

    def command(self, t, x, contact, dt) -> Sample:  # noqa: D102
        self.log["force"] = contact.force
        return self._filtered(self.reference(t), contact.force, dt)


class ForceImpedance(ImpedanceLaw):
    """FIM (4.22)-(4.26) with the reference (4.30) along ``normal``: tracks ``force`` when k_e, x_e are right."""

    def __init__(
        self,
        reference: Reference,
        normal: Any,
        force: float,
        surface: Any,
        environment_stiffness: float,
        mass: float = 0.1,
        damping: float | None = None,
        stiffness: float = 200.0,
        period: float | None = None,
    ) -> None:
        """Set up the force loop.

        Args:
            reference: Approach trajectory (size 3, world [m]); only its components across ``normal`` are kept.
            normal: Direction [unit, world] in which the finger presses into the environment (any 3-D direction).
            force: Desired normal force f_d [N] >= 0, or a profile (Reference of size 1, e.g. a smooth step).
            surface: A point x_e [m] of the environment's unloaded surface (only its normal component matters).
            environment_stiffness: k_e [N/m] > 0 as the fingertip sees it.
            mass, damping, stiffness, period: As :class:`ImpedanceLaw`; ``damping=None`` is critical damping of
                the contact loop (K_I + k_e); a given damping must keep that loop's damping ratio >= 0.5.
        """
        k_e = as_positive(environment_stiffness, "environment_stiffness")
        mass, stiffness = as_positive(mass, "mass"), as_positive(stiffness, "stiffness")
        if damping is None:
            damping = critical_damping(mass, stiffness, k_e)
        minimum = critical_damping(mass, stiffness, k_e, ratio=MIN_CONTACT_DAMPING_RATIO)
        if as_real(damping, "damping") < minimum:
            raise InputError(
                f"`damping` B_I = {damping:g} N s/m violates the damping condition: the contact loop M_I e'' + B_I e' +"
                f" (K_I + k_e) e needs B_I >= {minimum:.4g} (damping ratio {MIN_CONTACT_DAMPING_RATIO}) for M_I ="
                f" {mass:g}, K_I = {stiffness:g}, k_e = {k_e:g}"
            )
        super().__init__(reference, mass, damping, stiffness, period)
        self.normal = as_unit(normal, "normal")
        if isinstance(force, Reference):
            if force.size != 1:
                raise InputError(f"a desired-force profile must be a Reference of size 1 [N], got size {force.size}")
            self.profile: Reference | None = force
            self.force = float(force(0.0)[0][0])
        else:
            self.profile = None
            self.force = as_real(force, "force")
        self.surface = float(self.normal @ as_vector(surface, "surface", 3))
        self.environment_stiffness = k_e
        self._projector = (self.normal, np.eye(3) - np.outer(self.normal, self.normal))

    def target(self) -> float:
        """Normal coordinate [m] of the reference, (4.26)/(4.30): x_e + f_d / k_e."""
        return self.surface + self.force / self.environment_stiffness

    def feedforward(self, contact: FingerContact) -> np.ndarray:
        """f_d n while touching, else nothing."""
        return self.force * self.normal if contact.touching else np.zeros(3)

    def command(self, t, x, contact, dt) -> Sample:  # noqa: D102
        n = self.normal
        if self.profile is not None:
            self.force = float(self.profile(t)[0][0])
            if self.force < 0.0:
                raise InputError(f"desired force must be >= 0 [N], got {self.force} at t = {t} s")
        position, velocity, acceleration = self.reference(t)
        if self._projector[0] is not n:  # I - n n^T, rebuilt when `normal` is replaced
            self._projector = (n, np.eye(3) - np.outer(n, n))
        projector = self._projector[1]
        desired = (projector @ position + self.target() * n, projector @ velocity, projector @ acceleration)
        measured = float(n @ contact.force) if contact.touching else 0.0
        error = (measured - self.force) if contact.touching else 0.0  # the filter acts only in contact (thesis)
        self.log["force"], self.log["force_error"] = measured, self.force - measured
        return self._filtered(desired, error * n, dt)


__all__ = [
    "MIN_CONTACT_DAMPING_RATIO",
    "ForceImpedance",
    "ImpedanceLaw",
    "PositionImpedance",
]
