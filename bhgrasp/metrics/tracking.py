"""Tracking and force error of a run: mean, RMS, maximum and final error per channel."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from bhgrasp.metrics.signals import as_reference, as_signal, per_channel, sample_times, time_average, window


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
    t = sample_times(t)
    actual = as_signal(actual, "actual", t.shape[0])
    desired = as_reference(desired, "desired", actual.shape)
    if scale is None:
        span = desired.max(axis=0) - desired.min(axis=0)
        scale = np.where(span > 0.0, span, np.abs(desired[-1]))
    else:
        scale = per_channel(scale, "scale", actual.shape[1], positive=True)
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
    t = sample_times(t)
    force = as_signal(force, "force", t.shape[0])
    desired = as_reference(desired, "desired", force.shape)
    return _tracking(t, force - desired, np.abs(desired[-1]), start_time)


def _tracking(t: np.ndarray, error: np.ndarray, scale: np.ndarray, start_time: float) -> TrackingError:
    t, error = window(t, start_time, error)
    magnitude = np.abs(error)
    max_abs = magnitude.max(axis=0)
    rms = np.sqrt(time_average(t, error**2))
    safe_scale = np.where(scale > 0.0, scale, np.nan)  # NaN percentages where the scale is 0 (undefined)
    return TrackingError(
        max_abs=max_abs,
        rms=rms,
        max_percent=100.0 * max_abs / safe_scale,
        rms_percent=100.0 * rms / safe_scale,
        final_abs=magnitude[-1],
    )


__all__ = ["TrackingError", "force_error", "tracking_error"]
