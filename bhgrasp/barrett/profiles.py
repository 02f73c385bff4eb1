"""The pucks' rest-to-rest move profiles: a trapezoid in velocity, ACCEL-limited up to MV (in counts and ms)."""

from __future__ import annotations

import numpy as np


def trapezoid(distance: float, v_max: float, accel: float) -> tuple[float, float, float, float]:
    """A rest-to-rest profile over ``distance``: (signed distance, peak speed, ramp time, total time) [counts, ms]."""
    length = abs(distance)
    peak = min(v_max, np.sqrt(length * accel))
    ramp = peak / accel
    total = 2.0 * ramp + (length - peak * ramp) / peak if peak > 0 else 0.0
    return float(distance), float(peak), float(ramp), float(total)


def profile_at(profile: tuple[float, float, float, float], ms: float) -> tuple[float, float]:
    """(offset [counts], velocity [counts/ms]) of a :func:`trapezoid` at ``ms`` after its start."""
    distance, peak, ramp, total = profile
    sign, t = np.sign(distance), min(ms, total)
    if total == 0.0:
        return distance, 0.0
    accel = peak / ramp
    if t < ramp:
        offset, speed = 0.5 * accel * t**2, accel * t
    elif t <= total - ramp:
        offset, speed = 0.5 * peak * ramp + peak * (t - ramp), peak
    else:
        left = total - t
        offset, speed = abs(distance) - 0.5 * accel * left**2, accel * left
    return float(sign * offset), float(sign * speed)


__all__ = ["profile_at", "trapezoid"]
