"""The engine protocol: what a Simulator asks of the engine that steps its physics, over plain data.

Two engines implement it, the compiled one (:class:`~bhgrasp.sim.compiled.CompiledEngine`, the C++ step of
``bhgrasp._core``) and its readable Python twin (:class:`~bhgrasp.sim.python_engine.PythonEngine`).  An engine is
built once from a scene, a contact law and frozen :class:`~bhgrasp.sim.settings.SimulatorSettings`; a step is a
function of its arguments alone (configuration, velocity, joint torques, the drive's terms in the current actuation
mode, the contact memory), so the engine keeps nothing from one step to the next and the Simulator reaches into
none of its parts.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, NamedTuple, Protocol

import numpy as np

from bhgrasp.data import ContactMemory, ContactSet
from bhgrasp.sim.actuation import Actuation
from bhgrasp.sim.settings import SimulatorSettings


@dataclass(frozen=True, eq=False)
class DriveTerms:
    """An actuation's terms in its current mode, as a step needs them (plain arrays).

    Attributes:
        transmission: ``T`` (nv_hand, n_driven): hand velocities = ``T @`` driven velocities.
        joint_damping: Viscous damping per hand joint [N m s/rad] (passive joints + drive).
        friction: Coulomb friction per hand joint [N m].
        motor_damping: The drive's own share of ``joint_damping`` [N m s/rad] (what the clutch does not pass).
    """

    transmission: np.ndarray
    joint_damping: np.ndarray
    friction: np.ndarray
    motor_damping: np.ndarray

    @classmethod
    def of(cls, actuation: Actuation) -> DriveTerms:
        """The terms of ``actuation`` in its current mode."""
        damping = actuation.joint_damping()
        return cls(actuation.transmission(), damping, actuation.friction, damping - actuation.damping)


def drive_key(actuation: Actuation) -> tuple:
    """What an actuation's :class:`DriveTerms` depend on: its modes and parameters (a cache key)."""
    return (
        actuation.modes().tobytes(),
        actuation.damping.tobytes(),
        actuation.friction.tobytes(),
        getattr(actuation, "motor_damping", None),
        getattr(actuation, "saturate", None),
    )


class Divergence(NamedTuple):
    """Why a step diverged, as an engine saw it (``kind`` 0: it did not)."""

    kind: int
    index: int
    value: float


NO_DIVERGENCE = Divergence(0, -1, 0.0)


class StepResult(NamedTuple):
    """What one engine step returns (the compiled engine returns its own C++ ``StepResult`` of the same fields).

    Attributes:
        q, v: The scene's configuration and velocity after the step.
        contacts: The step's contacts with their forces (a ``ContactSet``, or the compiled engine's ``Contacts``).
        drive: Hand joint torques the drive delivered over the step [N m], (nv_hand,).
        memory: The contact memory after the step (a ``ContactMemory``, or the compiled engine's ``Memory``).
        divergence: What the engine found diverged, or ``None`` when it leaves the check to the Simulator.
        load: The load the drive carried [N m], (nv_hand,): ``drive`` less the hand links' own inertial torques
            (M a), what a clutch between a motor of dominant reflected inertia and the links transmits.
    """

    q: np.ndarray
    v: np.ndarray
    contacts: Any
    drive: np.ndarray
    memory: Any
    divergence: Any
    load: np.ndarray


class StepFields(Protocol):
    """A step's result as the Simulator reads it, field by field.

    A :class:`StepResult` (the Python engine) or the compiled engine's own ``StepResult`` (the same fields read from
    C++, ``q`` and ``v`` read-only; not a tuple).
    """

    q: np.ndarray
    v: np.ndarray
    contacts: Any
    drive: np.ndarray
    memory: Any
    divergence: Any
    load: np.ndarray


class Engine(Protocol):
    """One physics step over plain data; both engines implement it."""

    name: str

    def drive(self, terms: DriveTerms) -> Any:
        """``terms`` in the form this engine's :meth:`step` takes (built once per actuation mode)."""

    def memory(self, memory: ContactMemory) -> Any:
        """A :class:`~bhgrasp.data.contacts.ContactMemory` in the form this engine's :meth:`step` takes."""

    def step(self, q: np.ndarray, v: np.ndarray, tau: np.ndarray, drive: Any, memory: Any) -> StepFields:
        """Advance ``dt`` from ``(q, v)`` with hand joint torques ``tau`` (or nv generalized forces)."""

    def detect(self, q: np.ndarray, memory: ContactMemory) -> ContactSet:
        """The contacts at ``q`` matched to ``memory`` (no forces)."""

    def contact_set(self, contacts: Any) -> ContactSet:
        """A step's contacts as a :class:`~bhgrasp.data.contacts.ContactSet`."""

    def contact_memory(self, memory: Any) -> ContactMemory:
        """A step's memory as a :class:`~bhgrasp.data.contacts.ContactMemory`."""


def divergence(q: np.ndarray, v: np.ndarray, contacts: ContactSet, settings: SimulatorSettings) -> Divergence:
    """Whether a step's result diverged, checked in the compiled step's order (``src/engine.cpp``).

    A non-finite position (kind 1) or velocity (2), then a speed above ``max_speed`` (3), a contact deeper than
    ``max_penetration`` (4), a coordinate beyond ``max_coordinate`` (5); ``index`` is the first offending coordinate
    (-1 for a depth), ``value`` what it held.
    """
    for kind, values in ((1, q), (2, v)):
        bad = np.flatnonzero(~np.isfinite(values))
        if len(bad):
            return Divergence(kind, int(bad[0]), float(values[bad[0]]))
    if len(v):
        index = int(np.argmax(np.abs(v)))
        if not abs(v[index]) <= settings.max_speed:
            return Divergence(3, index, float(abs(v[index])))
    if len(contacts) and contacts.depth.max() > settings.max_penetration:
        return Divergence(4, -1, float(contacts.depth.max()))
    if len(q):
        index = int(np.argmax(np.abs(q)))
        if not abs(q[index]) <= settings.max_coordinate:
            return Divergence(5, index, float(q[index]))
    return NO_DIVERGENCE


__all__ = ["NO_DIVERGENCE", "Divergence", "DriveTerms", "Engine", "StepFields", "StepResult", "divergence", "drive_key"]
