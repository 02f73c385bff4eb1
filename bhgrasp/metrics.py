"""Performance metrics of a controlled run: tracking and force error, step response, control effort, chattering.

Plain functions on numpy arrays, independent of the simulator.  Every function takes the sample times ``t``
(shape (N,), strictly increasing, seconds) and one or more signals of shape (N,) or (N, k): a 1-D signal is one
channel, and results are per channel, always of shape (k,) (k = 1 for a 1-D signal).  Time averages use the
trapezoidal rule over time, so non-uniformly sampled records are weighted correctly.  Results are in the units
of the signal unless stated otherwise.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from bhgrasp._validation import as_array, as_positive, as_real, as_vector
from bhgrasp.errors import InputError

UNIFORM_SAMPLING_TOLERANCE = 1e-6  # relative spread of the sample intervals accepted as uniform sampling


@dataclass(frozen=True)
class TrackingError:
    """Per-channel error statistics of ``actual - desired``, each an array of shape (k,).

    Attributes:
        max_abs: Largest absolute error, in signal units.
        rms: Root mean square of the error, time-averaged with the trapezoidal rule, in signal units.
        max_percent: ``100 * max_abs / scale`` [%]; NaN (undefined) where the scale is 0.
        rms_percent: ``100 * rms / scale`` [%]; NaN (undefined) where the scale is 0.
        final_abs: Absolute error at the last sample, in signal units.
    """

    max_abs: np.ndarray
    rms: np.ndarray
    max_percent: np.ndarray
    rms_percent: np.ndarray
    final_abs: np.ndarray


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


def tracking_error(t: Any, actual: Any, desired: Any, scale: Any = None, start_time: float = 0.0) -> TrackingError:
    """Error statistics of ``actual - desired`` over the samples with ``t >= start_time``.

    Args:
        t: (N,) strictly increasing sample times [s].
        actual: (N,) or (N, k) measured signal.
        desired: Reference, the shape of ``actual`` or a scalar (constant set-point).
        scale: Reference magnitude for the percentages, scalar or (k,), > 0.  Default, per channel: the range
            (max - min) of ``desired`` over the whole run; where that is 0, ``|desired|`` at the last sample;
            where that is also 0 the percentages are NaN (undefined).
        start_time: Samples before this time [s] are ignored (e.g. an initial transient).

    Returns:
        The per-channel :class:`TrackingError`.

    Raises:
        InputError: On bad shapes, NaN/inf, non-increasing ``t``, a non-positive ``scale``, or fewer than 2
            samples at ``t >= start_time``.
    """
    t = _times(t)
    actual = _signal(actual, "actual", t.shape[0])
    desired = _reference(desired, "desired", actual.shape)
    if scale is None:
        span = desired.max(axis=0) - desired.min(axis=0)
        scale = np.where(span > 0.0, span, np.abs(desired[-1]))
    else:
        scale = _per_channel(scale, "scale", actual.shape[1], positive=True)
    return _tracking(t, actual - desired, scale, start_time)


def force_error(t: Any, force: Any, desired: Any, start_time: float = 0.0) -> TrackingError:
    """Error statistics of force-magnitude signals; :func:`tracking_error` with percentages of the set-point.

    Args:
        t: (N,) strictly increasing sample times [s].
        force: (N,) or (N, k) measured force magnitudes [N].
        desired: Desired force magnitudes [N], the shape of ``force`` or a scalar (constant set-point).
        start_time: Samples before this time [s] are ignored (e.g. the approach before contact).

    Returns:
        The per-channel :class:`TrackingError` [N]; percentages are of ``|desired|`` at the last sample (NaN where
        that is 0).

    Raises:
        InputError: As :func:`tracking_error`.
    """
    t = _times(t)
    force = _signal(force, "force", t.shape[0])
    desired = _reference(desired, "desired", force.shape)
    return _tracking(t, force - desired, np.abs(desired[-1]), start_time)


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
    t = _times(t)
    y = _signal(y, "y", t.shape[0])
    k = y.shape[1]
    target = _per_channel(target, "target", k)
    start = y[0].copy() if start is None else _per_channel(start, "start", k)
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


def control_effort(t: Any, u: Any) -> np.ndarray:
    """Root mean square of each input channel, time-averaged with the trapezoidal rule.

    Args:
        t: (N,) strictly increasing sample times [s].
        u: (N,) or (N, k) control inputs.

    Returns:
        (k,) RMS of each channel, in the units of ``u``.

    Raises:
        InputError: On bad shapes, NaN/inf or non-increasing ``t``.
    """
    t = _times(t)
    return np.sqrt(_time_average(t, _signal(u, "u", t.shape[0]) ** 2))


def chattering_index(t: Any, u: Any, start_time: float = 0.0) -> np.ndarray:
    """Total variation of each input channel per second, over the samples with ``t >= start_time``.

    ``sum |u[i+1] - u[i]| / (t_end - t_start)``.  A smooth signal of amplitude A and frequency f has index 4 A f
    (over whole periods); a bang-bang input switching sign between -K and K at every sample of period h has
    2 K / h.  Comparing the two tells chattering from legitimate motion.

    Args:
        t: (N,) strictly increasing sample times [s].
        u: (N,) or (N, k) control inputs.
        start_time: Samples before this time [s] are ignored.

    Returns:
        (k,) index of each channel, in units of ``u`` per second.

    Raises:
        InputError: On bad shapes, NaN/inf, non-increasing ``t``, or fewer than 2 samples at ``t >= start_time``.
    """
    t = _times(t)
    t, u = _window(t, start_time, _signal(u, "u", t.shape[0]))
    return np.abs(np.diff(u, axis=0)).sum(axis=0) / (t[-1] - t[0])


def high_frequency_power(t: Any, u: Any, cutoff: float, start_time: float = 0.0) -> np.ndarray:
    """Fraction of each channel's power (after removing its mean) at frequencies above ``cutoff``.

    The power spectral density is Welch's estimate (``scipy.signal.welch``, Hann window, ``nperseg =
    min(256, N)``), which needs uniformly sampled data.

    Args:
        t: (N,) strictly increasing, uniformly spaced (within 1e-6 relative) sample times [s].
        u: (N,) or (N, k) signal, e.g. control inputs.
        cutoff: Frequency [Hz], > 0 and below the Nyquist frequency ``1 / (2 h)``.
        start_time: Samples before this time [s] are ignored.

    Returns:
        (k,) fraction in [0, 1] of each channel; 0 for a constant channel.

    Raises:
        InputError: On bad shapes, NaN/inf, non-increasing or non-uniform ``t``, a ``cutoff`` outside
            (0, Nyquist), or fewer than 2 samples at ``t >= start_time``.
    """
    from scipy.signal import welch

    t = _times(t)
    t, u = _window(t, start_time, _signal(u, "u", t.shape[0]))
    cutoff = as_positive(cutoff, "cutoff")
    steps = np.diff(t)
    period = (t[-1] - t[0]) / (t.shape[0] - 1)
    spread = np.max(np.abs(steps - period)) / period
    if spread > UNIFORM_SAMPLING_TOLERANCE:
        raise InputError(
            f"`t` must be uniformly sampled (intervals within {UNIFORM_SAMPLING_TOLERANCE:g} relative), got "
            f"intervals from {steps.min():.6g} to {steps.max():.6g} s (relative spread {spread:.3g})"
        )
    if cutoff >= 0.5 / period:
        raise InputError(
            f"`cutoff` must be below the Nyquist frequency {0.5 / period:.6g} Hz (sample period {period:.6g} s), "
            f"got {cutoff!r} Hz"
        )
    centred = u - u.mean(axis=0)
    frequencies, density = welch(centred, fs=1.0 / period, nperseg=min(256, t.shape[0]), detrend=False, axis=0)
    total = density.sum(axis=0)
    high = density[frequencies > cutoff].sum(axis=0)
    constant = np.ptp(u, axis=0) == 0.0
    return np.where(constant | (total <= 0.0), 0.0, high / np.where(total > 0.0, total, 1.0))


def _tracking(t: np.ndarray, error: np.ndarray, scale: np.ndarray, start_time: float) -> TrackingError:
    t, error = _window(t, start_time, error)
    magnitude = np.abs(error)
    max_abs = magnitude.max(axis=0)
    rms = np.sqrt(_time_average(t, error**2))
    safe_scale = np.where(scale > 0.0, scale, np.nan)  # NaN percentages where the scale is 0 (undefined)
    return TrackingError(
        max_abs=max_abs,
        rms=rms,
        max_percent=100.0 * max_abs / safe_scale,
        rms_percent=100.0 * rms / safe_scale,
        final_abs=magnitude[-1],
    )


def _times(value: Any) -> np.ndarray:
    t = as_vector(value, "t")
    if t.shape[0] < 2:
        raise InputError(f"`t` must hold at least 2 sample times, got shape {t.shape}")
    steps = np.diff(t)
    if not np.all(steps > 0.0):
        i = int(np.flatnonzero(steps <= 0.0)[0])
        raise InputError(
            f"`t` must be strictly increasing, got t[{i}] = {float(t[i])!r} then t[{i + 1}] = {float(t[i + 1])!r}"
        )
    return t


def _signal(value: Any, name: str, n: int) -> np.ndarray:
    """Return a (n,) or (n, k) signal as a finite (n, k) float array."""
    shape = _numeric(value, name).shape
    if len(shape) not in (1, 2) or shape[0] != n or (len(shape) == 2 and shape[1] == 0):
        raise InputError(
            f"`{name}` must have shape ({n},) or ({n}, k) with k >= 1 (one row per sample of `t`), got shape {shape}"
        )
    array = as_array(value, name, (n,) if len(shape) == 1 else (n, None))
    return array.reshape(n, -1)


def _reference(value: Any, name: str, shape: tuple[int, int]) -> np.ndarray:
    """Return a reference signal of the given (n, k) shape; a scalar is a constant reference."""
    if _numeric(value, name).ndim == 0:
        return np.full(shape, as_real(value, name, nonnegative=False))
    array = _signal(value, name, shape[0])
    if array.shape[1] != shape[1]:
        raise InputError(
            f"`{name}` must have as many channels as the measured signal ({shape[1]}), got shape {np.shape(value)}"
        )
    return array


def _per_channel(value: Any, name: str, k: int, positive: bool = False) -> np.ndarray:
    """Return a scalar or (k,) parameter as a finite (k,) array (each > 0 if ``positive``)."""
    shape = _numeric(value, name).shape
    if shape == ():
        array = np.full(k, as_real(value, name, nonnegative=False))
    elif shape == (k,):
        array = as_vector(value, name, k)
    else:
        raise InputError(f"`{name}` must be a scalar or have shape ({k},) (one per channel), got shape {shape}")
    if positive and np.any(array <= 0.0):
        raise InputError(f"`{name}` must be > 0 on every channel, got {array}")
    return array


def _numeric(value: Any, name: str) -> np.ndarray:
    try:
        return np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError) as error:
        raise InputError(f"`{name}` must be numeric (a number or an array of numbers), got {value!r}") from error


def _rise_fractions(rise: Any) -> tuple[float, float]:
    if _numeric(rise, "rise").shape != (2,):
        raise InputError(f"`rise` must be a pair (lower, upper) of step fractions, got {rise!r}")
    lower, upper = as_vector(rise, "rise", 2)
    if not 0.0 <= lower < upper <= 1.0:
        raise InputError(f"`rise` must satisfy 0 <= lower < upper <= 1, got {rise!r}")
    return float(lower), float(upper)


def _window(t: np.ndarray, start_time: Any, signal: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Return the samples with ``t >= start_time`` (at least 2)."""
    start_time = as_real(start_time, "start_time", nonnegative=False)
    keep = t >= start_time
    count = int(np.count_nonzero(keep))
    if count < 2:
        raise InputError(
            f"`start_time` = {start_time!r} s leaves {count} sample(s) of `t` (which spans [{t[0]:.6g}, "
            f"{t[-1]:.6g}] s); at least 2 are needed"
        )
    return t[keep], signal[keep]


def _time_average(t: np.ndarray, values: np.ndarray) -> np.ndarray:
    """Trapezoidal time-average of each column of ``values`` over ``[t[0], t[-1]]``."""
    steps = np.diff(t)[:, None]
    return (0.5 * steps * (values[1:] + values[:-1])).sum(axis=0) / (t[-1] - t[0])


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


__all__ = [
    "StepResponse",
    "TrackingError",
    "chattering_index",
    "control_effort",
    "force_error",
    "high_frequency_power",
    "step_response",
    "tracking_error",
]
