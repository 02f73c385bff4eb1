"""Control effort of a run: its mean squared input, chattering index and high-frequency power per channel."""

from __future__ import annotations

from typing import Any

import numpy as np

from bhgrasp._validation import as_positive
from bhgrasp.errors import InputError
from bhgrasp.metrics.signals import UNIFORM_SAMPLING_TOLERANCE, as_signal, sample_times, time_average, window


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
    t = sample_times(t)
    return np.sqrt(time_average(t, as_signal(u, "u", t.shape[0]) ** 2))


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
    t = sample_times(t)
    t, u = window(t, start_time, as_signal(u, "u", t.shape[0]))
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

    t = sample_times(t)
    t, u = window(t, start_time, as_signal(u, "u", t.shape[0]))
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


__all__ = ["chattering_index", "control_effort", "high_frequency_power"]
