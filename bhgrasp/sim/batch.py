"""Batched rollouts: N copies of one simulator's scene stepped together by the compiled engine.

Each environment has its own Pinocchio and coal data and its own contact memory (``src/batch.cpp``); one
:meth:`BatchSimulator.step` advances every environment with its own inputs, on ``threads`` threads (each environment
on one thread, with the arithmetic of a single :meth:`~bhgrasp.sim.Simulator.step`: a batch of N gives the bits of N
separate runs, whatever the thread count).  A controller for a batch is vectorised: it reads the batch's arrays
(hand ``q``, ``v`` of shape (N, nv_hand), object positions, and the compiled kernels :meth:`gravity_torques` and
:meth:`fingertip_jacobians`) and returns inputs of shape (N, n_inputs).  An environment whose step diverges is
frozen and reported in :attr:`diverged` / :meth:`divergence`; the others go on.  :meth:`BatchSimulator.rollout`
runs open-loop inputs through many steps in one call, each environment's steps on one thread (the threads are kept
between calls and meet once per call, where a step meets them once per step).

Both actuation models run in the batch: :class:`~bhgrasp.sim.actuation.FullyActuated` (one torque per joint) and
:class:`~bhgrasp.sim.actuation.BarrettActuation` (four motor torques per environment; each environment's
TorqueSwitch modes switch in C++, ``src/barrett.cpp``, the Python model's twin: a batch reproduces separate
``Simulator`` runs bit for bit).  Use threads only up to the free cores: a batch inside each worker of a process
pool already has its core.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from bhgrasp._validation import as_positive
from bhgrasp.data import ContactSet, SimulatedState, State
from bhgrasp.errors import InputError
from bhgrasp.sim.actuation import BarrettActuation, FullyActuated, barrett_modes
from bhgrasp.sim.compiled import (
    barrett_of,
    contact_set,
    core_module,
    drive_of,
    engine_settings,
    memory_of,
    native_memory,
)
from bhgrasp.sim.geometry_text import geometry_text
from bhgrasp.sim.simulator import MATCH_RADIUS, Simulator
from bhgrasp.sim.state_check import check_state, divergence_text
from bhgrasp.sim.step_output import StepOutput


@dataclass(frozen=True, eq=False)
class BatchRollout:
    """The states of a batch after every step of :meth:`BatchSimulator.rollout`.

    An environment that diverged repeats its last good state from its divergence on
    (:attr:`BatchSimulator.diverged` says which).
    """

    t: np.ndarray  # (steps,) time after each step [s]
    scene_q: np.ndarray  # (N, steps, nq) scene configurations
    scene_v: np.ndarray  # (N, steps, nv) scene velocities
    nq_hand: int  # the hand's share of a configuration (its first entries)
    nv_hand: int  # the hand's share of a velocity (its first entries)

    @property
    def q(self) -> np.ndarray:
        """(N, steps, nq_hand) hand joint positions [rad]."""
        return self.scene_q[:, :, : self.nq_hand]

    @property
    def v(self) -> np.ndarray:
        """(N, steps, nv_hand) hand joint velocities [rad/s]."""
        return self.scene_v[:, :, : self.nv_hand]

    def __repr__(self) -> str:
        size, steps = self.scene_q.shape[:2]
        return f"BatchRollout({size} environments, {len(self.t)} steps, recorded: {steps > 0})"


class BatchSimulator:
    """N environments of one :class:`~bhgrasp.sim.Simulator`'s scene, stepped together in C++."""

    def __init__(self, simulator: Simulator, states: Sequence[State], threads: int = 1) -> None:
        """Copy the simulator's scene, law and options once per environment.

        Args:
            simulator: The scene, contact law, actuation (fully actuated) and options of every environment, read
                once here (a later change of the actuation's damping or friction does not reach the batch).
            states: One start state per environment (states of ``simulator``'s scene, e.g. from
                :meth:`~bhgrasp.sim.Simulator.initial_state` or a run); they carry the contact memory.
            threads: Worker threads per step (>= 1).

        Raises:
            InputError: No states, a state of another scene or a malformed one (as
                :meth:`~bhgrasp.sim.Simulator.check_state` finds them), states at different times, an actuation
                whose transmission changes (Barrett), or ``threads`` < 1.
        """
        if not isinstance(simulator.actuation, FullyActuated | BarrettActuation):
            raise InputError(
                "BatchSimulator runs FullyActuated and BarrettActuation hands, got "
                f"{type(simulator.actuation).__name__}"
            )
        if isinstance(threads, bool) or not isinstance(threads, int | np.integer) or threads < 1:
            raise InputError(f"`threads` must be a positive integer, got {threads!r}")
        states = list(states)
        if not states:
            raise InputError("`states` must hold at least one start state (one per environment)")
        scene = simulator.scene
        memories = []
        for i, state in enumerate(states):
            try:
                memories.append(check_state(state, scene, simulator.layout, simulator.settings))
            except InputError as error:
                raise InputError(f"`states[{i}]`: {error}") from error
        times = {state.t for state in states}
        if len(times) > 1:
            raise InputError(f"the start states must share one time, got {sorted(times)}")
        core = core_module()
        self.simulator = simulator
        self.threads = int(threads)
        self.t = states[0].t
        native = engine_settings(scene, simulator.layout, simulator.law, simulator.settings, MATCH_RADIUS)
        self._batch = core.Batch(scene.model.saveToString(), geometry_text(scene.geometry), native, len(states))
        for i, (state, memory) in enumerate(zip(states, memories)):
            self._batch.set_state(i, state.scene_q, state.scene_v, native_memory(memory))
        self._barrett = isinstance(simulator.actuation, BarrettActuation)
        if self._barrett and simulator.actuation.n_inputs != 4:
            raise InputError(
                "BatchSimulator runs the Barrett hand's four motors alone, got "
                f"{simulator.actuation.n_inputs} inputs (a mounted hand): step it with Simulator"
            )
        if self._barrett:
            self._batch.set_barrett(barrett_of(simulator.actuation))
            for i, state in enumerate(states):
                self._batch.set_modes(i, list(barrett_modes(state.actuation_modes)))
        self._drive = drive_of(simulator.actuation)
        tips = simulator.scene.hand.fingertip_frames
        self._tip_frames = {finger: scene.model.getFrameId(frame) for finger, frame in tips.items()}
        self._nqh, self._nvh = scene.nq_hand, scene.nv_hand

    @property
    def size(self) -> int:
        """Number of environments N."""
        return self._batch.size

    @property
    def scene_q(self) -> np.ndarray:
        """(N, nq) scene configurations."""
        return self._batch.q

    @property
    def scene_v(self) -> np.ndarray:
        """(N, nv) scene velocities."""
        return self._batch.v

    @property
    def q(self) -> np.ndarray:
        """(N, nv_hand) hand joint positions [rad]."""
        return self._batch.q[:, : self._nqh]

    @property
    def v(self) -> np.ndarray:
        """(N, nv_hand) hand joint velocities [rad/s]."""
        return self._batch.v[:, : self._nvh]

    @property
    def modes(self) -> np.ndarray:
        """(N, n_modes) actuation modes per environment (full actuation: none).

        Barrett: the TorqueSwitch of F1, F2, F3, then (if self-locking) their worm locks.
        """
        if not self._barrett:
            return np.zeros((self.size, 0))
        count = 6 if self.simulator.actuation.self_locking else 3
        return np.array([self._batch.modes(i)[:count] for i in range(self.size)], dtype=float)

    def object_positions(self, index: int = 0) -> np.ndarray:
        """(N, 3) world position [m] of object ``index``'s centre of mass (free objects)."""
        slices = self.simulator.scene.object_q_slice(index)
        return self._batch.q[:, slices.start : slices.start + 3]

    @property
    def diverged(self) -> np.ndarray:
        """(N,) whether each environment's run diverged (it is frozen at its last good state)."""
        return np.array([self._batch.divergence(i).kind != 0 for i in range(self.size)])

    def divergence(self, env: int) -> str:
        """Why environment ``env`` diverged ("" if it did not)."""
        return divergence_text(self._batch.divergence(self._env(env)))

    # ------------------------------------------------------------------ kernels for vectorised controllers
    def gravity_torques(self) -> np.ndarray:
        """(N, nv_hand) hand gravity torques G(q) [N m] at the current states."""
        return self._batch.gravity(self.threads)

    def fingertip_jacobians(self, fingers: Sequence[str] | None = None) -> np.ndarray:
        """(N, n_fingers, 3, nv_hand) translational fingertip Jacobians, world-aligned, at the current states."""
        fingers = list(self._tip_frames) if fingers is None else list(fingers)
        unknown = [finger for finger in fingers if finger not in self._tip_frames]
        if unknown:
            raise InputError(f"unknown fingers {unknown}; valid fingers: {', '.join(self._tip_frames)}")
        frames = [int(self._tip_frames[finger]) for finger in fingers]
        return self._batch.frame_jacobians(frames, self.threads).reshape(self.size, len(frames), 3, self._nvh)

    # ------------------------------------------------------------------ stepping
    def step(self, u: Any) -> None:
        """Advance every environment by ``dt`` with inputs ``u`` of shape (N, n_inputs) [N m]."""
        u = np.asarray(u, dtype=float)
        shape = (self.size, self.simulator.actuation.n_inputs)
        if u.shape != shape:
            raise InputError(f"`u` must have shape {shape} (environments, inputs), got {u.shape}")
        bad = ~np.isfinite(u).all(axis=1)
        if bad.any():
            raise InputError(f"`u` must be finite; NaN/inf in environments {np.flatnonzero(bad).tolist()[:10]}")
        simulator = self.simulator
        if self._barrett:
            self._batch.step_barrett(u, simulator.max_speed, simulator.max_penetration, self.threads)
        else:
            torques = self._saturated(u)
            self._batch.step(torques, self._drive, simulator.max_speed, simulator.max_penetration, self.threads)
        self.t = round(self.t / self.simulator.dt + 1) * self.simulator.dt

    def rollout(self, u: Any, steps: int | None = None, record: bool = True) -> BatchRollout:
        """Open-loop rollouts: every environment steps through its own inputs in one compiled call.

        No Python runs between steps, and each environment's steps run on one thread: the threads meet once, at the
        end, where :meth:`step` meets them at every step.  The result is the same, bit for bit, as calling
        :meth:`step` with the same inputs, step after step.

        Args:
            u: Inputs [N m], (N, steps, n_inputs) one row per step, or (N, n_inputs) held for ``steps`` steps.
            steps: Number of steps; needed for held inputs, else taken from ``u`` (and checked against it).
            record: Keep the state after every step (``False``: only the final states, in the batch).

        Returns:
            The states after every step (empty arrays when ``record`` is false); the batch holds the last ones.

        Raises:
            InputError: ``u`` of another shape or not finite, ``steps`` not a positive integer.
        """
        u = np.asarray(u, dtype=float)
        n_inputs = self.simulator.actuation.n_inputs
        if steps is not None and (isinstance(steps, bool) or not isinstance(steps, int | np.integer) or steps < 1):
            raise InputError(f"`steps` must be a positive integer, got {steps!r}")
        if u.ndim == 3 and u.shape[0] == self.size and u.shape[2] == n_inputs:
            if steps is not None and steps != u.shape[1]:
                raise InputError(f"`steps` is {steps} but `u` holds {u.shape[1]} steps of inputs")
            steps = u.shape[1]
        elif u.shape != (self.size, n_inputs) or steps is None:
            raise InputError(
                f"`u` must have shape ({self.size}, steps, {n_inputs}) (environments, steps, inputs), or "
                f"({self.size}, {n_inputs}) held with `steps` given; got {u.shape} and steps={steps!r}"
            )
        if steps == 0:
            raise InputError("`u` must hold at least one step of inputs")
        bad = ~np.isfinite(u.reshape(self.size, -1)).all(axis=1)
        if bad.any():
            raise InputError(f"`u` must be finite; NaN/inf in environments {np.flatnonzero(bad).tolist()[:10]}")
        simulator = self.simulator
        inputs = (u if self._barrett else self._saturated(u)).reshape(self.size, -1)
        limits = (simulator.max_speed, simulator.max_penetration)
        q_record, v_record = self._batch.rollout(
            inputs, int(steps), self._barrett, self._drive, *limits, self.threads, bool(record)
        )
        times = []
        for _ in range(int(steps)):
            self.t = round(self.t / simulator.dt + 1) * simulator.dt
            times.append(self.t)
        shape = (self.size, int(steps), -1) if record else (self.size, 0, 0)
        return BatchRollout(np.array(times), q_record.reshape(shape), v_record.reshape(shape), self._nqh, self._nvh)

    def run(self, controller: Callable[[float, BatchSimulator], Any], duration: float) -> BatchSimulator:
        """Step ``duration`` [s] with ``u = controller(t, batch)`` (shape (N, n_inputs)) at every step."""
        steps = round(as_positive(duration, "duration") / self.simulator.dt)
        for _ in range(steps):
            self.step(controller(self.t, self))
        return self

    def contacts(self, env: int) -> ContactSet:
        """The contacts (with forces) of environment ``env``'s last step."""
        return contact_set(self._batch.contacts(self._env(env)))

    def state(self, env: int) -> State:
        """Environment ``env`` as a :class:`~bhgrasp.data.state.State` (built on demand; a start state for a run)."""
        env = self._env(env)
        memory = memory_of(self._batch.memory(env))
        modes = self.modes[env]
        source = StepOutput(self.simulator, self.contacts(env), memory)
        scene_q, scene_v = self._batch.q[env].copy(), self._batch.v[env].copy()
        return SimulatedState.lazy(self.t, scene_q, scene_v, modes, source, None, self.simulator.layout.signature)

    def _saturated(self, torques: np.ndarray) -> np.ndarray:
        """Joint torques [N m] (..., nv_hand) as the fully actuated hand applies them (clipped if it saturates).

        As :meth:`~bhgrasp.sim.actuation.FullyActuated.joint_torques`, for any leading axes.
        """
        actuation = self.simulator.actuation
        return np.clip(torques, -actuation.limit, actuation.limit) if actuation.saturate else torques

    def _env(self, env: int) -> int:
        if isinstance(env, bool) or not isinstance(env, int | np.integer) or not 0 <= env < self.size:
            raise InputError(f"`env` must be an environment index in [0, {self.size}), got {env!r}")
        return int(env)


__all__ = ["BatchRollout", "BatchSimulator"]
