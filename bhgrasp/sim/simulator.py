"""Simulator: fixed-step integration of a scene (hand + objects + contacts) under a controller.

Integrators (``integrator=``): ``"implicit"`` (default: linearly-implicit Euler, the stiffness and damping of
contacts, joint stops, object springs and joint damping folded into the velocity solve, so stiff contacts stay stable
at millisecond steps), ``"semi-implicit"`` (symplectic Euler with explicit forces) and ``"rk4"`` (Runge-Kutta on the
manifold, contacts re-detected at each stage); :mod:`~bhgrasp.sim.python_engine` states their equations.  A run
depends only on its inputs: the :class:`~bhgrasp.sim.state.State` carries the contact memory (tangential springs,
stick/slip) and the actuation modes, so a step depends only on its state and inputs, never on the steps or runs
before it.

Two engines run this physics: ``engine="compiled"`` (the default; the step in C++, ``src/engine.cpp``, through
:mod:`bhgrasp.sim.compiled`) and ``engine="python"`` (:mod:`bhgrasp.sim.python_engine`, the readable reference);
tests/test_compiled.py steps both in lockstep.  This module holds the Simulator: its options and states, the checks
of its inputs, the dispatch of a step to its engine and the divergence check; :mod:`~bhgrasp.sim.step_output` holds
what a step returns, :mod:`~bhgrasp.sim.run_loop` the loop of :meth:`Simulator.run`.
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
from bhgrasp.sim import run_loop
from bhgrasp.sim.actuation import Actuation, FullyActuated
from bhgrasp.sim.compiled import CompiledStep, memory_of
from bhgrasp.sim.contact import ContactEngine, ContactMemory, ContactSet, SpringDamper
from bhgrasp.sim.python_engine import PythonStep
from bhgrasp.sim.scene import Scene
from bhgrasp.sim.sensor_model import SensorModel
from bhgrasp.sim.state import SimulatedState, State, Trajectory
from bhgrasp.sim.step_output import StepInfo, _StepOutput

INTEGRATORS = ("implicit", "semi-implicit", "rk4")
ENGINES = ("compiled", "python")


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
        self._stepper = self._compiled if self._compiled is not None else PythonStep(self)  # the engine's step

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
        q_next, v_next, contacts, drive, memory, divergence = self._stepper.step(q, v, tau_hand, memory)
        t = round(state.t / self.dt + 1) * self.dt  # k dt exactly: no accumulated rounding
        if divergence is None or divergence.kind:  # the compiled step checked the same conditions
            self._check(t, q_next, v_next, contacts)
        if self._modal:
            self.actuation.update(q_next[: self.scene.nq_hand], v_next[: self._nvh], u, drive)
        return self._state(t, q_next, v_next, contacts, memory), StepInfo(contacts, drive)

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
        return run_loop.run(self, controller, duration, state=state, control_dt=control_dt, sensor_noise=sensor_noise,
                            disturbance=disturbance, seed=seed, progress=progress, record_every=record_every,
                            object_forces=object_forces, until=until, sensors=sensors)  # fmt: skip


__all__ = ["ENGINES", "INTEGRATORS", "Simulator", "StepInfo"]
