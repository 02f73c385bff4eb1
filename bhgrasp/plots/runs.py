"""Figures of contact and grasping runs.

Contact forces, controller logs, object pose errors, the grasp, cone margins, and the fingertips' workspace.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from bhgrasp.data import Trajectory
from bhgrasp.errors import InputError
from bhgrasp.plots.styles import (
    Figure,
    legend_beside,
    readable_log_axis,
    scatter_traces,
    trace_styles,
)


def force_figure(traces: dict[str, tuple[np.ndarray, np.ndarray, float | None]], title: str = "") -> Figure:
    """Contact force [N] against time [s] of several runs; a dashed line marks each run's desired force.

    Runs whose forces coincide stay visible (:func:`trace_styles`); the legend sits beside the axes.
    """
    if not traces:
        raise InputError("`traces` must hold at least one (t, force, desired) entry")
    figure = Figure(figsize=(10, 4.5), layout="tight")
    ax = figure.subplots()
    for style, (name, (t, force, desired)) in zip(trace_styles(len(traces)), traces.items()):
        (line,) = ax.plot(t, force, label=name, **style)
        if desired is not None:
            ax.axhline(desired, ls="--", lw=0.7, color=line.get_color())
    ax.set(xlabel="t [s]", ylabel="normal contact force [N]", title=title)
    ax.grid(alpha=0.3)
    legend_beside(ax)
    return figure


def force_case_figure(case: Any) -> Figure:
    """The figure of a force-control case's traces (``case.traces``, ``case.title``, ``case.key``).

    The tuning case plots each CMA-ES run's best fitness per generation on a log axis with decimal tick labels.
    """
    figure = force_figure(case.traces, case.title)
    if case.key == "tuning":
        axis = figure.axes[0]
        axis.set(xlabel="generation", ylabel="best fitness: mean |f_d - f| [N]", yscale="log")
        readable_log_axis(axis.yaxis)
        axis.grid(True, which="minor", alpha=0.15)
    return figure


def save_force_figure(case: Any, path: Path) -> Path:
    """PNG of a force-control case's traces (:func:`force_case_figure`)."""
    path = Path(path)
    force_case_figure(case).savefig(path, dpi=90)
    return path


def log_figure(
    runs: dict[str, Trajectory], key: str, channels: Sequence[int], labels: Sequence[str], ylabel: str, title: str = ""
) -> Figure:
    """Any logged controller internal against time, one panel per channel, one line per run.

    For example the sliding variables ``s`` of the sliding-mode family, the parameter estimates ``theta`` of the
    adaptive laws (channels = parameter indices), ``mass_estimate`` or ``object_parameters`` of the grasp laws.
    Samples where the run did not log ``key`` (NaN) are left blank.
    """
    if not runs:
        raise InputError("`runs` must hold at least one trajectory")
    if len(channels) != len(labels) or not channels:
        raise InputError(f"`channels` and `labels` must be non-empty and of equal length, got {channels}, {labels}")
    figure = Figure(figsize=(11, 2.6 * len(channels)), layout="tight")
    axes = figure.subplots(len(channels), 1, squeeze=False, sharex=True)[:, 0]
    for style, (name, traj) in zip(trace_styles(len(runs)), runs.items()):
        if key not in traj.log:
            raise InputError(f"run {name!r} has no logged {key!r}; it logs {sorted(traj.log)}")
        values = traj.log[key].reshape(len(traj), -1)
        for axis, channel in zip(axes, channels):
            axis.plot(traj.t, values[:, channel], label=name, **style)
    _finish_time_panels(axes, [f"{label} {ylabel}" for label in labels], title)
    return figure


def _finish_time_panels(axes, ylabels: Sequence[str], title: str) -> None:
    """Y labels, grid and legend on stacked time panels; the title on top, the time axis below."""
    for axis, ylabel in zip(axes, ylabels):
        axis.set(ylabel=ylabel)
        axis.grid(alpha=0.3)
        axis.legend(fontsize=7)
    axes[0].set_title(title)
    axes[-1].set_xlabel("t [s]")


def _grasping(traj: Trajectory) -> np.ndarray:
    """Samples where a grasp controller ran (its ``object_error`` is logged and finite)."""
    if "object_error" not in traj.log:
        raise InputError("the run has no logged `object_error` (use an object-space grasp controller)")
    return np.all(np.isfinite(traj.log["object_error"]), axis=1)


def object_error_figure(runs: dict[str, Trajectory], channels: Sequence[int] = (2, 3), title: str = "") -> Figure:
    """Object pose error against time for several runs, one panel per channel.

    Channels 0-2 are the position [mm], 3-5 the rotation vector [mrad] (world) of ``log["object_error"]``.
    """
    if not runs:
        raise InputError("`runs` must hold at least one trajectory")
    names = ("x", "y", "z", "rotation about x", "rotation about y", "rotation about z")
    figure = Figure(figsize=(11, 3.2 * len(channels)), layout="tight")
    axes = figure.subplots(len(channels), 1, squeeze=False, sharex=True)[:, 0]
    for style, (name, traj) in zip(trace_styles(len(runs)), runs.items()):
        mask = _grasping(traj)
        for axis, channel in zip(axes, channels):
            axis.plot(traj.t[mask], 1e3 * traj.log["object_error"][mask, channel], label=name, **style)
    ylabels = [f"{names[channel]} error [{'mm' if channel < 3 else 'mrad'}]" for channel in channels]
    _finish_time_panels(axes, ylabels, title)
    return figure


def grasp_figure(
    traj: Trajectory,
    finger_names: Sequence[str],
    measured_normal: np.ndarray,
    true_mass=None,
    grasp_time: float | None = None,
    motion: tuple[float, float] | None = None,
) -> Figure:
    """One grasp run from the grasp on: object pose error, measured vs. commanded normal forces, mass or margin.

    Traces that coincide stay visible (:func:`trace_styles`): each finger's measured force is drawn thinner and
    dashed above the previous finger's, so equal forces nest (F1 shows around and through F2), and the commanded
    forces, dotted, above them; the same for the pose error's axes.  Legends sit beside the panels, not over the
    traces.

    Args:
        traj: The run (logs ``object_error``, ``commanded_normal``).
        finger_names: The hand's fingers, in the order of ``commanded_normal``.
        measured_normal: (N, n_fingers) measured normal forces [N] (see ``bhgrasp.grasp.metrics.finger_normal_forces``).
        true_mass: Drawn beside the mass estimate [kg].
        grasp_time: When the grasp closed [s] (marked; the panels start there).
        motion: (start, end) of the object motion [s] (shaded).
    """
    grasping = _grasping(traj)
    t = traj.t[grasping]
    figure = Figure(figsize=(13, 7), layout="tight")
    axes = figure.subplots(2, 2, sharex=True).ravel()
    error = traj.log["object_error"][grasping]
    for k, (axis, style) in enumerate(zip("xyz", trace_styles(3))):
        axes[0].plot(t, 1e3 * error[:, k], label=axis, **style)
        axes[1].plot(t, 1e3 * error[:, 3 + k], label=f"about {axis}", **style)
    axes[0].set(ylabel="object position error [mm]", title="object pose error (world, COM)")
    axes[1].set(ylabel="object rotation error [mrad]")
    measured, commanded = measured_normal[grasping], traj.log["commanded_normal"][grasping]
    for k, (finger, style) in enumerate(zip(finger_names, trace_styles(len(finger_names)))):
        line = axes[2].plot(t, measured[:, k], label=f"{finger} measured", **style)[0]
        axes[2].plot(
            t,
            commanded[:, k],
            ":",
            lw=max(style["linewidth"] / 2, 0.8),
            zorder=3.0 + 0.01 * k,
            color="k" if k == 0 else line.get_color(),
            label=f"{finger} commanded",
        )
    axes[2].set(xlabel="t [s]", ylabel="normal force [N]", title="contact forces")
    if "mass_estimate" in traj.log:
        axes[3].plot(t, np.ravel(traj.log["mass_estimate"][grasping]), label="estimate")
        if true_mass is not None:
            axes[3].axhline(true_mass, color="k", linestyle=":", label="true mass")
        axes[3].set(ylabel="object mass [kg]", title="mass estimate")
    else:
        axes[3].plot(t, traj.log["cone_margin"][grasping], label="cone margin")
        axes[3].set(ylabel="cone margin [N]", title="commanded forces: mu f_n - |f_t|")
    axes[3].set(xlabel="t [s]")
    for axis in axes:
        if motion is not None:
            axis.axvspan(*motion, color="0.85", zorder=0, label="object motion")
        if grasp_time is not None:
            axis.axvline(grasp_time, color="k", lw=0.8, label="grasp closed")
        axis.grid(True, alpha=0.3)
        legend_beside(axis)
    start = f"{t[0]:.2f} s" if len(t) else "-"
    figure.suptitle(f"from the grasp on (t >= {start}; before it the fingers approach the object)", fontsize=9)
    return figure


def cone_margin_figure(runs: dict[str, Trajectory], title: str = "") -> Figure:
    """Cone margin mu f_n - |f_t| [N] of the commanded forces (negative: outside the assumed cone) of several runs.

    A linear axis; runs that coincide (e.g. the QP and G^+ forces until a cone binds) stay visible
    (:func:`trace_styles`); the zero line (the cone's boundary) lies behind them.
    """
    if not runs:
        raise InputError("`runs` must hold at least one trajectory")
    figure = Figure(figsize=(10, 4), layout="tight")
    axis = figure.subplots()
    for style, (name, traj) in zip(trace_styles(len(runs)), runs.items()):
        mask = _grasping(traj)
        axis.plot(traj.t[mask], traj.log["cone_margin"][mask], label=name, **style)
    axis.axhline(0.0, color="0.35", lw=0.8, zorder=1.5, label="cone boundary")  # behind the traces that sit on it
    axis.set(xlabel="t [s]", ylabel="cone margin [N]", title=title)
    axis.grid(alpha=0.3)
    legend_beside(axis)
    return figure


def workspace_figure(points: dict[str, np.ndarray], title: str = "") -> Figure:
    """Fingertip workspaces: top view (x-y, the palm plane) and side view (y-z) of sampled tip positions [m].

    Overlapping clouds stay visible (:func:`scatter_traces`): in the side view F1 and F2 (mirror images in x) fall
    on the same points, drawn as rings and dots.  Legends sit beside the views.

    Args:
        points: Finger -> (N, 3) fingertip positions in frame W (e.g. ``bhgrasp.model.ik.workspace(...).points``).
        title: Figure title.
    """
    if not points:
        raise InputError("`points` must hold at least one finger's samples")
    figure = Figure(figsize=(12, 5), layout="constrained")
    axes = figure.subplots(1, 2)
    for axis, (u, v) in zip(axes, ((0, 1), (1, 2))):
        scatter_traces(axis, {finger: (xyz[:, u], xyz[:, v]) for finger, xyz in points.items()})
        legend = legend_beside(axis, fontsize=9, markerscale=2.5)
        for handle in legend.legend_handles:
            handle.set_alpha(1.0)
        axis.grid(True, alpha=0.3)
    axes[0].set(xlabel="x [m]", ylabel="y [m]", title="top view (palm plane)", aspect="equal")
    axes[1].set(xlabel="y [m]", ylabel="z [m] (palm normal)", title="side view", aspect="equal")
    if title:
        figure.suptitle(title)
    return figure


__all__ = [
    "cone_margin_figure",
    "force_case_figure",
    "force_figure",
    "grasp_figure",
    "log_figure",
    "object_error_figure",
    "save_force_figure",
    "workspace_figure",
]
