"""Boundary validation: one idiom for every public entry point (shape, dtype, finiteness, names)."""

from __future__ import annotations

import math
from collections.abc import Iterable
from typing import Any

import numpy as np

from bhgrasp.errors import InputError


def finite_vector(vector: np.ndarray) -> bool:
    """Whether a float 1-D array holds no NaN/inf: its sum, a cheap test per call (an overflow: the full test)."""
    return math.isfinite(sum(vector.tolist())) or bool(np.isfinite(vector).all())


def as_vector(value: Any, name: str, size: int | None = None) -> np.ndarray:
    """Return ``value`` as a finite float64 1-D array, optionally of a given length.

    Args:
        value: Array-like input.
        name: Argument name used in error messages.
        size: Required length, or ``None`` for any length.

    Raises:
        InputError: If the input is not numeric, not 1-D, has the wrong length, or holds NaN/inf.
    """
    if type(value) is np.ndarray and value.dtype == np.float64 and value.ndim == 1 and value.shape[0] == size:
        if finite_vector(value):
            return value
    try:
        array = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError) as error:
        raise InputError(f"`{name}` must be a numeric array, got {value!r}") from error
    if array.ndim != 1 or (size is not None and array.shape[0] != size):
        expected = f"({size},)" if size is not None else "a 1-D array"
        raise InputError(f"`{name}` must have shape {expected}, got shape {array.shape}")
    _require_finite(array, name)
    return array


def as_array(value: Any, name: str, shape: tuple[int | None, ...]) -> np.ndarray:
    """Return ``value`` as a finite float64 array whose shape matches ``shape`` (``None`` = any length)."""
    if (
        type(value) is np.ndarray
        and value.dtype == np.float64
        and value.ndim == len(shape)
        and all(s is None or s == a for s, a in zip(shape, value.shape))
    ):
        flat = value.reshape(-1)
        if math.isfinite(np.dot(flat, flat)):  # fast path: a NaN/inf makes the dot non-finite (so does an overflow,
            # which takes the full check); for arrays of any size a BLAS dot beats as_vector's list sum
            return value
    try:
        array = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError) as error:
        raise InputError(f"`{name}` must be a numeric array, got {value!r}") from error
    if array.ndim != len(shape) or any(s is not None and s != a for s, a in zip(shape, array.shape)):
        expected = "(" + ", ".join("n" if s is None else str(s) for s in shape) + ")"
        raise InputError(f"`{name}` must have shape {expected}, got shape {array.shape}")
    _require_finite(array, name)
    return array


def as_positive(value: Any, name: str) -> float:
    """Return ``value`` as a finite float > 0."""
    try:
        number = float(value)
    except (TypeError, ValueError) as error:
        raise InputError(f"`{name}` must be a positive number, got {value!r}") from error
    if not np.isfinite(number) or number <= 0.0:
        raise InputError(f"`{name}` must be a positive finite number, got {number!r}")
    return number


def as_int(value: Any, name: str, minimum: int) -> int:
    """``value`` as an int >= ``minimum`` (bools and non-integral numbers are rejected)."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)) or value < minimum:
        raise InputError(f"`{name}` must be an int >= {minimum}, got {value!r}")
    return int(value)


def as_rates(value: Any, name: str, count: int) -> tuple[float, ...]:
    """``value`` (one number, or one per item) as ``count`` finite floats >= 0."""
    if np.ndim(value) == 0:
        return (as_real(value, name),) * count
    rates = tuple(as_real(rate, f"{name}[{i}]") for i, rate in enumerate(value))
    if len(rates) != count:
        raise InputError(f"`{name}` must hold one rate per item ({count}), got {len(rates)}")
    return rates


def as_real(value: Any, name: str, nonnegative: bool = True) -> float:
    """Return ``value`` as a finite float (>= 0 unless ``nonnegative`` is false)."""
    expected = "a finite number >= 0" if nonnegative else "a finite number"
    try:
        number = float(value)
    except (TypeError, ValueError) as error:
        raise InputError(f"`{name}` must be {expected}, got {value!r}") from error
    if not math.isfinite(number) or (nonnegative and number < 0.0):
        raise InputError(f"`{name}` must be {expected}, got {number!r}")
    return number


def require_name(name: str, valid: Iterable[str], what: str) -> str:
    """Return ``name`` if it is one of ``valid``, else raise an error listing the valid names."""
    valid = list(valid)
    if name not in valid:
        raise InputError(f"unknown {what} {name!r}; valid {what}s: {', '.join(valid)}")
    return name


def _require_finite(array: np.ndarray, name: str) -> None:
    if not np.all(np.isfinite(array)):
        bad = np.flatnonzero(~np.isfinite(array.ravel()))
        raise InputError(
            f"`{name}` must be finite, got NaN/inf at flat index {bad.tolist()[:5]}: {array.ravel()[bad][:5]}"
        )


ROTATION_TOLERANCE = 1e-9  # on R^T R - I and det R - 1; pin.rpy / quaternion / product rotations are ~1e-15


def require_rotation(rotation: np.ndarray, name: str) -> None:
    """Refuse a ``rotation`` that is not a rotation matrix (orthonormal, det +1, within ROTATION_TOLERANCE)."""
    rotation = np.asarray(rotation, dtype=float)
    error = float(np.max(np.abs(rotation.T @ rotation - np.eye(3))))
    determinant = float(np.linalg.det(rotation))
    if not (error <= ROTATION_TOLERANCE and abs(determinant - 1.0) <= ROTATION_TOLERANCE):
        raise InputError(
            f"`{name}` must have a rotation matrix as its rotation (orthonormal, det +1, within "
            f"{ROTATION_TOLERANCE:g}), got max |R^T R - I| = {error:.3g}, det R = {determinant:.6g}: "
            f"R = {np.round(rotation, 6).tolist()}"
        )


def as_unit(value: Any, name: str) -> np.ndarray:
    """``value`` as a unit 3-vector (normalised); a zero vector is refused."""
    vector = as_vector(value, name, 3)
    norm = float(np.linalg.norm(vector))
    if norm < 1e-12:
        raise InputError(f"`{name}` must be a non-zero 3-vector, got {vector.tolist()}")
    return vector / norm


def as_generator(rng: Any, name: str = "rng") -> np.random.Generator:
    """``rng`` if it is a numpy Generator, else a new one seeded with the integer ``rng``."""
    if isinstance(rng, np.random.Generator):
        return rng
    if isinstance(rng, (int, np.integer)) and not isinstance(rng, bool):
        return np.random.default_rng(int(rng))
    raise InputError(f"`{name}` must be a numpy.random.Generator or an integer seed, got {rng!r}")
