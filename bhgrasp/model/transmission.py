"""How a hand's drive turns its inputs into joint torques: the model a simulator and a controller share.

A drive has ``n_inputs`` inputs (motor or joint torques [N m]) and, in its current mode (e.g. the BH8-280's
TorqueSwitch states, :mod:`bhgrasp.barrett.transmission`):

- a transmission T (nv, m): the hand velocities the drive lets move are v = T w (joints outside T's range hold);
- a gear matrix B (nv, n_inputs): the joint torques per unit input, tau = B u (before the reactions of held joints);
- the viscous damping it puts on each joint [N m s/rad]: passive joint damping plus motor damping reflected
  through the gears, placed so that T^T D T counts each driven coordinate once.

These are properties of the hand, not of a simulator: :class:`~bhgrasp.sim.actuation.Actuation` simulates a drive
with them, and a controller that commands the inputs (:class:`~bhgrasp.controllers.motor_commands.MotorCommands`) reads
the same model. Modes are numeric flags as a :class:`~bhgrasp.data.state.State` carries them (``actuation_modes``);
``None`` or an empty array means the drive's initial mode.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Sequence
from typing import Any

import numpy as np

from bhgrasp._validation import as_vector
from bhgrasp.errors import InputError
from bhgrasp.model.hand import Hand


class Transmission(ABC):
    """A hand's drive: inputs -> joint torques, the motions it allows and the damping it adds, per mode."""

    def __init__(self, hand: Hand, damping: float | Sequence[float] = 0.0) -> None:
        """Args: ``hand``: the driven hand; ``damping``: passive viscous damping [N m s/rad], scalar or per joint."""
        if not isinstance(hand, Hand):
            raise InputError(f"`hand` must be a bhgrasp Hand, got {hand!r}")
        self.hand = hand
        self.passive_damping = per_joint(damping, hand.nv, "damping")

    @property
    @abstractmethod
    def n_inputs(self) -> int:
        """Number of inputs."""

    @abstractmethod
    def matrix(self, modes: Any = None) -> np.ndarray:
        """T (nv, m): hand velocities = T @ driven velocities, in ``modes``."""

    @abstractmethod
    def gears(self, modes: Any = None) -> np.ndarray:
        """B (nv, n_inputs): joint torques [N m] per unit input in ``modes`` (no saturation)."""

    @abstractmethod
    def joint_damping(self, modes: Any = None) -> np.ndarray:
        """Viscous damping per joint [N m s/rad] in ``modes``: passive plus reflected motor damping."""

    def motor_inputs(self, tau: Any, modes: Any = None) -> np.ndarray:
        """Inputs u with T^T B u = T^T tau: they do the work of ``tau`` [N m] on every motion T allows.

        Least squares when T^T B is not square (more inputs than driven coordinates).
        """
        transmission = self.matrix(modes)
        tau = as_vector(tau, "tau", transmission.shape[0])
        projected = transmission.T @ self.gears(modes)
        if projected.shape[0] == projected.shape[1]:
            return np.linalg.solve(projected, transmission.T @ tau)
        return np.linalg.lstsq(projected, transmission.T @ tau, rcond=None)[0]


class DirectDrive(Transmission):
    """One torque per joint (the thesis' assumption): T = B = I, damping the passive one."""

    def __init__(self, hand: Hand, damping: float | Sequence[float] = 0.0) -> None:
        """Args as :class:`Transmission`."""
        super().__init__(hand, damping)
        self._identity = np.eye(hand.nv)

    @property
    def n_inputs(self) -> int:
        """One input per joint."""
        return self.hand.nv

    def matrix(self, modes: Any = None) -> np.ndarray:
        """Identity: every joint is driven."""
        return self._identity

    def gears(self, modes: Any = None) -> np.ndarray:
        """Identity: the inputs are the joint torques."""
        return self._identity

    def joint_damping(self, modes: Any = None) -> np.ndarray:
        """The passive damping (a copy)."""
        return self.passive_damping.copy()


def per_joint(value: float | Sequence[float], size: int, name: str) -> np.ndarray:
    """A finite, non-negative value per joint from a scalar or ``size`` values (a fresh array)."""
    if np.ndim(value) == 0:
        try:
            array = np.full(size, float(value))
        except (TypeError, ValueError) as error:
            raise InputError(f"`{name}` must be a number or {size} numbers, got {value!r}") from error
    else:
        array = as_vector(value, name, size)
    if not np.all(np.isfinite(array)) or np.any(array < 0):
        raise InputError(f"`{name}` must be finite and >= 0, got {np.asarray(value).tolist()}")
    return array.copy()


__all__ = ["DirectDrive", "Transmission", "per_joint"]
