"""Chapter 4's force response metrics, from the first contact on, and the report rows that show them.

:func:`force_metrics` reads contact time, impact, peak, final force, overshoot, 2 % settling and steady-state error
from a run's normal force; ``_row`` formats them as a row of the report's tables under :data:`FORCE_HEADER`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bhgrasp import metrics

IMPACT_WINDOW = 0.02  # [s] after first contact: the impact transient, reported apart from the pushing peak


@dataclass(frozen=True)
class ForceMetrics:
    """Force response after first contact.

    Attributes: contact_time [s], impact (largest force in the first IMPACT_WINDOW after contact, before any
    controller can react) [N], peak (largest force after it) [N], final [N], overshoot [%], settling (2 %, after
    contact) [s], error (steady state, % of f_d).
    """

    contact_time: float
    impact: float
    peak: float
    final: float
    overshoot: float
    settling: float
    error: float


def force_metrics(t: np.ndarray, force: np.ndarray, desired: float | None = None) -> ForceMetrics:
    """Metrics of a force response; ``desired`` None uses the final force as the target (PIM, uncontrolled)."""
    touching = np.flatnonzero(force > 1e-6)
    if len(touching) == 0:
        return ForceMetrics(np.nan, 0.0, 0.0, 0.0, np.nan, np.nan, np.nan)
    k0 = touching[0]
    window = t < t[k0] + IMPACT_WINDOW
    impact = float(force[window].max())
    peak = float(force[~window].max()) if np.any(~window) else 0.0
    final = float(np.mean(force[-max(2, len(force) // 20) :]))
    target = final if desired is None else desired
    response = metrics.step_response(t[k0:], force[k0:], target, start=0.0)
    error = np.nan if desired is None else 100.0 * abs(final - desired) / desired
    overshoot = np.nan if desired is None else 100.0 * max(0.0, peak - desired) / desired  # after the impact
    return ForceMetrics(float(t[k0]), impact, peak, final, overshoot, float(response.settling_time[0]), error)


def _row(name: str, m: ForceMetrics, extra: list[str] | None = None) -> list[str]:
    return [
        name, f"{m.contact_time:.2f}", f"{m.impact:.2f}", f"{m.peak:.2f}", f"{m.final:.3f}", _fmt(m.overshoot, ".1f"),
        f"{m.settling:.3f}", "-" if np.isnan(m.error) else f"{m.error:.3f}", *(extra or []),
    ]  # fmt: skip


def _fmt(value: float, spec: str) -> str:
    return "-" if np.isnan(value) else format(value, spec)


FORCE_HEADER = [
    "run",
    "contact [s]",
    "impact [N]",
    "peak [N]",
    "final [N]",
    "overshoot %",
    "settling [s]",
    "ss error %",
]


__all__ = ["FORCE_HEADER", "IMPACT_WINDOW", "ForceMetrics", "force_metrics"]
