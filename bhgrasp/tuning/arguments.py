"""The arguments of :func:`~bhgrasp.tuning.cma.cma_es`, checked: start point, integers, bounds, objective, executor."""

from __future__ import annotations

import pickle
from typing import Any

import numpy as np

from bhgrasp._validation import as_vector
from bhgrasp.errors import InputError


def as_start(x0: Any) -> np.ndarray:
    """``x0`` as a finite (n,) array, n >= 1."""
    x0 = as_vector(x0, "x0")
    if x0.size == 0:
        raise InputError("`x0` must hold at least 1 parameter, got shape (0,)")
    return x0.copy()


def as_bounds(bounds: Any, x0: np.ndarray) -> tuple[np.ndarray | None, np.ndarray | None]:
    """``(lower, upper)`` as (n,) arrays with ``lower < upper`` and ``lower <= x0 <= upper``, or ``(None, None)``."""
    if bounds is None:
        return None, None
    try:
        lower, upper = bounds
        lower, upper = (np.broadcast_to(np.asarray(b, dtype=np.float64), x0.shape).copy() for b in (lower, upper))
    except (TypeError, ValueError) as error:
        raise InputError(f"`bounds` must be (lower, upper), each a number or of shape {x0.shape}") from error
    if np.any(np.isnan(lower) | np.isnan(upper)):
        raise InputError(f"`bounds` must not hold NaN, got lower {lower}, upper {upper}")
    if np.any(lower >= upper):
        raise InputError(f"`bounds` need lower < upper, got lower {lower}, upper {upper}")
    if np.any((x0 < lower) | (x0 > upper)):
        raise InputError(f"`x0` = {x0} must lie within `bounds`, lower {lower}, upper {upper}")
    return lower, upper


def check_objective_and_executor(objective: Any, executor: Any) -> None:
    """Require a callable objective, a valid executor, and a picklable objective for the default process pool."""
    if not callable(objective):
        raise InputError(f"`objective` must be callable, got {objective!r}")
    if isinstance(executor, str) and executor != "serial":
        raise InputError(f"`executor` must be None, 'serial' or a concurrent.futures.Executor, got {executor!r}")
    if executor is not None and not isinstance(executor, str) and not callable(getattr(executor, "submit", None)):
        raise InputError(f"`executor` must have a submit() method like concurrent.futures.Executor, got {executor!r}")
    if executor is None:
        try:
            pickle.dumps(objective)
        except Exception as error:
            raise InputError(
                "`objective` must be picklable to run in a process pool (a top-level function or a "
                f"functools.partial of one), got {objective!r}; or pass executor='serial'"
            ) from error


__all__ = ["as_bounds", "as_start", "check_objective_and_executor"]
