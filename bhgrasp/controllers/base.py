"""Controller protocol: ``reset(state)``, ``__call__(t, state) -> torques`` and a ``log`` of internals.

A controller sees only a :class:`~bhgrasp.data.state.State` and its own *nominal* :class:`~bhgrasp.model.hand.Hand`
(which may differ from the simulated plant: ``hand.perturbed(...)``); it never imports the simulator, so the same object
can drive a real hand.  The simulator also accepts any plain callable ``(t, state) -> u``.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from typing import Any

import numpy as np

from bhgrasp._validation import as_vector
from bhgrasp.data import State
from bhgrasp.errors import InputError
from bhgrasp.model.hand import Hand
from bhgrasp.motion.trajectories import Reference


class Controller(ABC):
    """Base of every controller.

    Attributes:
        log: Name -> latest value of the controller's internals (references, errors, sliding variables,
            parameter estimates); the simulator records it at every sample into ``Trajectory.log``.
    """

    def __init__(self) -> None:
        self.log: dict[str, np.ndarray] = {}

    def reset(self, state: State) -> None:  # noqa: B027  (stateless controllers need nothing)
        """Forget internal state (integrators, estimates) and start from ``state``."""

    @abstractmethod
    def __call__(self, t: float, state: State) -> np.ndarray:
        """Joint torques [N m], shape (nv,), for the sensed ``state`` at time ``t`` [s]."""


class JointTracking(Controller):
    """A controller that makes the hand joints track a joint reference, using a nominal model.

    Subclasses implement :meth:`torque` from the tracking error ``e = q - q_d`` (thesis (3.33)).
    """

    def __init__(self, nominal: Hand, reference: Reference) -> None:
        """Args: ``nominal``: the controller's model of the hand; ``reference``: joint reference of size ``nv``."""
        super().__init__()
        if not isinstance(nominal, Hand):
            raise InputError(f"`nominal` must be a bhgrasp Hand (e.g. `hand.perturbed(0.7)`), got {nominal!r}")
        if not isinstance(reference, Reference) or reference.size != nominal.nv:
            size = getattr(reference, "size", None)
            raise InputError(f"`reference` must be a Reference of size nv = {nominal.nv}, got {reference!r} ({size})")
        self.nominal = nominal
        self.reference = reference
        self._time: float | None = None

    def reset(self, state: State) -> None:
        """Check that the state fits the nominal model and restart the controller's clock."""
        as_vector(state.q, "state.q", self.nominal.nq)
        as_vector(state.v, "state.v", self.nominal.nv)
        self._time = None

    def __call__(self, t: float, state: State) -> np.ndarray:
        """Evaluate the reference at ``t`` and the control law on the sensed joint state."""
        q = as_vector(state.q, "state.q", self.nominal.nq)
        v = as_vector(state.v, "state.v", self.nominal.nv)
        q_d, v_d, a_d = self.reference(t)
        dt = 0.0 if self._time is None else t - self._time
        if dt < 0.0:
            raise InputError(f"time went backwards: t = {t} after {self._time}; call reset() to restart")
        self._time = t
        tau = self.torque(q, v, q_d, v_d, a_d, dt)
        self.log["q_d"], self.log["error"] = q_d, q - q_d
        if not np.all(np.isfinite(tau)):
            raise InputError(f"{type(self).__name__} produced non-finite torques {tau} at t = {t} s")
        return tau

    @abstractmethod
    def torque(
        self, q: np.ndarray, v: np.ndarray, q_d: np.ndarray, v_d: np.ndarray, a_d: np.ndarray, dt: float
    ) -> np.ndarray:
        """The control law: joint torques [N m] from state, reference and the time ``dt`` [s] since the last call."""


def gain_matrix(value: Any, size: int, name: str) -> np.ndarray:
    """A gain as a symmetric positive-definite (size, size) matrix: a positive scalar, per-joint vector or matrix.

    Raises:
        InputError: Wrong shape, non-finite, asymmetric or not positive definite.
    """
    array = np.asarray(value, dtype=float) if not isinstance(value, np.ndarray) else value.astype(float)
    if array.ndim == 0:
        array = np.full(size, float(array))
    if array.ndim == 1:
        as_vector(array, name, size)
        if np.any(array <= 0.0):
            raise InputError(f"`{name}` must be positive (a positive-definite diagonal gain), got {array}")
        return np.diag(array)
    if array.shape != (size, size) or not np.all(np.isfinite(array)):
        raise InputError(f"`{name}` must be a scalar, ({size},) or finite ({size}, {size}), got shape {array.shape}")
    if not np.allclose(array, array.T, rtol=1e-10, atol=1e-12):
        raise InputError(f"`{name}` must be symmetric, got {array}")
    if np.linalg.eigvalsh(array).min() <= 0.0:
        raise InputError(f"`{name}` must be positive definite; its eigenvalues are {np.linalg.eigvalsh(array)}")
    return array


def gain_vector(value: Any, size: int, name: str, allow_zero: bool = False) -> np.ndarray:
    """A diagonal gain as a (size,) vector of positive (or, with ``allow_zero``, non-negative) numbers."""
    array = as_vector(np.full(size, value) if np.ndim(value) == 0 else value, name, size)
    if np.any(array < 0.0) or (not allow_zero and np.any(array == 0.0)):
        expected = "non-negative" if allow_zero else "positive"
        raise InputError(f"`{name}` must be {expected}, got {array}")
    return array.copy()


def inertia_gain(hand: Hand, rate: float, q: Any = None) -> np.ndarray:
    """Per-joint torque gains ``rate`` x diag M(q): a gain that gives every joint the same rate [1/s or 1/s^2].

    ``q`` defaults to the middle of the joint range (0 for unlimited joints).  Used for the default gains of the
    sliding-mode family, whose laws take gains in torque units while a hand's links differ 10-fold in inertia.
    """
    if q is None:
        lower, upper = hand.lower, hand.upper
        q = np.where(np.isfinite(lower) & np.isfinite(upper), 0.5 * (lower + upper), 0.0)
    return float(rate) * np.diag(hand.mass_matrix(q)).copy()


__all__ = ["Controller", "JointTracking", "gain_matrix", "gain_vector", "inertia_gain"]
