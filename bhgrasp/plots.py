"""Matplotlib figures of runs: joint tracking, tracking errors and torques.

Figures are built with :class:`matplotlib.figure.Figure` (no pyplot state, no backend change): they work headless,
display in notebooks and save with ``figure.savefig``.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.figure import Figure

from bhgrasp.errors import InputError
from bhgrasp.state import Trajectory


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
        for row, (joint, label) in enumerate(zip(joints, labels)):
            desired = traj.log["q_d"][:, joint]
            (line,) = axes[row, 0].plot(traj.t, np.degrees(traj.q[:, joint]), lw=1.2, label=name)
            axes[row, 0].plot(traj.t, np.degrees(desired), ls="--", lw=0.8, color=line.get_color())
            axes[row, 1].plot(traj.t, np.degrees(traj.q[:, joint] - desired), lw=1.0, color=line.get_color())
            axes[row, 2].plot(traj.t, traj.u[:, joint], lw=0.6, color=line.get_color())
            axes[row, 0].set_ylabel(f"{label} [deg]")
    axes[0, 0].set_title("position (dashed: reference)")
    axes[0, 1].set_title("error q - q_d [deg]")
    axes[0, 2].set_title("torque [N m]")
    for ax in axes[-1]:
        ax.set_xlabel("t [s]")
    for ax in axes.ravel():
        ax.grid(alpha=0.3)
    axes[0, 0].legend(fontsize=7, ncol=2)
    if title:
        figure.suptitle(title)
    return figure


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


__all__ = ["force_figure", "save_case_figures", "save_force_figure", "tracking_figure"]
