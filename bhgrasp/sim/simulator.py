"""Simulator: fixed-step integration of a scene (hand + objects + contacts) under a controller.

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
step).  A run depends only on its inputs: the :class:`~bhgrasp.sim.state.State` carries the contact memory (tangential
springs, stick/slip) and the actuation modes, so a step depends only on its state and inputs, never on the steps
or runs before it.

Two engines run this physics: ``engine="compiled"`` (the default; the step in C++, ``src/engine.cpp``, through
:mod:`bhgrasp.sim.compiled`) and ``engine="python"`` (the methods below, the readable reference); tests/test_compiled.py
steps both in lockstep.

Actuation couplings (:class:`~bhgrasp.sim.actuation.BarrettActuation`) enter as a transmission ``T``: the solve is
done for the driven coordinates ``w`` with ``v_hand = T w``.  Contact forces enter the dynamics as generalised
forces ``J^T f``, the same as Pinocchio's ``f_ext`` (tests/test_hand.py checks the identity).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np
import pinocchio as pin

from bhgrasp._validation import as_array, as_positive, as_vector
from bhgrasp.errors import InputError, SimulationDiverged
from bhgrasp.objects import RigidObject
from bhgrasp.sim.actuation import Actuation, FullyActuated
from bhgrasp.sim.compiled import CompiledStep, contact_set, memory_of
from bhgrasp.sim.contact import ContactEngine, ContactMemory, ContactSet, SpringDamper, empty_contact_set
from bhgrasp.sim.integrators import gyroscopic_torque, spin_midpoint
from bhgrasp.sim.recorder import Recorder
from bhgrasp.sim.scene import Scene
from bhgrasp.sim.sensor_model import SensorModel, Sensors
from bhgrasp.sim.state import SimulatedState, State, Trajectory

INTEGRATORS = ("implicit", "semi-implicit", "rk4")
ENGINES = ("compiled", "python")
_FRICTION_VELOCITY = 1e-3  # [rad/s] regularisation of Coulomb joint friction


class StepInfo:
    """What one step computed, beyond the new state: contacts with their forces and the drive torques.

    Attributes:
        contacts: The step's contacts and forces, a :class:`~bhgrasp.sim.contact.ContactSet` (built when first read).
        drive_torques: Hand joint torques the drive delivered over the step [N m], (nv_hand,).
        contact_arrays: The contacts as the engine returned them: a ``ContactSet``, or the compiled engine's
            ``Contacts``; both carry the arrays ``pair``, ``point``, ``normal``, ``depth``, ``force``, ``sticking``.
    """

    __slots__ = ("_contacts", "contact_arrays", "drive_torques")

    def __init__(self, contacts: Any, drive_torques: np.ndarray) -> None:
        self.contact_arrays, self.drive_torques, self._contacts = contacts, drive_torques, None

    @property
    def contacts(self) -> ContactSet:
        """The step's contacts as a :class:`~bhgrasp.sim.contact.ContactSet` (built on first read, then kept)."""
        if self._contacts is None:
            arrays = self.contact_arrays
            self._contacts = arrays if isinstance(arrays, ContactSet) else contact_set(arrays)
        return self._contacts


class _StepOutput:
    """What a step hands to its :class:`~bhgrasp.sim.state.SimulatedState` to build derived fields from.

    ``contacts``: the step's ``ContactSet`` or compiled ``Contacts``; ``memory``: its ``ContactMemory`` or
    compiled ``Memory``.
    """

    __slots__ = ("contacts", "memory", "simulator")

    def __init__(self, simulator: Simulator, contacts: Any, memory: Any) -> None:
        self.simulator, self.contacts, self.memory = simulator, contacts, memory

    def derive(self, name: str, state: State) -> dict[str, Any]:
        """The derived field ``name`` of ``state`` (and its companions computed on the way)."""
        simulator = self.simulator
        if name in ("q", "v"):
            return {"q": state.scene_q[: simulator.scene.nq_hand].copy(), "v": state.scene_v[: simulator._nvh].copy()}
        if name in ("object_poses", "object_twists"):
            poses, twists = simulator._objects(state.scene_q, state.scene_v)
            return {"object_poses": poses, "object_twists": twists}
        if name == "contact_memory":
            memory = self.memory
            return {"contact_memory": memory if isinstance(memory, ContactMemory) else memory_of(memory)}
        contacts = self.contacts
        if not len(contacts):
            contacts = empty_contact_set()
        bodies = simulator._pair_bodies
        return {
            "contact_points": contacts.point, "contact_normals": contacts.normal, "contact_forces": contacts.force,
            "contact_bodies": tuple(bodies[k] for k in contacts.pair),
        }  # fmt: skip


class Simulator:
    """Fixed-step simulator of a :class:`~bhgrasp.sim.scene.Scene`."""

    def __init__(
        self,
        scene: Scene,
        dt: float = 1e-3,
        contact: SpringDamper | None = None,
        actuation: Actuation | None = None,
        integrator: str = "implicit",
        joint_limit_stiffness: float = 1e3,
        joint_limit_damping: float = 0.05,
        max_penetration: float = 0.02,
        max_speed: float = 100.0,
        engine: str = "compiled",
    ) -> None:
        """Set up the simulation.

        Args:
            scene: Hand, objects and environment.
            dt: Physics step [s].
            contact: Contact law (default ``SpringDamper()``: k = 1e4 N/m, c = 20 N s/m, mu = 0.8).
            actuation: Input model (default ``FullyActuated(scene.hand)``: one torque per joint).
            integrator: ``"implicit"``, ``"semi-implicit"`` or ``"rk4"``.
            joint_limit_stiffness: Stiffness [N m/rad] of the hand's joint stops.
            joint_limit_damping: Damping [N m s/rad] of the stops (acts only while a stop is penetrated).
            max_penetration: Contact depth [m] beyond which the run is declared diverged.
            max_speed: Joint or object speed [m/s or rad/s] beyond which the run is declared diverged.
            engine: ``"compiled"`` (the C++ step of ``bhgrasp._core``) or ``"python"`` (the readable reference
                implementation; the same physics, tests/test_compiled.py holds them in lockstep).

        Raises:
            CompiledEngineUnavailable: ``engine="compiled"`` but the C++ core was not built.
        """
        if integrator not in INTEGRATORS:
            raise InputError(f"`integrator` must be one of {INTEGRATORS}, got {integrator!r}")
        if engine not in ENGINES:
            raise InputError(f"`engine` must be one of {ENGINES}, got {engine!r}")
        self.scene = scene
        self.dt = as_positive(dt, "dt")
        self.law = contact if contact is not None else SpringDamper()
        self.actuation = actuation if actuation is not None else FullyActuated(scene.hand)
        if self.actuation.hand is not scene.hand:
            raise InputError("`actuation` must be built for the scene's hand (`Actuation(scene.hand, ...)`)")
        self.integrator = integrator
        self.limit_stiffness = as_positive(joint_limit_stiffness, "joint_limit_stiffness")
        self.limit_damping = float(joint_limit_damping)
        self.max_penetration = as_positive(max_penetration, "max_penetration")
        self.max_speed = as_positive(max_speed, "max_speed")
        self.engine = ContactEngine(scene, self.law)
        self.model, self.data = scene.model, scene.data
        self._nvh = scene.nv_hand
        self._hand_sizes = (scene.nq_hand, scene.nv_hand)
        kind = type(self.actuation)  # an actuation without modes needs no restore or update around each step
        self._modal = not (kind.restore is Actuation.restore and kind.reset is Actuation.reset
                           and kind.update is Actuation.update and kind.begin is Actuation.begin)  # fmt: skip
        self._lower, self._upper = scene.hand.lower, scene.hand.upper
        self._object_identity = np.eye(scene.nv - self._nvh)
        self._lower_triangle = np.tril_indices(scene.nv, -1)
        self._pair_bodies = [(pair.body_a, pair.body_b) for pair in scene.pairs]
        # free bodies: angular velocity coordinates, principal axes (columns, body frame) and moments [kg m^2]
        self._spinning = []
        for i, item in enumerate(scene.objects):
            if isinstance(item, RigidObject):
                moments, axes = np.linalg.eigh(item.spatial_inertia().inertia)
                angular = slice(scene.object_v_slice(i).start + 3, scene.object_v_slice(i).stop)
                self._spinning.append((angular, axes, tuple(float(x) for x in moments)))
        springs = [i for i, item in enumerate(scene.objects) if hasattr(item, "stiffness")]
        self._spring_q = np.array([scene.object_q_slice(i).start for i in springs], dtype=int)
        self._spring_v = np.array([scene.object_v_slice(i).start for i in springs], dtype=int)
        self.engine_name = engine
        self._compiled = CompiledStep(self) if engine == "compiled" else None

    # ------------------------------------------------------------------ states
    def initial_state(self, q_hand: Any = None) -> State:
        """The scene at rest with the hand at ``q_hand`` (default neutral) and objects as described."""
        q_hand = None if q_hand is None else as_vector(q_hand, "q_hand", self.scene.nq_hand)
        q, v = self.scene.initial_state(q_hand)
        self.engine.reset()
        self.actuation.reset(q[: self.scene.nq_hand])
        memory = ContactMemory.empty()
        contacts = self.engine.detect(q) if self._compiled is None else self._compiled.detect(q, memory)
        return self._state(0.0, q, v, contacts, memory)

    def _state(self, t: float, q: np.ndarray, v: np.ndarray, contacts: Any, memory: Any) -> SimulatedState:
        """The state at ``t``: ``contacts`` and ``memory`` as the engine made them (converted when first read)."""
        return SimulatedState.lazy(t, q, v, self.actuation.modes(), _StepOutput(self, contacts, memory),
                                   self._hand_sizes)  # fmt: skip

    def _objects(self, q: np.ndarray, v: np.ndarray) -> tuple[tuple[pin.SE3, ...], np.ndarray]:
        """Object poses (COM frames, world) and twists (n_objects, 6) (COM velocity, angular velocity; world)."""
        scene = self.scene
        n = len(scene.objects)
        poses = tuple(scene.object_pose(q, i) for i in range(n))
        return poses, np.array([scene.object_twist(q, v, i) for i in range(n)]).reshape(n, 6)

    def _memory(self, state: State) -> Any:
        """The contact memory a step from ``state`` starts with, as its engine needs it."""
        source = getattr(state, "_source", None) if isinstance(state, SimulatedState) else None
        memory = source.memory if source is not None else state.contact_memory
        if memory is None:
            return ContactMemory.empty()
        if self._compiled is None and not isinstance(memory, ContactMemory):
            return memory_of(memory)  # a compiled run's state continued by the Python engine
        return memory

    # ------------------------------------------------------------------ one step
    def step(self, state: State, u: Any, disturbance: Any = None, object_forces: Any = None) -> tuple[State, StepInfo]:
        """Advance ``dt`` with inputs ``u`` held constant.

        ``disturbance`` adds joint torques [N m]; ``object_forces`` (n_objects, 3) pushes each object at its
        centre of mass [N, world frame].

        Raises:
            SimulationDiverged: Non-finite input or state, runaway speed or penetration.
        """
        disturbance = self._disturbance(disturbance, "disturbance")
        if object_forces is not None:
            disturbance = self._with_object_forces(disturbance, object_forces)
        return self._advance(state, self._input(u, state.t), disturbance)

    def _with_object_forces(self, disturbance: np.ndarray | None, forces: Any) -> np.ndarray:
        """Generalized forces on the whole scene: hand joint torques, then world forces at the objects' COMs.

        A free object's first three velocity coordinates translate its COM along the world axes
        (:meth:`~bhgrasp.sim.scene.Scene.object_twist`), so a world force F enters as it is; a spring-mounted
        object's slide takes F . direction.
        """
        forces = as_array(forces, "object_forces", (len(self.scene.objects), 3))
        total = np.zeros(self.scene.nv)
        if disturbance is not None:
            total[: self._nvh] = disturbance
        for index, force in enumerate(forces):
            rows = self.scene.object_v_slice(index)
            if rows.stop - rows.start == 6:
                total[rows.start : rows.start + 3] = force
            else:
                total[rows] = force @ self.scene.objects[index].direction
        return total

    def _input(self, u: Any, t: float) -> np.ndarray:
        """The control input as a finite float array of shape (n_inputs,)."""
        u = np.asarray(u, dtype=float)
        if u.shape != (self.actuation.n_inputs,):
            raise InputError(f"`u` must have shape ({self.actuation.n_inputs},), got shape {u.shape}")
        if not math.isfinite(u.dot(u)) and not np.isfinite(u).all():  # the dot product: one cheap test per step
            raise SimulationDiverged(t, "control input u", u.tolist(), "the controller returned NaN/inf")
        return u

    def _advance(self, state: State, u: np.ndarray, disturbance: np.ndarray | None) -> tuple[State, StepInfo]:
        """:meth:`step` with the input and disturbance already checked (``None`` or finite joint torques)."""
        q, v = state.scene_q, state.scene_v
        # The step depends only on the state: its contact memory and actuation modes, not the last run's.
        memory = self._memory(state)
        if self._modal:
            self.actuation.restore(state.actuation_modes, q[: self.scene.nq_hand])
            self.actuation.begin(u)
        tau_hand = self.actuation.joint_torques(u)
        if disturbance is not None and len(disturbance) > self._nvh:  # external forces on the objects too
            disturbance = disturbance.copy()
            disturbance[: self._nvh] += tau_hand
            tau_hand = disturbance
        elif disturbance is not None:
            tau_hand = tau_hand + disturbance
        if self._compiled is not None:
            q_next, v_next, contacts, drive, memory, divergence = self._compiled.step(q, v, tau_hand, memory)
        else:
            divergence = None
            self.engine.memory = memory
            if self.integrator == "implicit":
                q_next, v_next, contacts, drive = self._implicit(q, v, tau_hand)
            else:
                q_next, v_next, contacts, drive = self._explicit(q, v, tau_hand)
            memory = self.engine.memory
        t = round(state.t / self.dt + 1) * self.dt  # k dt exactly: no accumulated rounding
        if divergence is None or divergence.kind:  # the compiled step checked the same conditions
            self._check(t, q_next, v_next, contacts)
        if self._modal:
            self.actuation.update(q_next[: self.scene.nq_hand], v_next[: self._nvh], u, drive)
        return self._state(t, q_next, v_next, contacts, memory), StepInfo(contacts, drive)

    def _implicit_gyroscopic(self, v: np.ndarray, bias: np.ndarray) -> None:
        """Replace each free body's explicit gyroscopic torque ``w x I w`` in ``bias`` by the implicit midpoint one.

        The torque-free spin over the step solves ``I (w+ - w) / dt + m x I m = 0`` with ``m = (w + w+) / 2``
        (Newton, to round-off); dotting with ``m`` and ``I m`` shows that it keeps the kinetic energy
        ``w.I w / 2`` and the body angular momentum's length ``|I w|`` exactly, at any step (explicit ``w x I w``
        gains energy at every step).  The step then uses ``m x I m`` as the body's gyroscopic torque.
        """
        for angular, axes, moments in self._spinning:
            w = axes.T @ v[angular]  # in the principal axes
            if moments[0] == moments[1] == moments[2] or not w.any():
                continue  # a sphere's (or a resting body's) gyroscopic torque is 0
            explicit = gyroscopic_torque(moments, w)
            middle = spin_midpoint(moments, w, 0.5 * self.dt)
            bias[angular] += axes @ (gyroscopic_torque(moments, middle) - explicit)

    def _increment_rate(self, increment: np.ndarray, v: np.ndarray) -> np.ndarray:
        """Rate of the increment ``theta`` in ``q (+) theta`` at velocity ``v``.

        A body's rotation ``R exp(theta)`` turns at body rate ``w`` when ``theta`` changes at
        ``dexp^-1_{-theta}(w) = w + theta x w / 2 + theta x (theta x w) / 12`` (to O(theta^3), enough for RK4); hand
        joints and translations are vector spaces, whose increments change at ``v``.
        """
        rate = v.copy()
        for angular, _, _ in self._spinning:
            theta, w = increment[angular], v[angular]
            half = np.cross(theta, w)
            rate[angular] = w + 0.5 * half + np.cross(theta, half) / 12.0
        return rate

    def _disturbance(self, torque: Any, name: str) -> np.ndarray | None:
        """A disturbance as finite joint torques of shape (nv_hand,) [N m] (``None``: none)."""
        if torque is None:
            return None
        array = np.asarray(torque, dtype=float)
        if array.shape != (self._nvh,):
            raise InputError(
                f"`{name}` must be {self._nvh} joint torques [N m] (one per hand joint), got shape {array.shape}"
            )
        if not np.isfinite(array).all():
            raise InputError(f"`{name}` must be finite, got {array.tolist()}")
        return array

    def _motor_damping(self) -> np.ndarray:
        """The drive's own damping (joint damping of the actuation minus the passive joints')."""
        return self.actuation.joint_damping() - self.actuation.damping

    def _mass_matrix(self, q: np.ndarray) -> np.ndarray:
        mass = pin.crba(self.model, self.data, q).copy()
        mass[self._lower_triangle] = mass.T[self._lower_triangle]
        return mass

    def _transmission(self) -> np.ndarray:
        hand = self.actuation.transmission()
        rows, cols = hand.shape
        full = np.zeros((self.scene.nv, cols + len(self._object_identity)))
        full[:rows, :cols] = hand
        full[rows:, cols:] = self._object_identity
        return full

    def _passive(self, q: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Joint-space springs/dampers: explicit torque, implicit stiffness K and damping C (diagonals).

        Object springs (spring-mounted objects, rest at 0), joint stops (only while penetrated), joint damping and
        regularised joint friction (linearised about ``v``).
        """
        nvh, nqh = self._nvh, self.scene.nq_hand
        stiffness = self.scene.joint_stiffness.copy()
        damping = self.scene.joint_damping.copy()
        torque = np.zeros(self.scene.nv)
        if len(self._spring_v):
            torque[self._spring_v] = -self.scene.joint_stiffness[self._spring_v] * q[self._spring_q]
        damping[:nvh] += self.actuation.joint_damping()
        friction = self.actuation.friction
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
            torque[:nvh] -= self.limit_stiffness * (q_hand - stop)
            stiffness[:nvh] += active * self.limit_stiffness
            damping[:nvh] += active * self.limit_damping
        return torque, stiffness, damping

    def _implicit(self, q: np.ndarray, v: np.ndarray, tau_hand: np.ndarray):
        dt, model, data = self.dt, self.model, self.data
        contacts = self.engine.detect(q)
        pin.computeJointJacobians(model, data, q)
        mass = self._mass_matrix(q)
        bias = pin.nonLinearEffects(model, data, q, v).copy()
        self._implicit_gyroscopic(v, bias)
        passive, stiffness, damping = self._passive(q, v)
        tau = np.zeros(self.scene.nv)
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
            self.engine.remember(contacts, np.zeros((0, 3)), np.zeros(0, dtype=bool))
            drive = self._drive(mass, v, v_next, bias - passive, dt * stiffness + damping)
            return pin.integrate(model, q, v_next * dt), v_next, contacts, drive
        jacobians = self.engine.jacobians(contacts)
        start_velocity = jacobians @ v
        stacked = jacobians.reshape(-1, self.scene.nv)  # (3m, nv)
        parts = self.engine.linear_parts(contacts, dt)
        status, slide_force = self.engine.start_status(contacts, parts, start_velocity)  # 0 off, 1 stick, 2 slide
        may_stick = status == 2  # a contact that starts sliding may stick once, if its friction would overshoot
        for _ in range(8):
            f0, gains = self.engine.linearise(parts, status, slide_force)
            matrix_c = matrix + dt * stacked.T @ (gains @ jacobians).reshape(-1, self.scene.nv)
            rhs_c = rhs + dt * stacked.T @ f0.ravel()
            reduced = transmission.T @ matrix_c @ transmission
            v_next = transmission @ np.linalg.solve(reduced, transmission.T @ rhs_c)
            relative = jacobians @ v_next
            forces = f0 - (gains @ relative[:, :, None])[:, :, 0]
            new_status, new_slide = self.engine.classify(contacts, forces, status, start_velocity, relative, may_stick)
            if (new_status == status).all() and (
                not (status == 2).any() or np.abs(new_slide - slide_force).max() < 1e-12
            ):
                break
            may_stick &= new_status == 2
            status, slide_force = new_status, new_slide
        forces[status == 0] = 0.0
        displacement = self.engine.end_displacement(contacts, relative, forces, status, dt)
        contacts.force, contacts.sticking = forces, status == 1
        self.engine.remember(contacts, displacement, status == 2)
        generalized = stacked.T @ forces.ravel()
        drive = self._drive(mass, v, v_next, bias - generalized - passive, dt * stiffness + damping)
        return pin.integrate(model, q, v_next * dt), v_next, contacts, drive

    def _drive(self, mass, v, v_next, forces, implicit_damping) -> np.ndarray:
        """Hand joint torques the drive delivered over the step (M a + bias - contact - passive + implicit terms).

        ``forces`` is bias - contact - passive torques, ``implicit_damping`` the diagonal (dt K + C) acting on v+.
        """
        drive = (mass @ ((v_next - v) / self.dt) + forces + implicit_damping * v_next)[: self._nvh]
        return drive - self._motor_damping() * v_next[: self._nvh]  # the clutch passes what the motor's losses leave

    def _explicit(self, q: np.ndarray, v: np.ndarray, tau_hand: np.ndarray):
        dt, model = self.dt, self.model
        tau = np.zeros(self.scene.nv)
        tau[: len(tau_hand)] = tau_hand
        transmission = self._transmission()
        if self.integrator == "semi-implicit":
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
        self.engine.remember(contacts, displacement, ~sticking)
        return q_next, v_next, contacts, drive

    def _acceleration(self, q: np.ndarray, v: np.ndarray, tau: np.ndarray, transmission: np.ndarray):
        """Explicit accelerations at (q, v) (contacts detected at q), with the step's contact bookkeeping."""
        model, data = self.model, self.data
        contacts = self.engine.detect(q)
        pin.computeJointJacobians(model, data, q)
        passive, _, damping = self._passive(q, v)
        total = tau + passive - damping * v
        forces, sticking, displacement = np.zeros((len(contacts), 3)), np.zeros(len(contacts), bool), None
        generalized = np.zeros(self.scene.nv)
        if len(contacts):
            jacobians = self.engine.jacobians(contacts)
            relative = np.einsum("mij,j->mi", jacobians, v)
            forces, sticking, displacement = self.engine.forces(contacts, relative, self.dt)
            generalized = np.einsum("mij,mi->j", jacobians, forces)
        mass = self._mass_matrix(q)
        bias = pin.nonLinearEffects(model, data, q, v).copy()
        if self.integrator == "semi-implicit":  # RK4's explicit stages are accurate to O(dt^4) as they are
            self._implicit_gyroscopic(v, bias)
        reduced = transmission.T @ mass @ transmission
        acceleration = transmission @ np.linalg.solve(reduced, transmission.T @ (total + generalized - bias))
        drive = (mass @ acceleration + bias - generalized - passive + damping * v)[: self._nvh]
        drive -= self._motor_damping() * v[: self._nvh]
        if displacement is None:
            displacement = np.zeros((0, 3))
        return acceleration, contacts, forces, sticking, displacement, drive

    def _check(self, t: float, q: np.ndarray, v: np.ndarray, contacts: ContactSet) -> None:
        speed = float(np.abs(v).max(initial=0.0))
        if not (speed <= self.max_speed and np.isfinite(q).all()):  # NaN fails every comparison
            if not np.isfinite(q).all() or not np.isfinite(v).all():
                name = "joint/object position" if not np.isfinite(q).all() else "joint/object velocity"
                raise SimulationDiverged(t, name, "NaN/inf", "reduce dt or the controller gains")
            index = int(np.argmax(np.abs(v)))
            raise SimulationDiverged(t, f"speed of velocity coordinate {index}", f"{speed:.3g}", "reduce dt or gains")
        if len(contacts) and contacts.depth.max() > self.max_penetration:
            raise SimulationDiverged(
                t, "contact depth", f"{contacts.depth.max():.4g} m", "stiffen the contact or reduce dt/forces"
            )

    # ------------------------------------------------------------------ runs
    def run(
        self,
        controller: Callable[[float, State], Any],
        duration: float,
        state: State | None = None,
        control_dt: float | None = None,
        sensor_noise: tuple[float, float] | None = None,
        disturbance: Callable[[float], Any] | Any = None,
        seed: int | None = None,
        progress: bool = True,
        record_every: int = 1,
        object_forces: Callable[[float], Any] | None = None,
        until: Callable[[State], bool] | None = None,
        sensors: SensorModel | None = None,
    ) -> Trajectory:
        """Simulate ``duration`` [s] under ``controller`` and record everything.

        Args:
            controller: ``(t, state) -> u`` callable or object with ``reset(state)``; an optional ``log`` dict
                (name -> latest value) is recorded at every sample.
            duration: Simulated time [s].
            state: Start state (default :meth:`initial_state`).
            control_dt: Controller period [s] (a multiple of ``dt``; inputs held in between); default ``dt``.
            sensor_noise: (sigma_q [rad], sigma_v [rad/s]) Gaussian noise on the hand state the controller sees:
                short for ``sensors=SensorModel(joint_position=sigma_q, joint_velocity=sigma_v)``.
            disturbance: Joint torques [N m] added to the actuators': an array, or a callable ``t -> array``.
            seed: Seed of the sensor noise (required with noisy ``sensor_noise`` or ``sensors``).
            progress: Show a tqdm progress bar for runs of more than 20 000 steps.
            record_every: Record one sample every this many physics steps.
            object_forces: ``t -> (n_objects, 3)`` forces [N, world frame] on the objects' centres of mass (e.g. a
                shake test), or ``None``.
            until: ``state -> bool`` checked after every step: the run stops early at the first state it accepts
                (e.g. an object that left the hand); the trajectory ends there.
            sensors: What the controller's sensors get wrong (:class:`~bhgrasp.sim.sensor_model.SensorModel`:
                noise on the joints, the object's pose and twist and the contact forces, and a delay).
        """
        duration = as_positive(duration, "duration")
        steps = round(duration / self.dt)
        hold = 1 if control_dt is None else round(as_positive(control_dt, "control_dt") / self.dt)
        if hold < 1 or abs(hold * self.dt - (control_dt or self.dt)) > 1e-9 * max(1.0, hold):
            raise InputError(f"`control_dt` must be a positive multiple of dt = {self.dt}, got {control_dt}")
        if sensor_noise is not None:
            if sensors is not None:
                raise InputError("give `sensor_noise` or `sensors`, not both (sensor_noise is short for sensors)")
            if seed is None:
                raise InputError("`sensor_noise` needs a `seed` (runs are deterministic)")
            sigma = as_vector(sensor_noise, "sensor_noise", 2)
            sensors = SensorModel(joint_position=sigma[0], joint_velocity=sigma[1])
        reader = Sensors(SensorModel() if sensors is None else sensors, seed)
        if isinstance(record_every, bool) or not isinstance(record_every, int | np.integer) or record_every < 1:
            raise InputError(
                f"`record_every` must be a positive integer (physics steps per sample), got {record_every!r}"
            )
        if disturbance is not None and not callable(disturbance):
            disturbance = self._disturbance(disturbance, "disturbance")
        state = self.initial_state() if state is None else state
        if state.scene_q is None or state.scene_q.shape != (self.scene.nq,):
            raise InputError(
                f"`state` must be a state of this simulator's scene (nq = {self.scene.nq}); use "
                "Simulator.initial_state() or a state a run of this simulator returned"
            )
        self.actuation.restore(state.actuation_modes, state.scene_q[: self.scene.nq_hand])
        if isinstance(getattr(controller, "log", None), dict):
            controller.log.clear()  # each run records its own internals, never the last run's
        if hasattr(controller, "reset"):
            controller.reset(state)
        recorder = Recorder(self.scene, self.actuation)
        u = np.zeros(self.actuation.n_inputs)
        info = StepInfo(empty_contact_set(), np.zeros(self._nvh))
        iterator = range(steps)
        if progress and steps > 20_000:
            from tqdm import tqdm

            iterator = tqdm(iterator, desc="simulating", unit="step", mininterval=1.0)
        for k in iterator:
            if k % hold == 0:
                sensed = reader.read(state)
                u = self._input(np.array(controller(state.t, sensed), dtype=float), state.t)
            if k % record_every == 0:
                recorder.add(state, u, info, getattr(controller, "log", None))
            torque = self._disturbance(disturbance(state.t), "disturbance(t)") if callable(disturbance) else disturbance
            if object_forces is not None:
                torque = self._with_object_forces(torque, object_forces(state.t))
            state, info = self._advance(state, u, torque)
            if until is not None and until(state):
                break
        recorder.add(state, u, info, getattr(controller, "log", None))
        return recorder.trajectory()


__all__ = ["ENGINES", "INTEGRATORS", "Simulator", "StepInfo"]
