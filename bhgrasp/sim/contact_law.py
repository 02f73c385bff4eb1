"""The contact force law: a spring-damper normal force and Coulomb friction that sticks, explicit and implicit.

Thesis 4.2 models contact as a spring (4.5)-(4.7) pushing the bodies apart along the contact normal.  Here every
contact point ``i`` between body ``a`` and body ``b`` (normal ``n`` from a to b, depth ``d >= 0``) gets a force
on ``b`` (and its opposite on ``a``, at the same point):

- normal: ``f_n = max(0, k d + c d_dot)`` (linear), or ``max(0, d^e (k + c d_dot))`` (Hunt-Crossley); never pulls;
- tangential, stick-slip (default): an elastic tangential displacement ``u`` (a spring anchored where the contact
  began to stick) gives ``f_t = -k_t u - c_t v_t``; when ``|f_t| > mu f_n`` the contact slides, ``f_t`` is
  projected onto the cone and the anchor follows so that ``k_t |u| = mu f_n``.  A contact that sticks has zero
  creep at equilibrium (no velocity is needed to hold a tangential load);
- tangential, regularised (option, for comparison): ``f_t = -mu f_n tanh(|v_t| / v_s) v_t / |v_t|``, which must
  creep to hold a load.

For the simulator's linearly-implicit step the force is written as ``f(v+) = f0 - D J v+`` (the spring evaluated
at the end of the step): :meth:`ContactForces.linear_parts` and :meth:`ContactForces.linearise` give ``f0`` and
``D``, :meth:`~bhgrasp.sim.contact.ContactEngine.jacobians` the relative Jacobians ``J``;
:meth:`ContactForces.classify` is the active-set rule.  :class:`~bhgrasp.sim.contact.ContactEngine`, which detects
the contacts, is a :class:`ContactForces`; ``src/contact_law.cpp`` is the compiled twin.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np

from bhgrasp._validation import as_positive, as_real
from bhgrasp.data import ContactSet
from bhgrasp.errors import InputError

_IDENTITY3 = np.eye(3)


@dataclass(frozen=True)
class SpringDamper:
    """The contact force law and its parameters.

    Attributes:
        stiffness: Normal stiffness k [N/m] (Hunt-Crossley: [N/m^e]).
        damping: Normal damping c [N s/m] (Hunt-Crossley: [N s/m^(e+1)]).
        friction: Coulomb coefficient of the hand's finger pads (a pair uses the smaller of its two surfaces').
        tangential_stiffness: k_t [N/m] of the stick spring; default ``stiffness``.
        tangential_damping: c_t [N s/m]; default ``damping``.
        normal_law: ``"linear"`` or ``"hunt-crossley"``.
        exponent: Hunt-Crossley exponent e (1.5 for Hertzian spheres).
        friction_law: ``"stick-slip"`` (true static friction) or ``"tanh"`` (regularised, creeps).
        slip_velocity: v_s of the tanh law [m/s].
    """

    stiffness: float = 1e4
    damping: float = 20.0
    friction: float = 0.8
    tangential_stiffness: float | None = None
    tangential_damping: float | None = None
    normal_law: Literal["linear", "hunt-crossley"] = "linear"
    exponent: float = 1.5
    friction_law: Literal["stick-slip", "tanh"] = "stick-slip"
    slip_velocity: float = 1e-3

    def __post_init__(self) -> None:
        as_positive(self.stiffness, "stiffness")
        as_real(self.damping, "damping")
        as_real(self.friction, "friction")
        as_positive(self.exponent, "exponent")
        as_positive(self.slip_velocity, "slip_velocity")
        if self.tangential_stiffness is not None:
            as_positive(self.tangential_stiffness, "tangential_stiffness")
        if self.tangential_damping is not None:
            as_real(self.tangential_damping, "tangential_damping")
        if self.normal_law not in ("linear", "hunt-crossley"):
            raise InputError(f"`normal_law` must be 'linear' or 'hunt-crossley', got {self.normal_law!r}")
        if self.friction_law not in ("stick-slip", "tanh"):
            raise InputError(f"`friction_law` must be 'stick-slip' or 'tanh', got {self.friction_law!r}")

    @property
    def k_t(self) -> float:
        """Tangential stiffness [N/m]."""
        return self.stiffness if self.tangential_stiffness is None else self.tangential_stiffness

    @property
    def c_t(self) -> float:
        """Tangential damping [N s/m]."""
        return self.damping if self.tangential_damping is None else self.tangential_damping


class ContactForces:
    """The force law of a :class:`SpringDamper` on the contacts of a :class:`~bhgrasp.data.contacts.ContactSet`.

    Explicit forces (:meth:`forces`), the linearly-implicit step's parts (:meth:`linear_parts`, :meth:`linearise`)
    and its active set (:meth:`start_status`, :meth:`classify`, :meth:`end_displacement`); the base of
    :class:`~bhgrasp.sim.contact.ContactEngine`, which detects the contacts.
    """

    def __init__(self, law: SpringDamper) -> None:
        """Evaluate ``law``."""
        self.law = law

    # ------------------------------------------------------------------ force law
    def forces(
        self, contacts: ContactSet, velocity: np.ndarray, dt: float = 0.0
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Explicit forces on body b, given relative point velocities (m, 3) [m/s].

        With ``dt`` > 0 the stick spring is evaluated at the end of the step (displacement + dt v_t).

        Returns:
            Forces (m, 3) [N], sticking flags (m,), end-of-step tangential displacements (m, 3) [m].
        """
        law = self.law
        normal = contacts.normal
        v_n = np.einsum("ij,ij->i", velocity, normal)
        v_t = velocity - v_n[:, None] * normal
        depth_rate = -v_n
        weight = contacts.weight
        if law.normal_law == "linear":
            f_n = weight * (law.stiffness * contacts.depth + law.damping * depth_rate)
        else:
            f_n = weight * contacts.depth**law.exponent * (law.stiffness + law.damping * depth_rate)
        f_n = np.maximum(f_n, 0.0)
        cone = contacts.friction * f_n
        if law.friction_law == "tanh":
            speed = np.linalg.norm(v_t, axis=1)
            direction = np.divide(v_t, speed[:, None], out=np.zeros_like(v_t), where=speed[:, None] > 0)
            f_t = -(cone * np.tanh(speed / law.slip_velocity))[:, None] * direction
            sticking = speed < law.slip_velocity
            displacement = np.zeros_like(v_t)
        else:
            displacement = contacts.displacement + dt * v_t
            f_t = -weight[:, None] * (law.k_t * displacement + law.c_t * v_t)
            f_t, sticking, displacement = self.project_on_cone(f_t, cone, displacement, weight)
        forces = f_n[:, None] * normal + f_t
        return forces, sticking, displacement

    # ------------------------------------------------------------------ linearly-implicit form (the simulator)
    def linear_parts(self, contacts: ContactSet, dt: float) -> tuple:
        """Per step, for the implicit solve: ``f0`` and gains ``D`` of the normal law alone and with the stick spring.

        The spring is evaluated at the end of a step of ``dt`` [s]: ``f(v+) = f0 - D J v+``.
        """
        law = self.law
        normal, depth, weight = contacts.normal, contacts.depth, contacts.weight
        outer = normal[:, :, None] * normal[:, None, :]
        if law.normal_law == "linear":
            force = weight * law.stiffness * depth
            gain = weight * (law.stiffness * dt + law.damping)
        else:
            power = depth**law.exponent
            force = weight * law.stiffness * power
            gain = weight * (law.exponent * law.stiffness * depth ** (law.exponent - 1.0) * dt + law.damping * power)
        f0 = force[:, None] * normal
        gains = gain[:, None, None] * outer
        if law.friction_law == "stick-slip":
            f0_stick = f0 - (weight * law.k_t)[:, None] * contacts.displacement
            gains_stick = gains + (weight * (law.k_t * dt + law.c_t))[:, None, None] * (_IDENTITY3 - outer)
        else:
            f0_stick, gains_stick = f0, gains
        return f0, gains, f0_stick, gains_stick

    def linearise(self, parts: tuple, status: np.ndarray, slide_force: np.ndarray):
        """Contact force ``f(v+) = f0 - D J v+`` of each contact in its status (0 off, 1 stick, 2 slide)."""
        f0, gains, f0_stick, gains_stick = parts
        stick = (status == 1)[:, None]
        f_0 = np.where(stick, f0_stick, f0 + slide_force)
        d = np.where(stick[:, :, None], gains_stick, gains)
        off = status == 0
        if off.any():
            f_0[off], d[off] = 0.0, 0.0
        return f_0, d

    def start_status(
        self, contacts: ContactSet, parts: tuple, start_velocity: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """The active set a step starts from: the previous step's stick/slip state.

        A contact that ended the last step sliding and still slips (faster than ``1e-6`` m/s) starts sliding, its
        kinetic friction on the cone of the normal force predicted at the start-of-step velocity, against the slip;
        every other contact starts sticking.  (Starting a fast slider sticking gives it a huge stick force on the
        first pass, which pitches the body and unloads its trailing contacts for the step.  Predicting slip of new
        contacts from the start velocity instead would over-predict it for light bodies whose implicit step stops
        the slip with a small force.)

        Returns:
            Status per contact (1 stick, 2 slide) and the sliding contacts' tangential forces (m, 3) [N].
        """
        m = len(contacts)
        status, slide = np.ones(m, dtype=int), np.zeros((m, 3))
        if self.law.friction_law != "stick-slip" or not contacts.was_sliding.any():
            return status, slide
        f0, gains, _, _ = parts
        normal = contacts.normal
        predicted = f0 - (gains @ start_velocity[:, :, None])[:, :, 0]  # the normal law alone
        cone = contacts.friction * np.maximum((predicted * normal).sum(axis=1), 0.0)
        v_t = start_velocity - (start_velocity * normal).sum(axis=1)[:, None] * normal
        speed = np.sqrt((v_t * v_t).sum(axis=1))
        sliding = contacts.was_sliding & (speed > 1e-6) & (cone > 0.0)
        status[sliding] = 2
        slide[sliding] = -v_t[sliding] * (cone[sliding] / speed[sliding])[:, None]
        return status, slide

    def classify(
        self,
        contacts: ContactSet,
        forces: np.ndarray,
        status: np.ndarray,
        start_velocity: np.ndarray,
        relative: np.ndarray | None = None,
        may_stick: np.ndarray | None = None,
    ) -> tuple[np.ndarray, np.ndarray]:
        """Drop pulling contacts; turn sticking contacts outside the cone into sliding ones (force on the cone).

        A sliding contact in ``may_stick`` whose end-of-step slip ``relative`` runs along its kinetic friction (the
        friction would have reversed the slip: it overshoots) sticks instead.  With the tanh law every contact
        "slides" with the regularised force of its start-of-step slip velocity.
        """
        normal = contacts.normal
        normal_force = (forces * normal).sum(axis=1)
        tangential = forces - normal_force[:, None] * normal
        new_status = np.where(normal_force > 0.0, status, 0)
        cone = contacts.friction * np.maximum(normal_force, 0.0)
        slide = np.zeros_like(forces)
        if self.law.friction_law == "tanh":
            v_t = start_velocity - np.einsum("ij,ij->i", start_velocity, normal)[:, None] * normal
            speed = np.linalg.norm(v_t, axis=1)
            scale = np.divide(np.tanh(speed / self.law.slip_velocity), speed, out=np.zeros_like(speed), where=speed > 0)
            slide = -(cone * scale)[:, None] * v_t
            new_status[new_status == 1] = 2
            return new_status, slide
        magnitude = np.sqrt((tangential * tangential).sum(axis=1))
        sliding = (new_status > 0) & ((magnitude > cone * (1 + 1e-9)) | (status == 2))
        if relative is not None and may_stick is not None:
            v_t = relative - (relative * normal).sum(axis=1)[:, None] * normal
            overshoot = may_stick & (status == 2) & (new_status > 0) & ((tangential * v_t).sum(axis=1) > 0.0)
            new_status[overshoot] = 1
            sliding &= ~overshoot
        if sliding.any():
            new_status[sliding] = 2
            # Kinetic friction lies on the cone, along the direction the sticking spring was pulling.
            slide[sliding] = tangential[sliding] * (cone[sliding] / np.maximum(magnitude[sliding], 1e-300))[:, None]
        return new_status, slide

    def end_displacement(
        self, contacts: ContactSet, relative: np.ndarray, forces: np.ndarray, status: np.ndarray, dt: float
    ) -> np.ndarray:
        """End-of-step tangential spring displacement: integrated while sticking, on the cone edge when sliding."""
        normal = contacts.normal
        v_t = relative - (relative * normal).sum(axis=1)[:, None] * normal
        displacement = contacts.displacement + dt * v_t
        sliding = status == 2
        if sliding.any():
            f_n = (forces[sliding] * normal[sliding]).sum(axis=1)
            tangential = forces[sliding] - f_n[:, None] * normal[sliding]
            displacement[sliding] = -tangential / (contacts.weight[sliding, None] * self.law.k_t)
        displacement[status == 0] = 0.0
        return displacement

    def project_on_cone(
        self, f_t: np.ndarray, cone: np.ndarray, displacement: np.ndarray, weight: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Clip tangential forces to ``|f_t| <= cone``; a sliding contact's anchor follows (w k_t |u| = cone)."""
        magnitude = np.linalg.norm(f_t, axis=1)
        sticking = magnitude <= cone
        sliding = ~sticking
        if np.any(sliding):
            direction = f_t[sliding] / magnitude[sliding, None]
            f_t = f_t.copy()
            f_t[sliding] = cone[sliding, None] * direction
            displacement = displacement.copy()
            displacement[sliding] = -f_t[sliding] / (weight[sliding, None] * self.law.k_t)
        return f_t, sticking, displacement
