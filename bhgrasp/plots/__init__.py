"""Matplotlib figures of runs: joint tracking, errors and torques, contact forces, object pose errors, cone margins.

Figures are :class:`Figure`, a :class:`matplotlib.figure.Figure` that renders itself as a PNG for Jupyter (no pyplot
state, no backend change): they work headless, show in any notebook with ``display(figure)`` or as a cell's last
value without ``%matplotlib inline``, and save with ``figure.savefig``.
"""

from bhgrasp.plots.joint import case_figures, save_case_figures, tracking_figure
from bhgrasp.plots.runs import (
    cone_margin_figure,
    force_case_figure,
    force_figure,
    grasp_figure,
    log_figure,
    object_error_figure,
    save_force_figure,
    workspace_figure,
)
from bhgrasp.plots.styles import (
    DASHES,
    POINT_STYLES,
    DecimalLogLocator,
    Figure,
    legend_beside,
    readable_log_axis,
    scatter_traces,
    trace_styles,
)

__all__ = [
    "DASHES",
    "POINT_STYLES",
    "DecimalLogLocator",
    "Figure",
    "case_figures",
    "cone_margin_figure",
    "force_case_figure",
    "force_figure",
    "grasp_figure",
    "legend_beside",
    "log_figure",
    "object_error_figure",
    "readable_log_axis",
    "save_case_figures",
    "save_force_figure",
    "scatter_traces",
    "trace_styles",
    "tracking_figure",
    "workspace_figure",
]
