"""Chapter 4's report rows of force responses: :func:`force_row` under :data:`FORCE_HEADER`.

The metrics are :func:`~bhgrasp.scenarios.finger_press.force_metrics`'s.
"""

from __future__ import annotations

import numpy as np

from bhgrasp.scenarios.finger_press import ForceMetrics


def force_row(name: str, m: ForceMetrics, extra: list[str] | None = None) -> list[str]:
    """One row of a force table: ``name``, the metrics ``m`` under :data:`FORCE_HEADER`, then ``extra`` cells."""
    return [
        name,
        f"{m.contact_time:.2f}",
        f"{m.impact:.2f}",
        f"{m.peak:.2f}",
        f"{m.final:.3f}",
        _fmt(m.overshoot, ".1f"),
        f"{m.settling:.3f}",
        "-" if np.isnan(m.error) else f"{m.error:.3f}",
        *(extra or []),
    ]


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


__all__ = ["FORCE_HEADER", "force_row"]
