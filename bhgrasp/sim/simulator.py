"""Simulator: fixed-step integration of a scene (hand + objects + contacts) under a controller.

Integrators (``integrator=``): ``"implicit"`` (default: linearly-implicit Euler, the stiffness and damping of
contacts, joint stops, object springs and joint damping folded into the velocity solve, so stiff contacts stay stable
at millisecond steps), ``"semi-implicit"`` (symplectic Euler with explicit forces) and ``"rk4"`` (Runge-Kutta on the
manifold, contacts re-detected at each stage); :mod:`~bhgrasp.sim.python_engine` states their equations.

The contract of a Simulator:

- **Its settings are frozen** (:class:`~bhgrasp.sim.settings.SimulatorSettings`): assigning ``sim.dt`` raises;
  :meth:`Simulator.with_settings` builds a new Simulator.
- **A step depends only on its inputs**: the :class:`~bhgrasp.data.state.State` carries the contact memory (an
  immutable :class:`~bhgrasp.data.contacts.ContactMemory`) and the actuation modes, never the steps or runs before.
- **A step checks the state it is given** belongs to its scene (the scene's signature, sizes, finite values, unit
  quaternions, coordinates within ``max_coordinate``) and raises an :class:`~bhgrasp.errors.InputError` naming the
  field; a state that this Simulator's own step made is trusted (its arrays are read-only).
- **It may be shared by threads**: steps from several threads run one at a time (a lock), each as if alone.  For
  parallel speed give each thread its own Simulator built with its own actuation (``with_settings`` and copies share
  the actuation object, whose modes, e.g. the Barrett TorqueSwitch, each step restores and updates; a stateless
  ``FullyActuated`` may be shared), or use :class:`~bhgrasp.sim.batch.BatchSimulator`.
- **It pickles** (rebuilt from its scene, contact law, actuation and settings), so it travels to a process or a Dask
  worker.
- **Every divergence names the value it saw** (:class:`~bhgrasp.errors.SimulationDiverged`).

Two engines run this physics behind the :class:`~bhgrasp.sim.engine.Engine` protocol: ``engine="compiled"`` (the
default; the step in C++, ``src/engine.cpp``) and ``engine="python"`` (the readable reference); tests/test_compiled.py
steps both in lockstep.
"""

from __future__ import annotations

import threading
from typing import Any

import numpy as np

from bhgrasp.data import ContactMemory, ContactSet, SimulatedState, State
from bhgrasp.errors import FrozenSettingError, InputError
from bhgrasp.sim import run_loop
from bhgrasp.sim.actuation import Actuation, BarrettActuation, FullyActuated, barrett_modes
from bhgrasp.sim.compiled import CompiledEngine
from bhgrasp.sim.contact_law import SpringDamper
from bhgrasp.sim.engine import DriveTerms, drive_key
from bhgrasp.sim.inputs import control_input, generalized_forces, joint_torques
from bhgrasp.sim.python_engine import PythonEngine
from bhgrasp.sim.scene import Scene
from bhgrasp.sim.scene_layout import SceneLayout
from bhgrasp.sim.settings import SimulatorSettings
from bhgrasp.sim.start_check import StartProblem, report, start_problems
from bhgrasp.sim.state_check import check_state, describe_divergence
from bhgrasp.sim.step_output import StepInfo, StepOutput

MATCH_RADIUS = 3e-3  # [m] a contact matches the last step's nearest point of its pair within this distance on body b


class Simulator:
    """Fixed-step simulator of a :class:`~bhgrasp.sim.scene.Scene` (its settings frozen once built)."""

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
        engine: str | None = None,
        max_coordinate: float = 1e4,
        start_check: str = "warn",
        linear_solver: str = "auto",
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
                implementation; the same physics, tests/test_compiled.py holds them in lockstep); ``None``
                (default): the default engine, compiled unless ``BHGRASP_ENGINE=python``.
            max_coordinate: Largest |coordinate| [m or rad] of a state: beyond it a state is refused and a step
                has diverged.
            start_check: ``"warn"``, ``"error"`` or ``"off"``: what :meth:`initial_state` does with a scene that
                starts wrong (bodies interpenetrating, an object its step cannot resolve; :meth:`check_start`).
            linear_solver: ``"auto"``, ``"dense"`` or ``"sparse"``: how the implicit step solves for the velocities
                (:attr:`~bhgrasp.sim.settings.SimulatorSettings.linear_solver`; auto: sparse under the implicit
                integrator for scenes of :data:`~bhgrasp.sim.settings.SPARSE_FROM` velocities or more).

        Raises:
            InputError: A setting out of range, or an actuation built for another hand.
            CompiledEngineUnavailable: The engine is the compiled one but the C++ core does not load.
        """
        settings = SimulatorSettings(
            dt=dt,
            integrator=integrator,
            joint_limit_stiffness=joint_limit_stiffness,
            joint_limit_damping=joint_limit_damping,
            max_penetration=max_penetration,
            max_speed=max_speed,
            max_coordinate=max_coordinate,
            engine=engine,
            start_check=start_check,
            linear_solver=linear_solver,
        )
        self._build(scene, contact, actuation, settings)

    @classmethod
    def from_settings(
        cls,
        scene: Scene,
        settings: SimulatorSettings,
        contact: SpringDamper | None = None,
        actuation: Actuation | None = None,
    ) -> Simulator:
        """A Simulator of ``scene`` with frozen ``settings`` (the contact law and actuation as in the constructor)."""
        if not isinstance(settings, SimulatorSettings):
            raise InputError(f"`settings` must be a SimulatorSettings, got {type(settings).__name__}")
        simulator = cls.__new__(cls)
        simulator._build(scene, contact, actuation, settings)
        return simulator

    def _build(
        self, scene: Scene, contact: SpringDamper | None, actuation: Actuation | None, settings: SimulatorSettings
    ) -> None:
        if not isinstance(scene, Scene):
            raise InputError(f"`scene` must be a Scene, got {type(scene).__name__}")
        actuation = actuation if actuation is not None else FullyActuated(scene.hand)
        if actuation.hand is not scene.hand:
            raise InputError("`actuation` must be built for the scene's hand (`Actuation(scene.hand, ...)`)")
        law = contact if contact is not None else SpringDamper()
        layout = SceneLayout.of(scene)
        kind = CompiledEngine if settings.engine == "compiled" else PythonEngine
        engine = kind(scene, layout, law, settings, MATCH_RADIUS)
        values = {"scene": scene, "law": law, "actuation": actuation, "settings": settings, "layout": layout}
        values |= {"engine": engine, "_drives": {}, "_lock": threading.Lock(), "_modal": _modal(actuation)}
        values["_barrett"] = {} if kind is CompiledEngine and type(actuation) is BarrettActuation else None
        values |= {"_barrett_modes": {}, "_barrett_flags": {}}  # modes -> flags array, id(array) -> (array, modes)
        for name, value in values.items():
            object.__setattr__(self, name, value)

    def with_settings(self, **changes: Any) -> Simulator:
        """A new Simulator of the same scene, contact law and actuation with some settings changed (e.g. ``dt``)."""
        unknown = sorted(set(changes) - set(SimulatorSettings.__dataclass_fields__))
        if unknown:
            raise InputError(f"unknown settings {unknown}; valid: {sorted(SimulatorSettings.__dataclass_fields__)}")
        settings = SimulatorSettings(**{**vars(self.settings), **changes})
        return Simulator.from_settings(self.scene, settings, self.law, self.actuation)

    def __setattr__(self, name: str, value: Any) -> None:
        setting = name in SimulatorSettings.__dataclass_fields__
        cure = f"simulator.with_settings({name}=...)" if setting else "Simulator(scene, contact=..., actuation=...)"
        raise FrozenSettingError(
            f"Simulator.{name} cannot change after the Simulator is built (its engine was set up with it); build a "
            f"new one: {cure}"
        )

    def __reduce__(self) -> tuple:
        """Pickles and copies rebuild the Simulator from its scene, contact law, actuation and settings."""
        return Simulator.from_settings, (self.scene, self.settings, self.law, self.actuation)

    # ------------------------------------------------------------------ settings (read-only)
    dt = property(lambda self: self.settings.dt, doc="Physics step [s].")
    integrator = property(lambda self: self.settings.integrator, doc="The integrator's name.")
    engine_name = property(lambda self: self.settings.engine, doc='``"compiled"`` or ``"python"``.')
    limit_stiffness = property(lambda self: self.settings.joint_limit_stiffness, doc="Joint stops [N m/rad].")
    limit_damping = property(lambda self: self.settings.joint_limit_damping, doc="Joint stops [N m s/rad].")
    max_penetration = property(lambda self: self.settings.max_penetration, doc="Divergence depth [m].")
    max_speed = property(lambda self: self.settings.max_speed, doc="Divergence speed [m/s or rad/s].")

    # ------------------------------------------------------------------ states
    def initial_state(self, q_hand: Any = None) -> State:
        """The scene at rest with the hand at ``q_hand`` (default neutral) and objects as described."""
        from bhgrasp._validation import as_vector

        q_hand = None if q_hand is None else as_vector(q_hand, "q_hand", self.scene.nq_hand)
        q, v = self.scene.initial_state(q_hand)
        memory = ContactMemory.empty()
        with self._lock:
            self.actuation.reset(q[: self.scene.nq_hand])
            contacts = self.engine.detect(q, memory)
            off = self.settings.start_check == "off"
            problems = () if off else tuple(self._start_problems(q, v, contacts))
            state = self._state(0.0, q, v, contacts, memory, problems)
        report(list(problems), self.settings.start_check)
        return state

    def check_start(self, state: State) -> list[StartProblem]:
        """What is wrong with starting from ``state`` (:mod:`~bhgrasp.sim.start_check`; empty if nothing is)."""
        self._start_memory(state)
        with self._lock:
            contacts = self.engine.detect(state.scene_q, ContactMemory.empty())
            return self._start_problems(state.scene_q, state.scene_v, contacts)

    def _start_problems(self, q: np.ndarray, v: np.ndarray, contacts: ContactSet) -> list[StartProblem]:
        settings = self.settings
        return start_problems(self.scene, q, v, contacts, self.law, self.dt, self.max_penetration, settings.integrator)

    def _state(
        self, t: float, q: Any, v: Any, contacts: Any, memory: Any, start: tuple = (), modes: Any = None
    ) -> SimulatedState:
        """The state at ``t`` with the engine's ``contacts`` and ``memory`` (converted when first read).

        ``start``: the problems of the initial state its run began from (named if the run diverges); ``modes``: its
        actuation modes (default: the actuation's now).
        """
        scene = self.scene
        source = StepOutput(self, contacts, memory, start)
        sizes = (scene.nq_hand, scene.nv_hand)
        modes = self.actuation.modes() if modes is None else modes
        return SimulatedState.lazy(t, q, v, modes, source, sizes, self.layout.signature)

    def check_state(self, state: State) -> State:
        """``state`` if this simulator can step it (see :func:`~bhgrasp.sim.state_check.check_state`).

        Raises:
            InputError: A state of another scene, or a malformed one; the message names the field.
        """
        self._start_memory(state)
        return state

    # ------------------------------------------------------------------ one step
    def step(self, state: State, u: Any, disturbance: Any = None, object_forces: Any = None) -> tuple[State, StepInfo]:
        """Advance ``dt`` with inputs ``u`` held constant.

        ``disturbance`` adds joint torques [N m]; ``object_forces`` (n_objects, 3) pushes each object at its
        centre of mass [N, world frame].

        Raises:
            InputError: A state of another scene or a malformed one (the message names the field), an input or a
                disturbance of the wrong shape or type.
            SimulationDiverged: Non-finite input, or a step whose result is not finite, too fast, too deep or too
                far out (the message names the value).
        """
        memory = self._start_memory(state)
        u = control_input(u, self.actuation.n_inputs, state.t)
        forces = joint_torques(disturbance, self.scene.nv_hand, "disturbance")
        if object_forces is not None:
            forces = generalized_forces(self.scene, forces, object_forces)
        with self._lock:
            return self._advance(state, u, forces, memory)

    def _start_memory(self, state: State) -> Any:
        """The contact memory a step from ``state`` starts with, as the engine takes it (the state checked)."""
        source = getattr(state, "_source", None) if type(state) is SimulatedState else None
        if source is not None and source.simulator is self:  # made by this simulator's step: read-only, trusted
            memory = source.memory
            return self.engine.memory(memory) if isinstance(memory, ContactMemory) else memory
        memory = check_state(state, self.scene, self.layout, self.settings)
        return self.engine.memory(memory)

    def _advance(
        self, state: State, u: np.ndarray, disturbance: np.ndarray | None, memory: Any
    ) -> tuple[State, StepInfo]:
        """:meth:`step` with the input, disturbance and state checked (under the lock)."""
        if self._barrett is not None:  # the BH8-280's drive in the compiled step's call
            result, modes = self._step_barrett(state, u, disturbance, memory)
        else:
            result, modes = self._step_actuated(state, u, disturbance, memory), None
        t = round(state.t / self.settings.dt + 1) * self.settings.dt  # k dt exactly: no accumulated rounding
        source = getattr(state, "_source", None)
        start = source.start if isinstance(source, StepOutput) and source.simulator is self else ()
        if result.divergence.kind:
            raise self._diverged(t, result, start)
        if self._modal and self._barrett is None:
            nqh, nvh = self.scene.nq_hand, self.scene.nv_hand
            self.actuation.update(result.q[:nqh], result.v[:nvh], u, result.drive, result.load)
        return self._state(t, result.q, result.v, result.contacts, result.memory, start, modes), StepInfo(
            result, self.engine
        )

    def _diverged(self, t: float, result: Any, start: tuple) -> Exception:
        """The ``SimulationDiverged`` of a step that ended at ``t`` [s] with ``result``'s divergence."""
        contacts = self.engine.contact_set(result.contacts) if result.divergence.kind == 4 else None
        return describe_divergence(t, result.divergence, self.settings, self.scene, start, contacts)

    def closes_loops_in_cpp(self) -> bool:
        """Whether :meth:`run_compiled` can run: the compiled engine, a :class:`FullyActuated` (not a subclass)."""
        return self.settings.engine == "compiled" and type(self.actuation) is FullyActuated

    def run_compiled(self, state: State, loop: Any, until: float, steps: int) -> tuple[Any, State, Any, Any] | None:
        """Up to ``steps`` steps from ``state`` under a compiled loop controller ``loop``, in one C++ call.

        ``loop``: a ``bhgrasp._core.LoopController``; the loop stops before a step at t >= ``until`` [s].  Each step
        is :meth:`step`'s with the controller's inputs, bit for bit.  Returns the C++ ``LoopRun``
        (``src/closed_loop.hpp``), the state after its last step and that step's info (``state`` and ``None`` if it
        took none), and ``None``; or, when a step diverged, the run, ``None``, ``None`` and the ``SimulationDiverged``
        :meth:`step` raises for it (for the caller to raise once the controller is settled).  ``None`` where the
        loop cannot run (:meth:`closes_loops_in_cpp`, or a state this simulator's compiled step did not make).
        """
        source = getattr(state, "_source", None) if type(state) is SimulatedState else None
        if source is None or source.simulator is not self or not self.closes_loops_in_cpp():
            return None
        if isinstance(source.contacts, ContactSet):
            return None  # (an initial state's contacts, not a compiled step's)
        memory = self._start_memory(state)
        actuation = self.actuation
        limit = actuation.limit if actuation.saturate else None
        start = (state.scene_q, state.scene_v, source.contacts, memory, state.t)
        with self._lock:
            run = self.engine.run_loop(loop, self._drive(), start, self.dt, steps, until, limit)
        if run.stop == 2:
            return run, None, None, self._diverged(run.diverged_at, run.last, source.start)
        if not run.steps:
            return run, state, None, None
        last = run.last
        after = self._state(float(run.t[-1]), last.q, last.v, last.contacts, last.memory, source.start)
        return run, after, StepInfo(last, self.engine), None

    def _step_actuated(self, state: State, u: np.ndarray, disturbance: np.ndarray | None, memory: Any) -> Any:
        """The engine's step under the actuation's joint torques and drive in the state's modes."""
        q, v = state.scene_q, state.scene_v
        actuation, nqh, nvh = self.actuation, self.scene.nq_hand, self.scene.nv_hand
        if self._modal:  # the step depends only on the state's actuation modes, not the last run's
            actuation.restore(state.actuation_modes, q[:nqh])
            actuation.begin(u)
        tau_hand = actuation.joint_torques(u)
        if disturbance is not None and len(disturbance) > nvh:  # external forces on the objects too
            disturbance = disturbance.copy()
            disturbance[:nvh] += tau_hand
            tau_hand = disturbance
        elif disturbance is not None:
            tau_hand = tau_hand + disturbance
        return self.engine.step(q, v, tau_hand, self._drive(), memory)

    def _step_barrett(
        self, state: State, u: np.ndarray, disturbance: np.ndarray | None, memory: Any
    ) -> tuple[Any, np.ndarray]:
        """The compiled step with the Barrett drive in the same call, from the state's modes; and the modes after it.

        The actuation takes the modes after it, as :meth:`~bhgrasp.sim.actuation.BarrettActuation.update` leaves them.
        Each combination of modes a step meets gets one read-only flags array, which the states share.
        """
        actuation = self.actuation
        key = actuation.parameters()
        drive = self._barrett.get(key)
        if drive is None:  # new parameters (self-locking among them): new drive, new modes arrays
            self._barrett.clear()
            self._barrett_modes.clear()
            self._barrett_flags.clear()
            drive = self._barrett[key] = self.engine.barrett(actuation)
        flags = state.actuation_modes
        known = self._barrett_flags.get(id(flags))
        modes = known[1] if known is not None and known[0] is flags else barrett_modes(flags)
        result, after = self.engine.step_barrett(drive, state.scene_q, state.scene_v, u, disturbance, modes, memory)
        actuation.take(after)
        shared = self._barrett_modes.get(after)
        if shared is None:
            shared = actuation.modes()
            shared.flags.writeable = False
            self._barrett_modes[after] = shared
            self._barrett_flags[id(shared)] = (shared, after)
        return result, shared

    def _drive(self) -> Any:
        """The actuation's terms in its current mode, as the engine takes them (built once for each mode)."""
        key = drive_key(self.actuation)
        drive = self._drives.get(key)
        if drive is None:
            drive = self._drives[key] = self.engine.drive(DriveTerms.of(self.actuation))
        return drive

    # ------------------------------------------------------------------ runs
    run = run_loop.run


def _modal(actuation: Actuation) -> bool:
    """Whether an actuation has modes to restore and update around each step (else its hooks are skipped)."""
    kind = type(actuation)
    hooks = ("restore", "reset", "update", "begin")
    return any(getattr(kind, hook) is not getattr(Actuation, hook) for hook in hooks)


__all__ = ["MATCH_RADIUS", "Simulator"]
