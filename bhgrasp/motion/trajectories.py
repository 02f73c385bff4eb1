"""Reference generators for controllers (thesis chapters 3-5): desired position, velocity and acceleration.

Every reference is a callable ``ref(t) -> (position, velocity, acceleration)``: three fresh float64 arrays of
shape ``(ref.size,)``, evaluated analytically (no numerical differentiation).  Time ``t`` is in seconds and may be
any finite number (before a delay the reference holds its start).  Units are those of the values given: joint
references in [rad], [rad/s], [rad/s^2]; Cartesian ones in [m], [m/s], [m/s^2] in the world frame.

- :class:`SmoothStep`: the thesis' first-order approach to a goal (5.36), optionally delayed per component.
- :func:`exponential_approach`: the same curve written with a rate, as in thesis (4.29).
- :class:`Sinusoid`: ``offset + amplitude sin(2 pi f t + phase)``.
- :class:`Quintic`: minimum-jerk point-to-point motion (zero velocity and acceleration at both ends).
- :class:`Constant`: a set point.

Pose references (:mod:`bhgrasp.motion.pose_references`) and fingertip references turned into joint ones
(:mod:`bhgrasp.motion.fingertip_reference`) build on :class:`Reference` and the helpers here.

Scalar arguments broadcast against per-component arrays; arrays must all have the same length.  Arguments are
validated at construction and raise :class:`~bhgrasp.errors.InputError` naming the argument, the value and what
was expected.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from typing import Any

import numpy as np

from bhgrasp._validation import as_real, as_vector
from bhgrasp.errors import InputError

Sample = tuple[np.ndarray, np.ndarray, np.ndarray]  # (position, velocity, acceleration), each of shape (size,)


class Reference(ABC):
    """A desired trajectory: ``ref(t)`` returns (position, velocity, acceleration), each of shape (size,)."""

    @property
    @abstractmethod
    def size(self) -> int:
        """Number of components of each returned array."""

    @abstractmethod
    def __call__(self, t: float) -> Sample:
        """Position, velocity and acceleration at time ``t`` [s] (finite), as fresh float64 arrays.

        Raises:
            InputError: ``t`` is not a finite number.
        """

    def __repr__(self) -> str:
        return f"{type(self).__name__}(size={self.size})"


class SmoothStep(Reference):
    """First-order approach from ``start`` to ``goal``, thesis (5.36), with an optional per-component delay.

    ``q_d(t) = start + (goal - start) (1 - exp(-(t - delay) / a))`` for ``t >= delay`` and ``start`` before, with
    ``a`` the time constant.  This is the thesis' reference as printed: its position is continuous but its
    velocity jumps from 0 to ``(goal - start) / a`` at ``t = delay`` (the value returned at ``t = delay`` is the
    one after the jump) and its acceleration from 0 to ``-(goal - start) / a^2``.  Use :class:`Quintic` where a
    smooth start matters.  Per-component delays let, e.g., the spread joints move first and the fingers later.
    """

    def __init__(self, start: Any, goal: Any, time_constant: Any, delay: Any = 0.0) -> None:
        """Build the step.

        Args:
            start: Initial value, scalar or shape (n,).
            goal: Final value, scalar or shape (n,).
            time_constant: ``a`` [s] > 0, scalar or per component (63 % of the way after one ``a``).
            delay: Start time [s] >= 0, scalar or per component.
        """
        self.start, self.goal, self.time_constant, self.delay = components(
            start=start, goal=goal, time_constant=time_constant, delay=delay
        )
        require_all(self.time_constant > 0.0, "time_constant", self.time_constant, "> 0 [s]")
        require_all(self.delay >= 0.0, "delay", self.delay, ">= 0 [s]")

    @property
    def size(self) -> int:
        """Number of components."""
        return self.start.size

    def __call__(self, t: float) -> Sample:
        """Position, velocity and acceleration at time ``t`` [s]."""
        return self._sample(time_of(t))

    def table(self, times: Any) -> np.ndarray:
        """(position, velocity, acceleration) at each of ``times`` [s], one row each, (n, 3 size).

        The samples of :meth:`__call__` to the bit: the same operations, on every time at once.
        """
        times = as_vector(times, "times")
        return np.concatenate(self._sample(times[:, None]), axis=1)

    def _sample(self, t: Any) -> Sample:
        """The step at ``t`` [s], a float (rows of size) or a column of times (rows of (n, size))."""
        elapsed = t - self.delay
        moving = elapsed >= 0.0
        scaled = np.where(moving, elapsed, 0.0) / self.time_constant
        decay = np.where(moving, np.exp(-scaled), 0.0)
        change = self.goal - self.start
        position = self.start + change * np.where(moving, -np.expm1(-scaled), 0.0)
        velocity = change * decay / self.time_constant
        acceleration = -velocity / self.time_constant
        return position, velocity, acceleration


def exponential_approach(start: Any, goal: Any, rate: Any) -> SmoothStep:
    """The thesis' exponential Cartesian path (4.29): ``x(t) = x_i e^{-a t} + x_f (1 - e^{-a t})``.

    The thesis prints ``x_i`` in both terms; the second is the final point ``x_f`` (so ``x(0) = x_i`` and
    ``x -> x_f``).  This is :class:`SmoothStep` with time constant ``1 / rate`` and no delay.

    Args:
        start: ``x_i``, scalar or shape (n,).
        goal: ``x_f``, scalar or shape (n,).
        rate: ``a`` [1/s] > 0, scalar or per component.
    """
    (rates,) = components(rate=rate)
    require_all(rates > 0.0, "rate", rates, "> 0 [1/s]")
    return SmoothStep(start, goal, 1.0 / rates if np.ndim(rate) else 1.0 / float(rate))


class Sinusoid(Reference):
    """``offset + amplitude sin(2 pi frequency t + phase)``, per component."""

    def __init__(self, offset: Any, amplitude: Any, frequency: Any, phase: Any = 0.0) -> None:
        """Build the sinusoid; scalars broadcast to the common size of the array arguments.

        Args:
            offset: Mean value, scalar or shape (n,).
            amplitude: Amplitude (any sign), scalar or shape (n,).
            frequency: Frequency [Hz] >= 0, scalar or per component.
            phase: Phase at ``t = 0`` [rad], scalar or per component.
        """
        self.offset, self.amplitude, self.frequency, self.phase = components(
            offset=offset, amplitude=amplitude, frequency=frequency, phase=phase
        )
        require_all(self.frequency >= 0.0, "frequency", self.frequency, ">= 0 [Hz]")

    @property
    def size(self) -> int:
        """Number of components."""
        return self.offset.size

    def __call__(self, t: float) -> Sample:
        """Position, velocity and acceleration at time ``t`` [s]."""
        omega = 2.0 * np.pi * self.frequency
        angle = omega * time_of(t) + self.phase
        sine = self.amplitude * np.sin(angle)
        return self.offset + sine, self.amplitude * omega * np.cos(angle), -(omega**2) * sine


class Quintic(Reference):
    """Minimum-jerk motion from ``start`` to ``goal``: zero velocity and acceleration at both ends.

    With ``s = (t - delay) / duration`` clipped to [0, 1]: ``start + (goal - start)(10 s^3 - 15 s^4 + 6 s^5)``.
    It holds ``start`` (exactly) until ``delay`` and ``goal`` (exactly) from ``delay + duration`` on.  The peak
    speed is ``1.875 |goal - start| / duration``.
    """

    def __init__(self, start: Any, goal: Any, duration: Any, delay: Any = 0.0) -> None:
        """Build the motion.

        Args:
            start: Initial value, scalar or shape (n,).
            goal: Final value, scalar or shape (n,).
            duration: Time to go from start to goal [s] > 0, scalar or per component.
            delay: Start time [s] >= 0, scalar or per component.
        """
        self.start, self.goal, self.duration, self.delay = components(
            start=start, goal=goal, duration=duration, delay=delay
        )
        require_all(self.duration > 0.0, "duration", self.duration, "> 0 [s]")
        require_all(self.delay >= 0.0, "delay", self.delay, ">= 0 [s]")

    @property
    def size(self) -> int:
        """Number of components."""
        return self.start.size

    def __call__(self, t: float) -> Sample:
        """Position, velocity and acceleration at time ``t`` [s]."""
        s = np.clip((time_of(t) - self.delay) / self.duration, 0.0, 1.0)
        change = self.goal - self.start
        blend, rate, curvature = minimum_jerk(s)
        position = np.where(s >= 1.0, self.goal, self.start + change * blend)
        return position, change * rate / self.duration, change * curvature / (self.duration * self.duration)


def minimum_jerk(s: Any) -> tuple[Any, Any, Any]:
    """The minimum-jerk blend b(s) = 10 s^3 - 15 s^4 + 6 s^5 and its first two derivatives in s, for s in [0, 1].

    Products only (no ``**``): a float and a float64 array give the same bits, on any CPU (NumPy's vectorised
    ``power`` may round differently from the C library's ``pow``).
    """
    square, rest = s * s, 1.0 - s
    return square * s * (10.0 + s * (-15.0 + 6.0 * s)), 30.0 * square * rest * rest, 60.0 * s * rest * (1.0 - 2.0 * s)


class Constant(Reference):
    """A set point: ``value`` with zero velocity and acceleration."""

    def __init__(self, value: Any) -> None:
        """Build the set point from a scalar (size 1) or an array of shape (n,)."""
        (self.value,) = components(value=value)

    @property
    def size(self) -> int:
        """Number of components."""
        return self.value.size

    def __call__(self, t: float) -> Sample:
        """The value, and zero velocity and acceleration, at any finite ``t`` [s]."""
        time_of(t)
        return self.value.copy(), np.zeros(self.size), np.zeros(self.size)


def time_of(t: Any) -> float:
    """``t`` [s] as a finite float (any sign)."""
    return as_real(t, "t", nonnegative=False)


def components(**values: Any) -> list[np.ndarray]:
    """Each argument (scalar or 1-D) as a finite float64 array of the common length (scalars broadcast)."""
    arrays = {}
    for name, value in values.items():
        if np.ndim(value) == 0:
            arrays[name] = np.array([as_real(value, name, nonnegative=False)])
        else:
            arrays[name] = as_vector(value, name).copy()
            if arrays[name].size == 0:
                raise InputError(f"`{name}` must have at least one component, got shape (0,)")
    sizes = {name: array.size for name, array in arrays.items() if np.ndim(values[name]) != 0}
    if len(set(sizes.values())) > 1:
        shapes = ", ".join(f"`{name}` {(size,)}" for name, size in sizes.items())
        raise InputError(f"array arguments must have the same shape (scalars broadcast), got {shapes}")
    size = next(iter(sizes.values()), 1)
    return [np.broadcast_to(array, (size,)).copy() for array in arrays.values()]


def require_all(condition: np.ndarray, name: str, value: np.ndarray, expected: str) -> None:
    """Raise an :class:`~bhgrasp.errors.InputError` naming ``name``, ``value`` and ``expected`` unless all hold."""
    if not np.all(condition):
        shown = value.tolist() if value.size > 1 else float(value[0])
        raise InputError(f"`{name}` must be {expected}, got {shown!r}")


__all__ = [
    "Constant",
    "Quintic",
    "Reference",
    "Sample",
    "Sinusoid",
    "SmoothStep",
    "components",
    "exponential_approach",
    "minimum_jerk",
    "require_all",
    "time_of",
]
