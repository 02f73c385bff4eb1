"""The signals the metrics read, checked: sample times, per-channel arrays and references, time windows and averages."""

from __future__ import annotations

from typing import Any

import numpy as np

from bhgrasp._validation import as_array, as_real, as_vector
from bhgrasp.errors import InputError

UNIFORM_SAMPLING_TOLERANCE = 1e-6  # relative spread of the sample intervals accepted as uniform sampling


def sample_times(value: Any) -> np.ndarray:
    """``value`` as sample times [s]: at least two, finite, strictly increasing."""
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


def as_signal(value: Any, name: str, n: int) -> np.ndarray:
    """Return a (n,) or (n, k) signal as a finite (n, k) float array."""
    shape = as_numeric(value, name).shape
    if len(shape) not in (1, 2) or shape[0] != n or (len(shape) == 2 and shape[1] == 0):
        raise InputError(
            f"`{name}` must have shape ({n},) or ({n}, k) with k >= 1 (one row per sample of `t`), got shape {shape}"
        )
    array = as_array(value, name, (n,) if len(shape) == 1 else (n, None))
    return array.reshape(n, -1)


def as_reference(value: Any, name: str, shape: tuple[int, int]) -> np.ndarray:
    """Return a reference signal of the given (n, k) shape; a scalar is a constant reference."""
    if as_numeric(value, name).ndim == 0:
        return np.full(shape, as_real(value, name, nonnegative=False))
    array = as_signal(value, name, shape[0])
    if array.shape[1] != shape[1]:
        raise InputError(
            f"`{name}` must have as many channels as the measured signal ({shape[1]}), got shape {np.shape(value)}"
        )
    return array


def per_channel(value: Any, name: str, k: int, positive: bool = False) -> np.ndarray:
    """Return a scalar or (k,) parameter as a finite (k,) array (each > 0 if ``positive``)."""
    shape = as_numeric(value, name).shape
    if shape == ():
        array = np.full(k, as_real(value, name, nonnegative=False))
    elif shape == (k,):
        array = as_vector(value, name, k)
    else:
        raise InputError(f"`{name}` must be a scalar or have shape ({k},) (one per channel), got shape {shape}")
    if positive and np.any(array <= 0.0):
        raise InputError(f"`{name}` must be > 0 on every channel, got {array}")
    return array


def as_numeric(value: Any, name: str) -> np.ndarray:
    """``value`` as a float64 array, or an InputError naming ``name``."""
    try:
        return np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError) as error:
        raise InputError(f"`{name}` must be numeric (a number or an array of numbers), got {value!r}") from error


def window(t: np.ndarray, start_time: Any, signal: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
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


def time_average(t: np.ndarray, values: np.ndarray) -> np.ndarray:
    """Trapezoidal time-average of each column of ``values`` over ``[t[0], t[-1]]``."""
    steps = np.diff(t)[:, None]
    return (0.5 * steps * (values[1:] + values[:-1])).sum(axis=0) / (t[-1] - t[0])


__all__ = [
    "UNIFORM_SAMPLING_TOLERANCE",
    "as_numeric",
    "as_reference",
    "as_signal",
    "per_channel",
    "sample_times",
    "time_average",
    "window",
]
