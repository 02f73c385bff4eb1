"""The Python engine: the readable reference step of ``Simulator(..., engine="python")``.

Integrators (``integrator=``):

- ``"implicit"`` (default): linearly-implicit Euler.  The stiffness and damping of active contacts, joint-limit
  stops, object springs and joint damping are folded into the velocity solve
  ``(M + dt sum J^T D J + dt (dt K + C)) v+ = M v + dt (tau - h + sum J^T f0 - K q)``, then ``q+ = q (+) dt v+``.
  Contacts whose force would pull are dropped and sticking contacts that leave the friction cone switch to
  sliding (a few active-set passes), so stiff contacts (k up to 5e4 N/m) stay stable at millisecond steps.  The
  passes start from the previous step's stick/slip state, so a contact that is sliding is never forced to stick
  first.
- ``"semi-implicit"``: symplectic Euler with explicit forces (``v+ = v + dt a(q, v)``, ``q+ = q (+) dt v+``).
- ``"rk4"``: classical Runge-Kutta on the manifold with explicit forces, contacts re-detected at each stage.

Free bodies translate world-aligned (``m dv/dt = f``: linear momentum is conserved to round-off in any collision,
friction included) and, with the implicit and semi-implicit steps, turn under an implicit-midpoint gyroscopic torque
that keeps a torque-free body's kinetic energy and ``|I w|`` exactly (the explicit ``w x I w`` gains energy every
step).

Actuation couplings (:class:`~bhgrasp.sim.actuation.BarrettActuation`) enter as a transmission ``T``: the solve is
done for the driven coordinates ``w`` with ``v_hand = T w``.  Contact forces enter the dynamics as generalised
forces ``J^T f``, the same as Pinocchio's ``f_ext`` (tests/test_hand.py checks the identity).

:class:`PythonStep` is the twin of :class:`~bhgrasp.sim.compiled.CompiledStep`: the C++ step (``src/engine.cpp``,
``src/implicit.cpp``) mirrors it function by function, and tests/test_compiled.py steps both in lockstep.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
import pinocchio as pin

from bhgrasp.sim.contact import ContactMemory
from bhgrasp.sim.integrators import gyroscopic_torque, spin_midpoint

if TYPE_CHECKING:
    from bhgrasp.sim.simulator import Simulator

_FRICTION_VELOCITY = 1e-3  # [rad/s] regularisation of Coulomb joint friction


class PythonStep:
    """A simulator's physics step in Python, on its scene, contact engine, actuation and options (read live)."""

    def __init__(self, simulator: Simulator) -> None:
        """Step ``simulator``'s scene; what only this engine needs (joint limits, index arrays) is kept here."""
        self._simulator = simulator
        scene = simulator.scene
        self._lower, self._upper = scene.hand.lower, scene.hand.upper
        self._object_identity = np.eye(scene.nv - scene.nv_hand)
        self._lower_triangle = np.tril_indices(scene.nv, -1)

    def step(self, q: np.ndarray, v: np.ndarray, tau_hand: np.ndarray, memory: ContactMemory):
        """One step from a :class:`~bhgrasp.sim.contact_set.ContactMemory`.

        Returns (q+, v+, contacts with forces, drive torques [N m], memory, divergence), as
        :meth:`~bhgrasp.sim.compiled.CompiledStep.step` does; the divergence is ``None``: the simulator checks.
        """
        simulator = self._simulator
        simulator.engine.memory = memory
        if simulator.integrator == "implicit":
            q_next, v_next, contacts, drive = self._implicit(q, v, tau_hand)
        else:
            q_next, v_next, contacts, drive = self._explicit(q, v, tau_hand)
        return q_next, v_next, contacts, drive, simulator.engine.memory, None

    # ------------------------------------------------------------------ joint space
    def _implicit_gyroscopic(self, v: np.ndarray, bias: np.ndarray) -> None:
        """Replace each free body's explicit gyroscopic torque ``w x I w`` in ``bias`` by the implicit midpoint one.

        The torque-free spin over the step solves ``I (w+ - w) / dt + m x I m = 0`` with ``m = (w + w+) / 2``
        (Newton, to round-off); dotting with ``m`` and ``I m`` shows that it keeps the kinetic energy
        ``w.I w / 2`` and the body angular momentum's length ``|I w|`` exactly, at any step (explicit ``w x I w``
        gains energy at every step).  The step then uses ``m x I m`` as the body's gyroscopic torque.
        """
        for angular, axes, moments in self._simulator._spinning:
            w = axes.T @ v[angular]  # in the principal axes
            if moments[0] == moments[1] == moments[2] or not w.any():
                continue  # a sphere's (or a resting body's) gyroscopic torque is 0
            explicit = gyroscopic_torque(moments, w)
            middle = spin_midpoint(moments, w, 0.5 * self._simulator.dt)
            bias[angular] += axes @ (gyroscopic_torque(moments, middle) - explicit)

    def _increment_rate(self, increment: np.ndarray, v: np.ndarray) -> np.ndarray:
        """Rate of the increment ``theta`` in ``q (+) theta`` at velocity ``v``.

        A body's rotation ``R exp(theta)`` turns at body rate ``w`` when ``theta`` changes at
        ``dexp^-1_{-theta}(w) = w + theta x w / 2 + theta x (theta x w) / 12`` (to O(theta^3), enough for RK4); hand
        joints and translations are vector spaces, whose increments change at ``v``.
        """
        rate = v.copy()
        for angular, _, _ in self._simulator._spinning:
            theta, w = increment[angular], v[angular]
            half = np.cross(theta, w)
            rate[angular] = w + 0.5 * half + np.cross(theta, half) / 12.0
        return rate

    def _motor_damping(self) -> np.ndarray:
        """The drive's own damping (joint damping of the actuation minus the passive joints')."""
        actuation = self._simulator.actuation
        return actuation.joint_damping() - actuation.damping

    def _mass_matrix(self, q: np.ndarray) -> np.ndarray:
        mass = pin.crba(self._simulator.model, self._simulator.data, q).copy()
        mass[self._lower_triangle] = mass.T[self._lower_triangle]
        return mass

    def _transmission(self) -> np.ndarray:
        hand = self._simulator.actuation.transmission()
        rows, cols = hand.shape
        full = np.zeros((self._simulator.scene.nv, cols + len(self._object_identity)))
        full[:rows, :cols] = hand
        full[rows:, cols:] = self._object_identity
        return full

    def _passive(self, q: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Joint-space springs/dampers: explicit torque, implicit stiffness K and damping C (diagonals).

        Object springs (spring-mounted objects, rest at 0), joint stops (only while penetrated), joint damping and
        regularised joint friction (linearised about ``v``).
        """
        simulator = self._simulator
        scene = simulator.scene
        nvh, nqh = simulator._nvh, scene.nq_hand
        stiffness = scene.joint_stiffness.copy()
        damping = scene.joint_damping.copy()
        torque = np.zeros(scene.nv)
        if len(simulator._spring_v):
            torque[simulator._spring_v] = -scene.joint_stiffness[simulator._spring_v] * q[simulator._spring_q]
        damping[:nvh] += simulator.actuation.joint_damping()
        friction = simulator.actuation.friction
        if friction.any():
            ratio = v[:nvh] / _FRICTION_VELOCITY
            decay = np.exp(-2.0 * np.abs(ratio))  # sech^2 = 4 e^-2|x| / (1 + e^-2|x|)^2: cosh overflows past 0.7 rad/s
            slope = friction / _FRICTION_VELOCITY * (4.0 * decay / (1.0 + decay) ** 2)
            torque[:nvh] += slope * v[:nvh] - friction * np.tanh(ratio)
            damping[:nvh] += slope
        q_hand = q[:nqh]
        stop = np.clip(q_hand, self._lower, self._upper)
        active = stop != q_hand
        if active.any():
            torque[:nvh] -= simulator.limit_stiffness * (q_hand - stop)
            stiffness[:nvh] += active * simulator.limit_stiffness
            damping[:nvh] += active * simulator.limit_damping
        return torque, stiffness, damping

    # ------------------------------------------------------------------ the implicit step
    def _implicit(self, q: np.ndarray, v: np.ndarray, tau_hand: np.ndarray):
        simulator = self._simulator
        dt, model, data = simulator.dt, simulator.model, simulator.data
        engine, nv = simulator.engine, simulator.scene.nv
        contacts = engine.detect(q)
        pin.computeJointJacobians(model, data, q)
        mass = self._mass_matrix(q)
        bias = pin.nonLinearEffects(model, data, q, v).copy()
        self._implicit_gyroscopic(v, bias)
        passive, stiffness, damping = self._passive(q, v)
        tau = np.zeros(nv)
        tau[: len(tau_hand)] = tau_hand  # hand joint torques, or with external forces on the objects' coordinates
        # Springs acting on joint coordinates (limits, object springs): the explicit torque is in `passive`;
        # their stiffness acts on the displacement dt v+ of this step.
        matrix = mass + dt * np.diag(dt * stiffness + damping)
        rhs = mass @ v + dt * (tau - bias + passive)
        transmission = self._transmission()
        m = len(contacts)
        if m == 0:  # free motion: one linear solve, no contact bookkeeping
            reduced = transmission.T @ matrix @ transmission
            v_next = transmission @ np.linalg.solve(reduced, transmission.T @ rhs)
            contacts.force, contacts.sticking = np.zeros((0, 3)), np.zeros(0, dtype=bool)
            engine.remember(contacts, np.zeros((0, 3)), np.zeros(0, dtype=bool))
            drive = self._drive(mass, v, v_next, bias - passive, dt * stiffness + damping)
            return pin.integrate(model, q, v_next * dt), v_next, contacts, drive
        jacobians = engine.jacobians(contacts)
        start_velocity = jacobians @ v
        stacked = jacobians.reshape(-1, nv)  # (3m, nv)
        parts = engine.linear_parts(contacts, dt)
        status, slide_force = engine.start_status(contacts, parts, start_velocity)  # 0 off, 1 stick, 2 slide
        may_stick = status == 2  # a contact that starts sliding may stick once, if its friction would overshoot
        for _ in range(8):
            f0, gains = engine.linearise(parts, status, slide_force)
            matrix_c = matrix + dt * stacked.T @ (gains @ jacobians).reshape(-1, nv)
            rhs_c = rhs + dt * stacked.T @ f0.ravel()
            reduced = transmission.T @ matrix_c @ transmission
            v_next = transmission @ np.linalg.solve(reduced, transmission.T @ rhs_c)
            relative = jacobians @ v_next
            forces = f0 - (gains @ relative[:, :, None])[:, :, 0]
            new_status, new_slide = engine.classify(contacts, forces, status, start_velocity, relative, may_stick)
            if (new_status == status).all() and (
                not (status == 2).any() or np.abs(new_slide - slide_force).max() < 1e-12
            ):
                break
            may_stick &= new_status == 2
            status, slide_force = new_status, new_slide
        forces[status == 0] = 0.0
        displacement = engine.end_displacement(contacts, relative, forces, status, dt)
        contacts.force, contacts.sticking = forces, status == 1
        engine.remember(contacts, displacement, status == 2)
        generalized = stacked.T @ forces.ravel()
        drive = self._drive(mass, v, v_next, bias - generalized - passive, dt * stiffness + damping)
        return pin.integrate(model, q, v_next * dt), v_next, contacts, drive

    def _drive(self, mass, v, v_next, forces, implicit_damping) -> np.ndarray:
        """Hand joint torques the drive delivered over the step (M a + bias - contact - passive + implicit terms).

        ``forces`` is bias - contact - passive torques, ``implicit_damping`` the diagonal (dt K + C) acting on v+.
        """
        nvh = self._simulator._nvh
        drive = (mass @ ((v_next - v) / self._simulator.dt) + forces + implicit_damping * v_next)[:nvh]
        return drive - self._motor_damping() * v_next[:nvh]  # the clutch passes what the motor's losses leave

    # ------------------------------------------------------------------ the explicit steps
    def _explicit(self, q: np.ndarray, v: np.ndarray, tau_hand: np.ndarray):
        simulator = self._simulator
        dt, model = simulator.dt, simulator.model
        tau = np.zeros(simulator.scene.nv)
        tau[: len(tau_hand)] = tau_hand
        transmission = self._transmission()
        if simulator.integrator == "semi-implicit":
            acceleration, contacts, forces, sticking, displacement, drive = self._acceleration(q, v, tau, transmission)
            v_next = v + dt * acceleration
            q_next = pin.integrate(model, q, v_next * dt)
        else:
            # Runge-Kutta-Munthe-Kaas: each stage's configuration is q (+) theta, and a body's rotation increment
            # theta grows at dexp^-1_{-theta}(w), not w (adding the stages' w is second order on SO(3)).
            k1, contacts, forces, sticking, displacement, drive = self._acceleration(q, v, tau, transmission)
            v2 = v + dt / 2 * k1
            q2 = pin.integrate(model, q, v * dt / 2)
            rate2 = self._increment_rate(v * dt / 2, v2)
            k2 = self._acceleration(q2, v2, tau, transmission)[0]
            v3 = v + dt / 2 * k2
            q3 = pin.integrate(model, q, rate2 * dt / 2)
            rate3 = self._increment_rate(rate2 * dt / 2, v3)
            k3 = self._acceleration(q3, v3, tau, transmission)[0]
            v4 = v + dt * k3
            q4 = pin.integrate(model, q, rate3 * dt)
            rate4 = self._increment_rate(rate3 * dt, v4)
            k4 = self._acceleration(q4, v4, tau, transmission)[0]
            v_next = v + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
            q_next = pin.integrate(model, q, dt / 6 * (v + 2 * rate2 + 2 * rate3 + rate4))
        contacts.force, contacts.sticking = forces, sticking
        simulator.engine.remember(contacts, displacement, ~sticking)
        return q_next, v_next, contacts, drive

    def _acceleration(self, q: np.ndarray, v: np.ndarray, tau: np.ndarray, transmission: np.ndarray):
        """Explicit accelerations at (q, v) (contacts detected at q), with the step's contact bookkeeping."""
        simulator = self._simulator
        model, data, engine, nvh = simulator.model, simulator.data, simulator.engine, simulator._nvh
        contacts = engine.detect(q)
        pin.computeJointJacobians(model, data, q)
        passive, _, damping = self._passive(q, v)
        total = tau + passive - damping * v
        forces, sticking, displacement = np.zeros((len(contacts), 3)), np.zeros(len(contacts), bool), None
        generalized = np.zeros(simulator.scene.nv)
        if len(contacts):
            jacobians = engine.jacobians(contacts)
            relative = np.einsum("mij,j->mi", jacobians, v)
            forces, sticking, displacement = engine.forces(contacts, relative, simulator.dt)
            generalized = np.einsum("mij,mi->j", jacobians, forces)
        mass = self._mass_matrix(q)
        bias = pin.nonLinearEffects(model, data, q, v).copy()
        if simulator.integrator == "semi-implicit":  # RK4's explicit stages are accurate to O(dt^4) as they are
            self._implicit_gyroscopic(v, bias)
        reduced = transmission.T @ mass @ transmission
        acceleration = transmission @ np.linalg.solve(reduced, transmission.T @ (total + generalized - bias))
        drive = (mass @ acceleration + bias - generalized - passive + damping * v)[:nvh]
        drive -= self._motor_damping() * v[:nvh]
        if displacement is None:
            displacement = np.zeros((0, 3))
        return acceleration, contacts, forces, sticking, displacement, drive


__all__ = ["PythonStep"]
