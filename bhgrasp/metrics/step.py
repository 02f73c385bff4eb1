"""Step response of a run: rise time, overshoot, settling time and steady-state error per channel."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from bhgrasp._validation import as_positive, as_vector
from bhgrasp.errors import InputError
from bhgrasp.metrics.signals import as_numeric, as_signal, per_channel, sample_times


@dataclass(frozen=True)
class StepResponse:
    """Per-channel step-response characteristics, each an array of shape (k,).

    Attributes:
        overshoot_percent: Largest excursion beyond the target in the step direction, in % of the step size.
        rise_time: Time [s] from first reaching the lower to first reaching the upper rise fraction of the step;
            ``inf`` if either is never reached.
        settling_time: Time [s] from ``t[0]`` after which the response stays within the band around the target;
            ``inf`` if it is outside the band at the last sample.
        steady_state_error: ``|y[-1] - target|``, in signal units.
        peak_time: Time [s] from ``t[0]`` of the sample furthest in the step direction.
    """

    overshoot_percent: np.ndarray
    rise_time: np.ndarray
    settling_time: np.ndarray
    steady_state_error: np.ndarray
    peak_time: np.ndarray


def step_response(
    t: Any,
    y: Any,
    target: Any,
    start: Any = None,
    band: float = 0.02,
    rise: tuple[float, float] = (0.1, 0.9),
) -> StepResponse:
    """Characteristics of the response ``y`` to a step from ``start`` to ``target`` applied at ``t[0]``.

    Crossing times (rise, settling) are linearly interpolated between samples; the overshoot and peak are those
    of the samples.

    Args:
        t: (N,) strictly increasing sample times [s].
        y: (N,) or (N, k) response.
        target: Final value of the step, scalar or (k,).
        start: Initial value of the step, scalar or (k,); default ``y[0]``.
        band: Settling band as a fraction of ``|target - start|``, in (0, 1).
        rise: (lower, upper) fractions of the step defining the rise time, ``0 <= lower < upper <= 1``.

    Returns:
        The per-channel :class:`StepResponse`.

    Raises:
        InputError: On bad shapes, NaN/inf, non-increasing ``t``, bad ``band``/``rise``, or a zero step size
            (``target == start``) on some channel.
    """
    t = sample_times(t)
    y = as_signal(y, "y", t.shape[0])
    k = y.shape[1]
    target = per_channel(target, "target", k)
    start = y[0].copy() if start is None else per_channel(start, "start", k)
    band = as_positive(band, "band")
    if band >= 1.0:
        raise InputError(f"`band` must be a fraction of the step size in (0, 1), got {band!r}")
    lower, upper = _rise_fractions(rise)
    step = target - start
    if np.any(step == 0.0):
        channel = int(np.flatnonzero(step == 0.0)[0])
        raise InputError(
            f"step size `target - start` is 0 on channel {channel} (start = {float(start[channel])!r}, "
            f"target = {float(target[channel])!r}); a step response needs target != start"
        )
    progress = (y - start) / step  # 0 at the start value, 1 at the target, increasing in the step direction
    peak = np.argmax(progress, axis=0)
    return StepResponse(
        overshoot_percent=100.0 * np.maximum(0.0, progress[peak, np.arange(k)] - 1.0),
        rise_time=np.array([_rise_time(t, p, lower, upper) for p in progress.T]),
        settling_time=np.array([_settling(t, p, band) for p in progress.T]) - t[0],
        steady_state_error=np.abs(y[-1] - target),
        peak_time=t[peak] - t[0],
    )


def _rise_fractions(rise: Any) -> tuple[float, float]:
    if as_numeric(rise, "rise").shape != (2,):
        raise InputError(f"`rise` must be a pair (lower, upper) of step fractions, got {rise!r}")
    lower, upper = as_vector(rise, "rise", 2)
    if not 0.0 <= lower < upper <= 1.0:
        raise InputError(f"`rise` must satisfy 0 <= lower < upper <= 1, got {rise!r}")
    return float(lower), float(upper)


def _rise_time(t: np.ndarray, progress: np.ndarray, lower: float, upper: float) -> float:
    """Time from first reaching ``lower`` to first reaching ``upper``; ``inf`` if ``upper`` is never reached."""
    end = _first_crossing(t, progress, upper)
    return end if end == np.inf else end - _first_crossing(t, progress, lower)


def _first_crossing(t: np.ndarray, progress: np.ndarray, level: float) -> float:
    """First time ``progress`` reaches ``level`` (interpolated), ``t[0]`` if it starts there, ``inf`` if never."""
    reached = np.flatnonzero(progress >= level)
    if reached.size == 0:
        return np.inf
    i = int(reached[0])
    if i == 0:
        return float(t[0])
    return _interpolate(t, progress, i - 1, level)


def _settling(t: np.ndarray, progress: np.ndarray, band: float) -> float:
    """Time after which ``|progress - 1| <= band`` for good (interpolated); ``inf`` if outside at the end."""
    outside = np.flatnonzero(np.abs(progress - 1.0) > band)
    if outside.size == 0:
        return float(t[0])
    j = int(outside[-1])
    if j == t.shape[0] - 1:
        return np.inf
    level = 1.0 + band if progress[j] > 1.0 else 1.0 - band  # the edge of the band crossed on the way in
    return _interpolate(t, progress, j, level)


def _interpolate(t: np.ndarray, values: np.ndarray, i: int, level: float) -> float:
    """Time at which the segment from sample ``i`` to ``i + 1`` reaches ``level`` (linear interpolation)."""
    fraction = (level - values[i]) / (values[i + 1] - values[i])
    return float(t[i] + fraction * (t[i + 1] - t[i]))


__all__ = ["StepResponse", "step_response"]
