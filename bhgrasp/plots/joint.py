"""Joint-space figures: tracking, errors and torques of several runs; an experiment case's figures by file name."""

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
    trace_styles,
)


def tracking_figure(
    runs: dict[str, Trajectory],
    joints: Sequence[int],
    labels: Sequence[str],
    title: str = "",
    groups: Sequence[Sequence[str]] | None = None,
) -> Figure:
    """One row per joint: position with its reference [deg], tracking error [deg] and torque [N m] of each run.

    Runs whose traces coincide stay visible (:func:`trace_styles`: each run keeps one colour and line style in all
    its panels); a legend sits beside each block's top right panel.

    Args:
        runs: Name -> trajectory with ``log["q_d"]`` (any :class:`~bhgrasp.controllers.JointTracking` run).
        joints: Joint indices to show.
        labels: One label per joint.
        title: Figure title.
        groups: Run names by block: each block gets its own rows (one per joint), so that many runs are read a few
            at a time on scales of their own (e.g. CTC's large error does not flatten the sliding laws' small ones).
            Default: all runs in one block.  Names not in ``runs`` are skipped; every run must be in one block.
    """
    if not runs:
        raise InputError("`runs` must hold at least one trajectory")
    if len(joints) != len(labels) or not joints:
        raise InputError(f"`joints` and `labels` must be non-empty and of equal length, got {joints}, {labels}")
    for name, traj in runs.items():
        if "q_d" not in traj.log:
            raise InputError(f"run {name!r} has no logged reference `q_d` (use a JointTracking controller)")
    blocks = [list(runs)] if groups is None else [[name for name in group if name in runs] for group in groups]
    blocks = [block for block in blocks if block]
    grouped = [name for block in blocks for name in block]
    if sorted(grouped) != sorted(runs):
        raise InputError(f"`groups` must hold every run once, got {list(groups or [])} for runs {list(runs)}")
    colours = {name: f"C{k % 10}" for k, name in enumerate(runs)}
    n = len(joints)
    figure = Figure(figsize=(14, 2.6 * n * len(blocks)), layout="constrained")
    axes = figure.subplots(n * len(blocks), 3, squeeze=False, sharex=True)
    for b, block in enumerate(blocks):
        for style, name in zip(trace_styles(len(block)), block):
            traj, colour = runs[name], colours[name]
            for row, joint in enumerate(joints, start=b * n):
                desired = traj.log["q_d"][:, joint]
                axes[row, 0].plot(traj.t, np.degrees(traj.q[:, joint]), label=name, color=colour, **style)
                axes[row, 1].plot(traj.t, np.degrees(traj.q[:, joint] - desired), color=colour, **style)
                # torques: the raw signal faint and behind (a chattering law's band must not hide the others), its
                # 20 ms running mean on top
                axes[row, 2].plot(traj.t, traj.u[:, joint], lw=0.4, alpha=0.2, color=colour, zorder=1)
                axes[row, 2].plot(traj.t, _running_mean(traj.t, traj.u[:, joint], 0.02), color=colour, **style)
        first = runs[block[0]]
        for row, (joint, label) in enumerate(zip(joints, labels), start=b * n):  # the reference once, on top
            axes[row, 0].plot(
                first.t,
                np.degrees(first.log["q_d"][:, joint]),
                color="k",
                ls="--",
                lw=0.9,
                zorder=10,
                label="reference" if row == b * n else None,
            )
            axes[row, 0].set_ylabel(f"{label} [deg]")
            axes[row, 1].set_ylabel(f"{label} error [deg]")
            axes[row, 2].set_ylabel(f"{label} torque [N m]")
        heading = "" if groups is None else f"{', '.join(block)}: "
        axes[b * n, 0].set_title("position (black dashed: reference)")
        axes[b * n, 1].set_title(f"{heading}tracking error q - q_d", fontweight="normal" if groups is None else "bold")
        axes[b * n, 2].set_title("torque (faint: raw; lines: 20 ms mean)")
        legend_beside(axes[b * n, 2], *axes[b * n, 0].get_legend_handles_labels())
    for ax in axes[-1]:
        ax.set_xlabel("t [s]")
    for ax in axes.ravel():
        ax.grid(alpha=0.3)
    if title:
        figure.suptitle(title)
    return figure


def _running_mean(t: np.ndarray, values: np.ndarray, window: float) -> np.ndarray:
    """Centred running mean of ``values`` over ``window`` [s] (samples at a uniform step), same length."""
    width = max(1, round(window / max(float(np.median(np.diff(t))), 1e-12))) if len(t) > 1 else 1
    kernel = np.ones(width) / width
    padded = np.pad(values, (width // 2, width - 1 - width // 2), mode="edge")
    return np.convolve(padded, kernel, mode="valid")


def case_figures(case: Any) -> dict[str, Figure]:
    """Tracking figures of an experiment case, by PNG file name: runs grouped by noise and measured joints.

    A figure's title is the case's ``figure_title`` (else its ``title``) and says whether its runs had sensor noise
    (when the case ran both ways); the case's ``figure_groups`` (if any) split the runs into blocks of rows
    (:func:`tracking_figure`); ``chapter3_<key>_<index>_<noise|clean>.png``.
    """
    groups: dict[tuple, dict[str, Any]] = {}
    for run in case.runs.values():
        if "q_d" in run.trajectory.log:
            groups.setdefault((run.noise, run.joints), {})[run.name] = run
    both = len({noise for noise, _ in groups}) > 1
    heading = getattr(case, "figure_title", "") or case.title
    figures: dict[str, Figure] = {}
    for index, ((noise, joints), runs) in enumerate(groups.items()):
        first = next(iter(runs.values()))
        name = f"chapter3_{case.key}_{index}_{'noise' if noise else 'clean'}.png"
        title = heading + (" - with sensor noise" if noise else " - without sensor noise" if both else "")
        figures[name] = tracking_figure(
            {k: r.trajectory for k, r in runs.items()},
            joints[:4],
            first.labels[:4],
            title,
            getattr(case, "figure_groups", None),
        )
    return figures


def save_case_figures(case: Any, output: Path) -> list[str]:
    """PNG figures of an experiment case (:func:`case_figures`) written into ``output``; returns their names."""
    output = Path(output)
    names: list[str] = []
    for name, figure in case_figures(case).items():
        figure.savefig(output / name, dpi=90)
        names.append(name)
    return names


__all__ = ["case_figures", "save_case_figures", "tracking_figure"]
