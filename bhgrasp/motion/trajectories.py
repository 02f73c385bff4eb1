"""Reference generators for controllers (thesis chapters 3-5): desired position, velocity and acceleration.

Every reference is a callable ``ref(t) -> (position, velocity, acceleration)``: three fresh float64 arrays of
shape ``(ref.size,)``, evaluated analytically (no numerical differentiation).  Time ``t`` is in seconds and may be
any finite number (before a delay the reference holds its start).  Units are those of the values given: joint
references in [rad], [rad/s], [rad/s^2]; Cartesian ones in [m], [m/s], [m/s^2] in the world frame.

- :class:`SmoothStep`: the thesis' first-order approach to a goal (5.36), optionally delayed per component.
- :func:`exponential_approach`: the same curve written with a rate, as in thesis (4.29).
- :class:`Sinusoid`: ``offset + amplitude sin(2 pi f t + phase)``.
- :class:`Quintic`: minimum-jerk point-to-point motion (zero velocity and acceleration at both ends).
- :class:`PoseMotion`: minimum-jerk motion of a rigid-body pose by a world offset (twist as its velocity).
- :class:`Constant`: a set point.
- :class:`CartesianReference`: a fingertip reference in the world turned into a joint reference of a whole hand
  by closed-form IK and the finger Jacobian.

Scalar arguments broadcast against per-component arrays; arrays must all have the same length.  Arguments are
validated at construction and raise :class:`~bhgrasp.errors.InputError` naming the argument, the value and what
was expected.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from typing import Any

import numpy as np
import pinocchio as pin

from bhgrasp._validation import as_positive, as_real, as_vector, require_name
from bhgrasp.errors import InputError, ModelError
from bhgrasp.model.hand import Hand
from bhgrasp.model.ik import finger_ik

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
        self.start, self.goal, self.time_constant, self.delay = _components(
            start=start, goal=goal, time_constant=time_constant, delay=delay
        )
        _require(self.time_constant > 0.0, "time_constant", self.time_constant, "> 0 [s]")
        _require(self.delay >= 0.0, "delay", self.delay, ">= 0 [s]")

    @property
    def size(self) -> int:
        """Number of components."""
        return self.start.size

    def __call__(self, t: float) -> Sample:
        """Position, velocity and acceleration at time ``t`` [s]."""
        elapsed = _time(t) - self.delay
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
    (rates,) = _components(rate=rate)
    _require(rates > 0.0, "rate", rates, "> 0 [1/s]")
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
        self.offset, self.amplitude, self.frequency, self.phase = _components(
            offset=offset, amplitude=amplitude, frequency=frequency, phase=phase
        )
        _require(self.frequency >= 0.0, "frequency", self.frequency, ">= 0 [Hz]")

    @property
    def size(self) -> int:
        """Number of components."""
        return self.offset.size

    def __call__(self, t: float) -> Sample:
        """Position, velocity and acceleration at time ``t`` [s]."""
        omega = 2.0 * np.pi * self.frequency
        angle = omega * _time(t) + self.phase
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
        self.start, self.goal, self.duration, self.delay = _components(
            start=start, goal=goal, duration=duration, delay=delay
        )
        _require(self.duration > 0.0, "duration", self.duration, "> 0 [s]")
        _require(self.delay >= 0.0, "delay", self.delay, ">= 0 [s]")

    @property
    def size(self) -> int:
        """Number of components."""
        return self.start.size

    def __call__(self, t: float) -> Sample:
        """Position, velocity and acceleration at time ``t`` [s]."""
        s = np.clip((_time(t) - self.delay) / self.duration, 0.0, 1.0)
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


class PoseMotion(Reference):
    """Minimum-jerk motion of a rigid-body pose by a world offset: the object reference of the grasp supervisor.

    With the minimum-jerk blend b(t) of :class:`Quintic` (0 -> 1 over ``duration`` after ``delay``):
    ``x(t) = x_0 + b dx`` and ``R(t) = exp(b dtheta) R_0`` (a rotation about the fixed world axis of
    ``dtheta``).  The sample is (x [m], rotation vector log(R) [rad]); the velocity and acceleration are the world
    twist (v [m/s], omega [rad/s]) and its derivative, omega = b' dtheta, which is what the object-space
    controllers read.  (Adding ``dtheta`` to the rotation vector of R_0 instead, as a :class:`Quintic` on the six
    components would, turns about the wrong axis unless R_0 = I.)
    """

    def __init__(self, start: Any, offset: Any, duration: float, delay: float = 0.0) -> None:
        """Build the motion.

        Args:
            start: Initial pose as a ``pinocchio.SE3`` (world <- body).
            offset: (dx [m], dtheta [rad]): translation and rotation vector of the change, world.
            duration: Time of the motion [s] > 0.
            delay: Start time [s] >= 0.
        """
        if not isinstance(start, pin.SE3):
            raise InputError(f"`start` must be a pinocchio.SE3, got {type(start).__name__}")
        self.start = pin.SE3(start)
        self.offset = as_vector(offset, "offset", 6)
        self.duration, self.delay = as_positive(duration, "duration"), as_real(delay, "delay")

    @property
    def size(self) -> int:
        """Six: position and rotation vector."""
        return 6

    def __call__(self, t: float) -> Sample:
        """Pose (x, log R), twist (v, omega) and its derivative at time ``t`` [s]."""
        s = min(max((_time(t) - self.delay) / self.duration, 0.0), 1.0)  # the blend of Quintic(0, 1, ...), in floats
        blend, rate, curvature = minimum_jerk(s)
        rate, curvature = rate / self.duration, curvature / (self.duration * self.duration)
        rotation = pin.exp3(blend * self.offset[3:]) @ self.start.rotation
        position = np.concatenate((self.start.translation + blend * self.offset[:3], pin.log3(rotation)))
        return position, rate * self.offset, curvature * self.offset


class PosePath(Reference):
    """Back-to-back minimum-jerk moves of a rigid-body pose: waypoints joined at rest.

    E.g. a wrist's approach, lift, hold and place.
    Move i starts when move i-1 ends (the first after ``delay``) and changes the pose by its world offset (dx [m],
    dtheta [rad]) as :class:`PoseMotion` does; a zero offset is a pause.  The sample and its derivatives are
    :class:`PoseMotion`'s, from the pose the earlier moves reached; every move starts and ends at rest, so the
    path is C2 at the joins.
    """

    def __init__(self, start: Any, moves: Any, delay: float = 0.0) -> None:
        """Build the path.

        Args:
            start: Initial pose, a ``pinocchio.SE3`` (world <- body).
            moves: Sequence of (offset (6,), duration [s] > 0).
            delay: Start time of the first move [s] >= 0.
        """
        if not isinstance(start, pin.SE3):
            raise InputError(f"`start` must be a pinocchio.SE3, got {type(start).__name__}")
        moves = list(moves)
        if not moves:
            raise InputError("`moves` must hold at least one (offset, duration) pair")
        self.segments: list[PoseMotion] = []
        pose, begin = pin.SE3(start), as_real(delay, "delay")
        for i, move in enumerate(moves):
            if len(move) != 2:
                raise InputError(f"`moves[{i}]` must be an (offset (6,), duration [s]) pair, got {move!r}")
            offset, duration = as_vector(move[0], f"moves[{i}] offset", 6), as_positive(move[1], f"moves[{i}] duration")
            self.segments.append(PoseMotion(pose, offset, duration, begin))
            pose = pin.SE3(pin.exp3(offset[3:]) @ pose.rotation, pose.translation + offset[:3])
            begin += duration
        self.end_time, self.end = begin, pose

    @property
    def size(self) -> int:
        """Six: position and rotation vector."""
        return 6

    def __call__(self, t: float) -> Sample:
        """Pose (x, log R), world twist and its derivative at time ``t`` [s]."""
        t = _time(t)
        for segment in self.segments:
            if t < segment.delay + segment.duration:
                return segment(t)
        return self.segments[-1](t)


class Constant(Reference):
    """A set point: ``value`` with zero velocity and acceleration."""

    def __init__(self, value: Any) -> None:
        """Build the set point from a scalar (size 1) or an array of shape (n,)."""
        (self.value,) = _components(value=value)

    @property
    def size(self) -> int:
        """Number of components."""
        return self.value.size

    def __call__(self, t: float) -> Sample:
        """The value, and zero velocity and acceleration, at any finite ``t`` [s]."""
        _time(t)
        return self.value.copy(), np.zeros(self.size), np.zeros(self.size)


class CartesianReference(Reference):
    """A fingertip reference in the world [m] turned into a joint reference of the whole hand (size ``nv``).

    At each time the finger's joints come from the closed-form :func:`~bhgrasp.model.ik.finger_ik`, seeded with the
    previous solution (``q_rest`` at first and after :meth:`reset`) so that the IK branch stays continuous along
    the path.  With ``J`` the finger's columns of :meth:`Hand.fingertip_jacobian` (world-aligned):
    ``qdot = J^+ xdot`` and ``qddot = J^+ (xddot - Jdot qdot)``, where ``Jdot qdot`` is the classical fingertip
    acceleration at zero joint acceleration, in the world.  ``J^+`` is a least-squares solve, so a finger with
    two joints works: its fingertip (e.g. Barrett F3, proximal and distal only) moves in a fixed plane, and the
    Cartesian reference must lie in that plane (as a straight line between two reachable in-plane points does);
    a point farther than ``plane_tolerance`` from it raises :class:`~bhgrasp.errors.UnreachableError` from
    ``finger_ik``.  Every other joint is held at ``q_rest`` with zero velocity and acceleration.

    Evaluation is stateful (the IK seed) and uses the hand's Pinocchio data: one reference per thread.  Near a
    finger singularity (stretched finger) ``J`` is ill-conditioned and the joint rates grow accordingly.
    """

    def __init__(
        self, hand: Hand, finger: str, reference: Reference, q_rest: Any, *, plane_tolerance: float = 1e-6
    ) -> None:
        """Build the joint reference.

        Args:
            hand: A hand whose finger is Barrett-like (optional spread, then two parallel-axis joints) and whose
                joints are all 1-DOF (``nq == nv``).
            finger: Finger name, e.g. ``"F1"``.
            reference: Fingertip position reference of size 3, world frame [m].
            q_rest: Hand configuration [rad], shape (nq,): the other joints' positions and the first IK seed.
            plane_tolerance: Largest distance [m] of the target from a two-joint finger's plane.

        Raises:
            InputError: Not a :class:`Hand`, unknown finger, a reference not of size 3, a bad ``q_rest`` or
                ``plane_tolerance``.
            ModelError: The hand has joints with ``nq != nv``.
        """
        if not isinstance(hand, Hand):
            raise InputError(f"`hand` must be a bhgrasp Hand, got {type(hand).__name__}")
        require_name(finger, hand.fingers, "finger")
        if not isinstance(reference, Reference) or reference.size != 3:
            got = f"size {reference.size}" if isinstance(reference, Reference) else type(reference).__name__
            raise InputError(f"`reference` must be a Reference of size 3 (fingertip position [m]), got {got}")
        if hand.nq != hand.nv:
            raise ModelError(f"CartesianReference needs nq == nv (1-DOF joints), got nq={hand.nq}, nv={hand.nv}")
        self.hand = hand
        self.finger = finger
        self.reference = reference
        self.q_rest = as_vector(q_rest, "q_rest", hand.nq).copy()
        self.plane_tolerance = as_positive(plane_tolerance, "plane_tolerance")
        self._indices = hand.finger_indices(finger)
        self._seed = self.q_rest.copy()

    @property
    def size(self) -> int:
        """``hand.nv``: one component per joint."""
        return self.hand.nv

    def reset(self) -> None:
        """Seed the next IK with ``q_rest`` again (e.g. before replaying the reference from its start)."""
        self._seed = self.q_rest.copy()

    def __call__(self, t: float) -> Sample:
        """Joint position [rad], velocity [rad/s] and acceleration [rad/s^2] at time ``t`` [s].

        Raises:
            InputError: ``t`` is not finite.
            UnreachableError: The fingertip target is out of reach, or out of a two-joint finger's plane.
        """
        x, xdot, xddot = self.reference(t)
        hand, indices = self.hand, self._indices
        solution = finger_ik(hand, self.finger, x, q0=self._seed, plane_tolerance=self.plane_tolerance)
        q = solution.apply(self.q_rest)
        self._seed = q.copy()
        jacobian = hand.fingertip_jacobian(q, self.finger)[:, indices]
        v = np.zeros(hand.nv)
        v[indices] = np.linalg.lstsq(jacobian, xdot, rcond=None)[0]
        a = np.zeros(hand.nv)
        bias = hand.fingertip_bias_acceleration(q, v, self.finger)
        a[indices] = np.linalg.lstsq(jacobian, xddot - bias, rcond=None)[0]
        return q, v, a


def _time(t: Any) -> float:
    return as_real(t, "t", nonnegative=False)


def _components(**values: Any) -> list[np.ndarray]:
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


def _require(condition: np.ndarray, name: str, value: np.ndarray, expected: str) -> None:
    if not np.all(condition):
        shown = value.tolist() if value.size > 1 else float(value[0])
        raise InputError(f"`{name}` must be {expected}, got {shown!r}")


__all__ = [
    "CartesianReference",
    "Constant",
    "PoseMotion",
    "PosePath",
    "Quintic",
    "Reference",
    "Sample",
    "Sinusoid",
    "SmoothStep",
    "exponential_approach",
]
