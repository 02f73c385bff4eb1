"""The impedance controller of thesis chapter 4: each finger's impedance law over a fingertip computed-torque loop.

The laws, and why the desired force is fed forward to the inner loop: :mod:`bhgrasp.controllers.impedance`.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from bhgrasp._validation import as_vector
from bhgrasp.controllers.base import Controller
from bhgrasp.controllers.impedance import ImpedanceLaw, Sample
from bhgrasp.controllers.workspace import WorkspaceComputedTorque
from bhgrasp.data import State
from bhgrasp.errors import InputError
from bhgrasp.grasp.sensing import ContactSensing
from bhgrasp.model.hand import Hand
from bhgrasp.motion.trajectories import Reference


class ImpedanceController(Controller):
    """Impedance outer loops for one or several fingers around an inner fingertip computed-torque loop.

    Logged per finger ``<finger>/force`` (normal or full force), ``<finger>/x_c``, ``<finger>/delta_x`` and the
    adaptive estimates; plus ``reaction_torque`` = J^T F of the sensed contacts (thesis (4.8)) unless turned off.
    """

    def __init__(
        self,
        nominal: Hand,
        laws: Mapping[str, ImpedanceLaw],
        kp: Any = 430.0,
        kv: Any = 175.0,
        feedforward: bool = True,
        log_reaction_torque: bool = True,
    ) -> None:
        """Set up the loops.

        Args:
            nominal: The controller's model of the hand.
            laws: Finger -> impedance law.
            kp, kv: Inner fingertip computed-torque gains [1/s^2], [1/s] (thesis F3: 430, 175).
            feedforward: Add J^T (desired contact force) while a finger touches (see the module notes).
            log_reaction_torque: Log ``reaction_torque`` (a point Jacobian per contact and step); off for runs that
                read only the forces, e.g. the evaluations of a tuning.
        """
        super().__init__()
        if not laws:
            raise InputError("`laws` must map at least one finger to an impedance law")
        for finger, law in laws.items():
            if not isinstance(law, ImpedanceLaw):
                raise InputError(f"laws[{finger!r}] must be an ImpedanceLaw (PositionImpedance, ...), got {law!r}")
        self.nominal = nominal
        self.laws = dict(laws)
        self._commands = {finger: _Commanded() for finger in self.laws}
        self.inner = WorkspaceComputedTorque(nominal, self._commands, kp=kp, kv=kv)
        self.sensing = ContactSensing(nominal)
        self.feedforward = bool(feedforward)
        self.log_reaction_torque = bool(log_reaction_torque)
        self._time: float | None = None

    def reset(self, state: State) -> None:
        """Reset every law's filter/estimates and the inner loop."""
        for law in self.laws.values():
            law.reset()
        for command in self._commands.values():
            command.sample = None
        self.inner.reset(state)
        self._time = None

    def __call__(self, t: float, state: State) -> np.ndarray:
        """Joint torques [N m]."""
        dt = 0.0 if self._time is None else t - self._time
        if dt < 0.0:
            raise InputError(f"time went backwards: t = {t} after {self._time}; call reset() to restart")
        self._time = t
        hand = self.nominal
        q, v = as_vector(state.q, "state.q", hand.nq), as_vector(state.v, "state.v", hand.nv)
        terms = self.inner._workspaces(q, v)
        contacts = self.sensing.fingers(state)
        extra = np.zeros(hand.nv)
        for finger, law in self.laws.items():
            contact = contacts[finger]
            sample = law.command(t, terms[finger].position, contact, dt)
            self._commands[finger].sample = sample
            if self.feedforward:
                force = np.asarray(law.feedforward(contact))
                if np.count_nonzero(force):  # (J^T 0 adds nothing)
                    extra += terms[finger].jacobian.T @ force  # the fingertip Jacobian (world)
            self.log[f"{finger}/x_c"] = sample[0]
            for key, value in law.log.items():
                self.log[f"{finger}/{key}"] = np.array(value, dtype=float)
        tau = self.inner._control(t, state, q, v, terms) + extra
        if self.log_reaction_torque:
            self.log["reaction_torque"] = (
                self.sensing.reaction_torques(state) if state.contact_bodies else np.zeros(hand.nv)
            )
        return tau


class _Commanded(Reference):
    """The inner loop's reference: whatever the outer loop last commanded."""

    def __init__(self) -> None:
        self.sample: Sample | None = None

    @property
    def size(self) -> int:
        return 3

    def __call__(self, t: float) -> Sample:
        if self.sample is None:
            raise InputError("the impedance outer loop has not produced a command yet")
        return self.sample


__all__ = ["ImpedanceController"]
