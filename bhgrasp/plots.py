"""Matplotlib figures of runs: joint tracking, errors and torques, contact forces, object pose errors, cone margins.

Figures are :class:`Figure`, a :class:`matplotlib.figure.Figure` that renders itself as a PNG for Jupyter (no pyplot
state, no backend change): they work headless, show in any notebook with ``display(figure)`` or as a cell's last
value without ``%matplotlib inline``, and save with ``figure.savefig``.
"""

from __future__ import annotations

import io
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import matplotlib.figure
import numpy as np

from bhgrasp.data import Trajectory
from bhgrasp.errors import InputError


class Figure(matplotlib.figure.Figure):
    """A matplotlib figure that Jupyter shows as a PNG by itself (``_repr_png_``), whatever the backend."""

    def _repr_png_(self) -> bytes:
        """The figure as PNG bytes at 100 dpi (what IPython's display calls)."""
        buffer = io.BytesIO()
        self.savefig(buffer, format="png", dpi=100)
        return buffer.getvalue()


def tracking_figure(
    runs: dict[str, Trajectory], joints: Sequence[int], labels: Sequence[str], title: str = ""
) -> Figure:
    """One row per joint: position with its reference [deg], tracking error [deg] and torque [N m] of each run.

    Args:
        runs: Name -> trajectory with ``log["q_d"]`` (any :class:`~bhgrasp.controllers.JointTracking` run).
        joints: Joint indices to show.
        labels: One label per joint.
        title: Figure title.
    """
    if not runs:
        raise InputError("`runs` must hold at least one trajectory")
    if len(joints) != len(labels) or not joints:
        raise InputError(f"`joints` and `labels` must be non-empty and of equal length, got {joints}, {labels}")
    figure = Figure(figsize=(13, 2.6 * len(joints)), layout="tight")
    axes = figure.subplots(len(joints), 3, squeeze=False, sharex=True)
    for name, traj in runs.items():
        if "q_d" not in traj.log:
            raise InputError(f"run {name!r} has no logged reference `q_d` (use a JointTracking controller)")
    for name, traj in runs.items():
        for row, (joint, label) in enumerate(zip(joints, labels)):
            desired = traj.log["q_d"][:, joint]
            (line,) = axes[row, 0].plot(traj.t, np.degrees(traj.q[:, joint]), lw=1.2, label=name)
            axes[row, 1].plot(traj.t, np.degrees(traj.q[:, joint] - desired), lw=1.0, color=line.get_color())
            # torques: the raw signal faint and behind (a chattering law's band must not hide the others), its
            # 20 ms running mean on top
            axes[row, 2].plot(traj.t, traj.u[:, joint], lw=0.4, alpha=0.2, color=line.get_color(), zorder=1)
            axes[row, 2].plot(traj.t, _running_mean(traj.t, traj.u[:, joint], 0.02), lw=1.1, color=line.get_color(),
                              zorder=2)  # fmt: skip
            axes[row, 0].set_ylabel(f"{label} [deg]")
    first = next(iter(runs.values()))
    for row, joint in enumerate(joints):  # the reference once, on top of every run
        axes[row, 0].plot(first.t, np.degrees(first.log["q_d"][:, joint]), color="k", ls="--", lw=0.9, zorder=10,
                          label="reference" if row == 0 else None)  # fmt: skip
    axes[0, 0].set_title("position (black dashed: reference)")
    axes[0, 1].set_title("error q - q_d [deg]")
    for ax in axes[-1]:
        ax.set_xlabel("t [s]")
    for ax in axes.ravel():
        ax.grid(alpha=0.3)
    axes[0, 0].legend(fontsize=7, ncol=2)
    axes[0, 2].set_title("torque [N m] (faint: raw; solid: 20 ms mean)")
    if title:
        figure.suptitle(title)
    return figure


def _running_mean(t: np.ndarray, values: np.ndarray, window: float) -> np.ndarray:
    """Centred running mean of ``values`` over ``window`` [s] (samples at a uniform step), same length."""
    width = max(1, round(window / max(float(np.median(np.diff(t))), 1e-12))) if len(t) > 1 else 1
    kernel = np.ones(width) / width
    padded = np.pad(values, (width // 2, width - 1 - width // 2), mode="edge")
    return np.convolve(padded, kernel, mode="valid")


def save_case_figures(case: Any, output: Path) -> list[str]:
    """PNG figures of an experiment case (runs grouped by noise; runs over different joints get their own)."""
    output = Path(output)
    names: list[str] = []
    groups: dict[tuple, dict[str, Any]] = {}
    for run in case.runs:
        key = (run.noise, run.joints) if "q_d" in run.trajectory.log else None
        if key is None:
            continue
        groups.setdefault(key, {})[run.name] = run
    for index, ((noise, joints), runs) in enumerate(groups.items()):
        first = next(iter(runs.values()))
        suffix = "noise" if noise else "clean"
        name = f"chapter3_{case.key}_{index}_{suffix}.png"
        title = f"{case.title}" + (" - with sensor noise" if noise else "")
        figure = tracking_figure({k: r.trajectory for k, r in runs.items()}, joints[:4], first.labels[:4], title)
        figure.savefig(output / name, dpi=90)
        names.append(name)
    return names


def force_figure(traces: dict[str, tuple[np.ndarray, np.ndarray, float | None]], title: str = "") -> Figure:
    """Contact force [N] against time [s] of several runs; a dashed line marks each run's desired force."""
    if not traces:
        raise InputError("`traces` must hold at least one (t, force, desired) entry")
    figure = Figure(figsize=(9, 4.5), layout="tight")
    ax = figure.subplots()
    for name, (t, force, desired) in traces.items():
        (line,) = ax.plot(t, force, lw=1.0, label=name)
        if desired is not None:
            ax.axhline(desired, ls="--", lw=0.7, color=line.get_color())
    ax.set(xlabel="t [s]", ylabel="normal contact force [N]", title=title)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, ncol=2)
    return figure


def save_force_figure(case: Any, path: Path) -> Path:
    """PNG of a force-control case's traces (``case.traces``, ``case.title``)."""
    path = Path(path)
    figure = force_figure(case.traces, case.title)
    if case.key == "tuning":
        figure.axes[0].set(xlabel="generation", ylabel="best fitness: mean |f_d - f| [N]", yscale="log")
    figure.savefig(path, dpi=90)
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
    for name, traj in runs.items():
        if key not in traj.log:
            raise InputError(f"run {name!r} has no logged {key!r}; it logs {sorted(traj.log)}")
        values = traj.log[key].reshape(len(traj), -1)
        for axis, channel in zip(axes, channels):
            axis.plot(traj.t, values[:, channel], lw=1.0, label=name)
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
    for name, traj in runs.items():
        mask = _grasping(traj)
        for axis, channel in zip(axes, channels):
            axis.plot(traj.t[mask], 1e3 * traj.log["object_error"][mask, channel], lw=1.0, label=name)
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

    Fingers whose forces coincide stay visible: each finger's traces are drawn thinner than the previous
    finger's, so equal traces nest.  Legends sit beside the panels, not over the traces.

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
    for k, axis in enumerate("xyz"):
        axes[0].plot(t, 1e3 * error[:, k], label=axis)
        axes[1].plot(t, 1e3 * error[:, 3 + k], label=f"about {axis}")
    axes[0].set(ylabel="object position error [mm]", title="object pose error (world, COM)")
    axes[1].set(ylabel="object rotation error [mrad]")
    measured, commanded = measured_normal[grasping], traj.log["commanded_normal"][grasping]
    widths = np.linspace(3.0, 1.0, len(finger_names)) if len(finger_names) > 1 else np.array([1.5])
    for k, finger in enumerate(finger_names):
        line = axes[2].plot(t, measured[:, k], lw=widths[k], label=f"{finger} measured")[0]
        axes[2].plot(t, commanded[:, k], ":", lw=max(widths[k] / 2, 0.8), color="k" if k == 0 else line.get_color(),
                     label=f"{finger} commanded")  # fmt: skip
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
        axis.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0)
    start = f"{t[0]:.2f} s" if len(t) else "-"
    figure.suptitle(f"from the grasp on (t >= {start}; before it the fingers approach the object)", fontsize=9)
    return figure


def cone_margin_figure(runs: dict[str, Trajectory], title: str = "") -> Figure:
    """Cone margin mu f_n - |f_t| [N] of the commanded forces (negative: outside the assumed cone) of several runs."""
    if not runs:
        raise InputError("`runs` must hold at least one trajectory")
    figure = Figure(figsize=(9, 4), layout="tight")
    axis = figure.subplots()
    for name, traj in runs.items():
        mask = _grasping(traj)
        axis.plot(traj.t[mask], traj.log["cone_margin"][mask], lw=1.0, label=name)
    axis.axhline(0.0, color="k", lw=0.7)
    axis.set(xlabel="t [s]", ylabel="cone margin [N]", title=title, yscale="symlog")
    axis.grid(alpha=0.3)
    axis.legend(fontsize=7)
    return figure


__all__ = [
    "Figure", "cone_margin_figure", "force_figure", "grasp_figure", "log_figure", "object_error_figure",
    "save_case_figures", "save_force_figure", "tracking_figure",
]  # fmt: skip
