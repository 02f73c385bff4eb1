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

:class:`PythonEngine` is the twin of :class:`~bhgrasp.sim.compiled.CompiledEngine`: the C++ step (``src/engine.cpp``,
``src/implicit.cpp``) mirrors it function by function, and tests/test_compiled.py steps both in lockstep.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import scipy.sparse as sparse

from bhgrasp.data import ContactMemory, ContactSet
from bhgrasp.sim.contact import ContactEngine
from bhgrasp.sim.contact_law import SpringDamper
from bhgrasp.sim.engine import DriveTerms, StepResult, divergence
from bhgrasp.sim.integrators import implicit_gyroscopic, increment_rate
from bhgrasp.sim.part_system import PartSystem, block_diagonal
from bhgrasp.sim.scene import Scene
from bhgrasp.sim.scene_layout import SceneLayout
from bhgrasp.sim.scene_parts import SceneParts
from bhgrasp.sim.settings import SimulatorSettings

_FRICTION_VELOCITY = 1e-3  # [rad/s] regularisation of Coulomb joint friction


class PythonEngine:
    """The physics step in Python on one scene, contact law and settings (the engine protocol).

    Its Pinocchio and coal work space is its own (the scene's parts, :mod:`~bhgrasp.sim.scene_parts`): engines of one
    scene share nothing.
    """

    name = "python"

    def __init__(
        self, scene: Scene, layout: SceneLayout, law: SpringDamper, settings: SimulatorSettings, match_radius: float
    ) -> None:
        """Prepare the step: the scene's parts of its own, the contact engine, what the step reads every time."""
        self.scene, self.settings = scene, settings
        self.parts = SceneParts(scene.hand_model, scene.model)
        self.contacts = ContactEngine(scene, law, match_radius, parts=self.parts)
        self._lower, self._upper = scene.hand.lower, scene.hand.upper
        self._sparse = settings.solves_sparse(scene.nv)  # the implicit step's velocity system by parts (part_system)
        self._system = PartSystem()
        self._object_identity = None if self._sparse else np.eye(scene.nv - scene.nv_hand)
        self._spinning = layout.spinning_bodies
        self._spring_q, self._spring_v = layout.spring_q, layout.spring_v

    def drive(self, terms: DriveTerms) -> DriveTerms:
        """The drive's terms, as this engine's step takes them (unchanged)."""
        return terms

    def memory(self, memory: ContactMemory) -> ContactMemory:
        """A contact memory, as this engine's step takes it (unchanged)."""
        return memory

    def contact_set(self, contacts: ContactSet) -> ContactSet:
        """A step's contacts (already a ContactSet)."""
        return contacts

    def contact_memory(self, memory: ContactMemory) -> ContactMemory:
        """A step's memory (already a ContactMemory)."""
        return memory

    def detect(self, q: np.ndarray, memory: ContactMemory) -> ContactSet:
        """The contacts at ``q`` matched to ``memory`` (no forces)."""
        return self.contacts.detect(q, memory)

    def step(
        self, q: np.ndarray, v: np.ndarray, tau_hand: np.ndarray, drive: DriveTerms, memory: ContactMemory
    ) -> StepResult:
        """One step from a :class:`~bhgrasp.data.contacts.ContactMemory`, with the drive's current terms.

        Returns the :class:`~bhgrasp.sim.engine.StepResult`, its divergence checked as the compiled step checks it.
        """
        if self.settings.integrator == "implicit":
            q_next, v_next, contacts, (torques, load), memory = self._implicit(q, v, tau_hand, drive, memory)
        else:
            q_next, v_next, contacts, (torques, load), memory = self._explicit(q, v, tau_hand, drive, memory)
        checked = divergence(q_next, v_next, contacts, self.settings)
        return StepResult(q_next, v_next, contacts, torques, memory, checked, load)

    # ------------------------------------------------------------------ joint space
    def _transmission(self, drive: DriveTerms) -> np.ndarray:
        hand = drive.transmission
        rows, cols = hand.shape
        full = np.zeros((self.scene.nv, cols + len(self._object_identity)))
        full[:rows, :cols] = hand
        full[rows:, cols:] = self._object_identity
        return full

    def _passive(self, q: np.ndarray, v: np.ndarray, drive: DriveTerms) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Joint-space springs/dampers: explicit torque, implicit stiffness K and damping C (diagonals).

        Object springs (spring-mounted objects, rest at 0), joint stops (only while penetrated), joint damping and
        regularised joint friction (linearised about ``v``).
        """
        scene, settings = self.scene, self.settings
        nvh, nqh = scene.nv_hand, scene.nq_hand
        stiffness = scene.joint_stiffness.copy()
        damping = scene.joint_damping.copy()
        torque = np.zeros(scene.nv)
        if len(self._spring_v):
            torque[self._spring_v] = -scene.joint_stiffness[self._spring_v] * q[self._spring_q]
        damping[:nvh] += drive.joint_damping
        friction = drive.friction
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
            torque[:nvh] -= settings.joint_limit_stiffness * (q_hand - stop)
            stiffness[:nvh] += active * settings.joint_limit_stiffness
            damping[:nvh] += active * settings.joint_limit_damping
        return torque, stiffness, damping

    # ------------------------------------------------------------------ the implicit step
    def _implicit(self, q: np.ndarray, v: np.ndarray, tau_hand: np.ndarray, drive: DriveTerms, memory: ContactMemory):
        dt, model, parts = self.settings.dt, self.scene.model, self.parts
        engine, nv = self.contacts, self.scene.nv
        contacts = engine.detect(q, memory)
        parts.compute_joint_jacobians(q)
        by_parts, system = self._sparse, self._system
        mass = block_diagonal(parts.mass_blocks(q)) if by_parts else parts.mass_matrix(q)
        bias = parts.nonlinear_effects(q, v)
        implicit_gyroscopic(bias, v, self._spinning, self.settings.dt)
        passive, stiffness, damping = self._passive(q, v, drive)
        tau = np.zeros(nv)
        tau[: len(tau_hand)] = tau_hand  # hand joint torques, or with external forces on the objects' coordinates
        # Springs acting on joint coordinates (limits, object springs): the explicit torque is in `passive`;
        # their stiffness acts on the displacement dt v+ of this step.
        rhs = mass @ v + dt * (tau - bias + passive)
        if by_parts:
            system.begin(drive.transmission, sparse.csr_array(mass + sparse.diags(dt * (dt * stiffness + damping))))
        else:
            matrix = mass + dt * np.diag(dt * stiffness + damping)
            transmission = self._transmission(drive)
        m = len(contacts)
        if m == 0:  # free motion: one linear solve, no contact bookkeeping
            if by_parts:
                v_next = system.solve(None, np.zeros((0, 3, 3)), dt, rhs)
            else:
                reduced = transmission.T @ matrix @ transmission
                v_next = transmission @ np.linalg.solve(reduced, transmission.T @ rhs)
            contacts.force, contacts.sticking = np.zeros((0, 3)), np.zeros(0, dtype=bool)
            memory = engine.remember(contacts, np.zeros((0, 3)), np.zeros(0, dtype=bool))
            torques = self._drive(mass, v, v_next, bias - passive, dt * stiffness + damping, drive)
            return pin.integrate(model, q, v_next * dt), v_next, contacts, torques, memory
        if by_parts:
            stacked = engine.part_jacobians(contacts)  # (3m, nv), sparse
            start_velocity = (stacked @ v).reshape(m, 3)
        else:
            jacobians = engine.jacobians(contacts)
            start_velocity = jacobians @ v
            stacked = jacobians.reshape(-1, nv)  # (3m, nv)
        parts = engine.linear_parts(contacts, dt)
        status, slide_force = engine.start_status(contacts, parts, start_velocity)  # 0 off, 1 stick, 2 slide
        may_stick = status == 2  # a contact that starts sliding may stick once, if its friction would overshoot
        for _ in range(8):
            f0, gains = engine.linearise(parts, status, slide_force)
            rhs_c = rhs + dt * stacked.T @ f0.ravel()
            if by_parts:
                v_next = system.solve(stacked, gains, dt, rhs_c)
                relative = (stacked @ v_next).reshape(m, 3)
            else:
                matrix_c = matrix + dt * stacked.T @ (gains @ jacobians).reshape(-1, nv)
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
        memory = engine.remember(contacts, displacement, status == 2)
        generalized = stacked.T @ forces.ravel()
        torques = self._drive(mass, v, v_next, bias - generalized - passive, dt * stiffness + damping, drive)
        return pin.integrate(model, q, v_next * dt), v_next, contacts, torques, memory

    def _drive(self, mass, v, v_next, forces, implicit_damping, drive: DriveTerms) -> tuple[np.ndarray, np.ndarray]:
        """The drive's hand joint torques over the step, and the links' load (the same less their inertia M a).

        The drive delivered M a + bias - contact - passive + implicit terms; ``forces`` is bias - contact - passive
        torques, ``implicit_damping`` the diagonal (dt K + C) acting on v+.
        """
        nvh = self.scene.nv_hand
        inertial = mass @ ((v_next - v) / self.settings.dt)
        torques = (inertial + forces + implicit_damping * v_next)[:nvh]
        torques = torques - drive.motor_damping * v_next[:nvh]  # the clutch passes what the motor's losses leave
        return torques, torques - inertial[:nvh]

    # ------------------------------------------------------------------ the explicit steps
    def _explicit(self, q: np.ndarray, v: np.ndarray, tau_hand: np.ndarray, drive: DriveTerms, memory: ContactMemory):
        dt, model = self.settings.dt, self.scene.model
        tau = np.zeros(self.scene.nv)
        tau[: len(tau_hand)] = tau_hand
        transmission = self._transmission(drive)
        if self.settings.integrator == "semi-implicit":
            acceleration, contacts, forces, sticking, displacement, torques = self._acceleration(
                q, v, tau, transmission, drive, memory
            )
            v_next = v + dt * acceleration
            q_next = pin.integrate(model, q, v_next * dt)
        else:
            # Runge-Kutta-Munthe-Kaas: each stage's configuration is q (+) theta, and a body's rotation increment
            # theta grows at dexp^-1_{-theta}(w), not w (adding the stages' w is second order on SO(3)).
            k1, contacts, forces, sticking, displacement, torques = self._acceleration(
                q, v, tau, transmission, drive, memory
            )
            v2 = v + dt / 2 * k1
            q2 = pin.integrate(model, q, v * dt / 2)
            rate2 = increment_rate(v * dt / 2, v2, self._spinning)
            k2 = self._acceleration(q2, v2, tau, transmission, drive, memory)[0]
            v3 = v + dt / 2 * k2
            q3 = pin.integrate(model, q, rate2 * dt / 2)
            rate3 = increment_rate(rate2 * dt / 2, v3, self._spinning)
            k3 = self._acceleration(q3, v3, tau, transmission, drive, memory)[0]
            v4 = v + dt * k3
            q4 = pin.integrate(model, q, rate3 * dt)
            rate4 = increment_rate(rate3 * dt, v4, self._spinning)
            k4 = self._acceleration(q4, v4, tau, transmission, drive, memory)[0]
            v_next = v + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
            q_next = pin.integrate(model, q, dt / 6 * (v + 2 * rate2 + 2 * rate3 + rate4))
        contacts.force, contacts.sticking = forces, sticking
        memory = self.contacts.remember(contacts, displacement, ~sticking)
        return q_next, v_next, contacts, torques, memory

    def _acceleration(
        self,
        q: np.ndarray,
        v: np.ndarray,
        tau: np.ndarray,
        transmission: np.ndarray,
        drive: DriveTerms,
        memory: ContactMemory,
    ):
        """Explicit accelerations at (q, v) (contacts detected at q), with the step's contact bookkeeping."""
        parts, engine, nvh = self.parts, self.contacts, self.scene.nv_hand
        contacts = engine.detect(q, memory)
        parts.compute_joint_jacobians(q)
        passive, _, damping = self._passive(q, v, drive)
        total = tau + passive - damping * v
        forces, sticking, displacement = np.zeros((len(contacts), 3)), np.zeros(len(contacts), bool), None
        generalized = np.zeros(self.scene.nv)
        if len(contacts):
            jacobians = engine.jacobians(contacts)
            relative = np.einsum("mij,j->mi", jacobians, v)
            forces, sticking, displacement = engine.forces(contacts, relative, self.settings.dt)
            generalized = np.einsum("mij,mi->j", jacobians, forces)
        mass = parts.mass_matrix(q)
        bias = parts.nonlinear_effects(q, v)
        if self.settings.integrator == "semi-implicit":  # RK4's explicit stages are accurate to O(dt^4) as they are
            implicit_gyroscopic(bias, v, self._spinning, self.settings.dt)
        reduced = transmission.T @ mass @ transmission
        acceleration = transmission @ np.linalg.solve(reduced, transmission.T @ (total + generalized - bias))
        inertial = mass @ acceleration
        torques = (inertial + bias - generalized - passive + damping * v)[:nvh]
        torques -= drive.motor_damping * v[:nvh]
        if displacement is None:
            displacement = np.zeros((0, 3))
        return acceleration, contacts, forces, sticking, displacement, (torques, torques - inertial[:nvh])


__all__ = ["PythonEngine"]
