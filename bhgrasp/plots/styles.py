"""Figure styles shared by :mod:`bhgrasp.plots`.

A Figure that shows itself in Jupyter, traces and point clouds that stay visible where they coincide, legends beside
the axes, readable log axes.
"""

from __future__ import annotations

import io
from typing import Any

import matplotlib.figure
import numpy as np
from matplotlib import ticker

from bhgrasp.errors import InputError


class Figure(matplotlib.figure.Figure):
    """A matplotlib figure that Jupyter shows as a PNG by itself (``_repr_png_``), whatever the backend."""

    def _repr_png_(self) -> bytes:
        """The figure as PNG bytes at 100 dpi (what IPython's display calls)."""
        buffer = io.BytesIO()
        self.savefig(buffer, format="png", dpi=100)
        return buffer.getvalue()


DASHES: tuple[Any, ...] = (
    (0, (5.0, 1.5)),
    (0, (5.0, 1.5, 1.5, 1.5)),
    (0, (1.5, 1.0)),
    (0, (3.0, 1.0, 1.0, 1.0, 1.0, 1.0)),
    (0, (8.0, 2.0)),
)
"""On-off patterns [in line widths] of the traces after the first (:func:`trace_styles`), cycled."""


def trace_styles(count: int) -> list[dict[str, Any]]:
    """Line styles for ``count`` traces drawn in this order on one axes that stay visible where the traces coincide.

    The first trace is solid and the widest, each later one thinner, dashed (its own on-off pattern, cycled
    through :data:`DASHES`) and drawn above the earlier ones: a trace equal to an earlier one shows that one as a
    rim around it and through its gaps.  One trace alone is a plain solid line.  Pass each dict to ``Axes.plot``
    as keyword arguments (``linewidth``, ``linestyle``, ``zorder``); colours stay the axes' cycle.

    Example: ``for style, (name, y) in zip(trace_styles(len(runs)), runs.items()): axis.plot(t, y, label=name,
    **style)``.
    """
    if count < 0:
        raise InputError(f"`count` must be >= 0, got {count}")
    if count == 1:
        return [{"linewidth": 1.2, "linestyle": "-", "zorder": 2.0}]
    widths = np.linspace(min(2.8, 1.0 + 1.6 * (count - 1)), 0.9, count)
    return [
        {
            "linewidth": round(float(width), 3),
            "linestyle": "-" if k == 0 else DASHES[(k - 1) % len(DASHES)],
            "zorder": 2.0 + 0.01 * k,
        }
        for k, width in enumerate(widths)
    ]


POINT_STYLES: tuple[dict[str, Any], ...] = (
    {"marker": "o", "s": 9.0, "linewidths": 0.5, "alpha": 0.6, "hollow": True},
    {"marker": "o", "s": 2.0, "linewidths": 0.0, "alpha": 0.7},
    {"marker": "+", "s": 5.0, "linewidths": 0.4, "alpha": 0.3},
    {"marker": "x", "s": 4.0, "linewidths": 0.5, "alpha": 0.6},
    {"marker": "s", "s": 7.0, "linewidths": 0.5, "alpha": 0.6, "hollow": True},
)
"""Scatter styles of :func:`scatter_traces` in drawing order: rings, dots (inside rings), pluses, crosses, squares."""


def scatter_traces(axis, clouds: dict[str, tuple[np.ndarray, np.ndarray]], colours: dict[str, Any] | None = None):
    """Scatter point clouds that may overlap so that each stays visible (the point analogue of :func:`trace_styles`).

    The first cloud is drawn as hollow rings, the second as filled dots on top (a dot inside a ring: both show, even
    where the clouds share their points), later ones as pluses, crosses and squares (:data:`POINT_STYLES`).
    ``clouds``: label -> (x, y); ``colours``: label -> colour (default: the colour cycle, C0, C1, ...).  Returns
    the collections.
    """
    collections = []
    for k, (label, (x, y)) in enumerate(clouds.items()):
        style = dict(POINT_STYLES[k % len(POINT_STYLES)])
        colour = (colours or {}).get(label, f"C{k}")
        colour_keys = {"facecolors": "none", "edgecolors": colour} if style.pop("hollow", False) else {"color": colour}
        collections.append(axis.scatter(x, y, label=label, zorder=1.0 + 0.01 * k, **colour_keys, **style))
    return collections


def legend_beside(axis, *args: Any, **kwargs: Any):
    """The axes' legend outside it, on the right (over no trace); ``args``/``kwargs`` as ``Axes.legend``."""
    kwargs = {"fontsize": 7, "loc": "upper left", "bbox_to_anchor": (1.01, 1.0), "borderaxespad": 0.0, **kwargs}
    return axis.legend(*args, **kwargs)


class DecimalLogLocator(ticker.LogLocator):
    """Log-axis ticks at round decimals, at least four in view where it can.

    The decades; else 1, 2, 5 x 10^k; and on a view narrower than a decade every digit, else every half digit, else
    every tenth, so a view inside one decade still gets labels.
    """

    MANTISSAS = (
        (1.0,),
        (1.0, 2.0, 5.0),
        tuple(range(1, 10)),
        tuple(np.arange(1.0, 10.0, 0.5)),
        tuple(np.arange(1.0, 10.0, 0.1)),
    )
    MIN_TICKS = 4

    def tick_values(self, vmin: float, vmax: float) -> np.ndarray:
        """The ticks within [vmin, vmax] (decades thinned to at most 10 on a wide axis)."""
        low, high = sorted((float(vmin), float(vmax)))
        if not (high > 0.0 and np.isfinite(high)):
            return np.array([])
        low = max(low, high * 1e-300)
        exponents = np.arange(np.floor(np.log10(low)), np.floor(np.log10(high)) + 1.0)
        if len(exponents) > 10:
            exponents = exponents[:: int(np.ceil(len(exponents) / 10))]
        choices = self.MANTISSAS if high < 10.0 * low else self.MANTISSAS[:2]  # finer only inside a decade
        for mantissas in choices:
            ticks = np.array([m * 10.0**e for e in exponents for m in mantissas])
            inside = ticks[(ticks >= low * (1 - 1e-9)) & (ticks <= high * (1 + 1e-9))]
            if len(inside) >= self.MIN_TICKS:
                break
        return inside if len(inside) >= 2 else super().tick_values(vmin, vmax)  # a sliver of a decade: matplotlib's


def readable_log_axis(axis) -> None:
    """Enough plain decimal labels ("0.09", "0.095", "0.1") on a log axis (``axis``: e.g. ``ax.yaxis``).

    Matplotlib labels a log axis spanning less than a decade with one or two ticks; :class:`DecimalLogLocator`
    puts at least four labelled ticks in view; unlabelled minor ticks at every digit stay.
    """
    axis.set_major_locator(DecimalLogLocator())
    axis.set_major_formatter(ticker.FuncFormatter(lambda value, _position: f"{value:g}"))
    axis.set_minor_locator(ticker.LogLocator(subs=np.arange(2.0, 10.0)))
    axis.set_minor_formatter(ticker.NullFormatter())


__all__ = [
    "DASHES",
    "POINT_STYLES",
    "DecimalLogLocator",
    "Figure",
    "legend_beside",
    "readable_log_axis",
    "scatter_traces",
    "trace_styles",
]
