"""Figures a paper would print (issue 32, item 10): units on every axis, readable ticks, no trace hidden.

:func:`assert_readable` checks a drawn figure; each test builds one of the project's figures from a short run and
checks it.  What each test caught on the code before this issue is in its docstring.
"""

from __future__ import annotations

import re
from itertools import combinations
from types import SimpleNamespace

import numpy as np
import pytest
from matplotlib.axes import Axes
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.collections import PathCollection
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from scipy.spatial import cKDTree

import bhgrasp as bh
from bhgrasp import plots
from bhgrasp.plots.runs import _grasping

UNIT = re.compile(r"\[[^\[\]]+\]")  # "[N]", "[deg]", "[N m]"
UNITLESS = ("generation",)  # axis labels that count something and have no unit (CMA-ES generations)
MIN_TICK_LABELS = 3  # distinct non-empty y tick labels within the axis limits
COINCIDE = 0.005  # two traces coincide where they are this close, as a fraction of the axes' height (or width)
STRETCH = 0.10  # ... over at least this fraction of their samples
MIN_RIM = 1.5  # [pt] a solid trace on top of an equal one must be this much thinner: 0.75 pt of it shows each side
FAINT = 0.3  # lines at alpha <= FAINT are a backdrop (raw torques behind their means), exempt from the hiding check
MIN_SIZE_RATIO = 4.0  # a filled marker on top of an equal one hides it unless that one has this much more area


def assert_readable(figure: Figure) -> None:
    """Draw ``figure`` (Agg) and check every axes that holds data (lines or scatter points).

    * Its x and y labels are non-empty and state a unit in brackets ("[N]"), or are in :data:`UNITLESS`; an empty x
      label passes when an axes sharing that x axis has one (stacked panels label the bottom one).
    * At least :data:`MIN_TICK_LABELS` distinct non-empty y tick labels (major or minor) lie within the y limits.
    * No trace is hidden: two lines with the same x samples that coincide (within :data:`COINCIDE` of the axes'
      height over >= :data:`STRETCH` of the samples) must leave the lower one visible: the upper one has gaps
      (dashed, dotted) and differs from it in dash pattern or width, or is at least :data:`MIN_RIM` thinner, or the
      lower one has markers of another kind.  (A stricter form of "their (linestyle, linewidth, marker) differ": a
      solid line on top hides an equal dashed one, and a 1 pt wider line under a solid one shows as a hairline.)
      Lines at alpha <= :data:`FAINT` and two-point reference lines (``axhline``, ``axvline``) are exempt.
      Likewise two scatter clouds whose points coincide (>= STRETCH of one's points within COINCIDE of the other's)
      differ in marker shape or fill (hollow/filled), or the lower one's markers have :data:`MIN_SIZE_RATIO` x the area.
    * Its legend covers no data point (no line vertex or scatter point inside the legend's box).
    """
    canvas = figure.canvas if isinstance(figure.canvas, FigureCanvasAgg) else FigureCanvasAgg(figure)
    canvas.draw()
    renderer = canvas.get_renderer()
    for axis in figure.axes:
        lines = [line for line in axis.lines if line.get_visible() and len(line.get_xdata()) >= 3]
        clouds = [c for c in axis.collections if isinstance(c, PathCollection) and len(c.get_offsets()) >= 3]
        if not lines and not clouds:
            continue
        where = f"axes {axis.get_title() or axis.get_ylabel()!r}"
        _check_labels(axis, where)
        labels = _y_tick_labels(axis)
        assert len(labels) >= MIN_TICK_LABELS, f"{where}: y tick labels {sorted(labels)} (want >= {MIN_TICK_LABELS})"
        _check_lines(axis, [line for line in lines if (line.get_alpha() or 1.0) > FAINT], where)
        _check_clouds(axis, clouds, where)
        _check_legend(axis, lines, clouds, renderer, where)


def _has_unit(label: str) -> bool:
    return bool(UNIT.search(label)) or label.strip() in UNITLESS


def _check_labels(axis: Axes, where: str) -> None:
    ylabel = axis.get_ylabel()
    assert _has_unit(ylabel), f"{where}: y label {ylabel!r} states no unit in brackets"
    xlabel = axis.get_xlabel()
    if not xlabel:  # stacked panels: the bottom one of a shared x axis carries the label
        siblings = [other.get_xlabel() for other in axis.get_shared_x_axes().get_siblings(axis) if other is not axis]
        xlabel = next((label for label in siblings if label), "")
    assert _has_unit(xlabel), f"{where}: x label {xlabel!r} states no unit in brackets"


def _y_tick_labels(axis: Axes) -> set[str]:
    """The distinct non-empty y tick labels drawn within the axis limits (major and minor)."""
    low, high = sorted(axis.get_ylim())
    margin = 1e-9 * max(abs(low), abs(high), 1.0)
    labels = set()
    for locations, ticks in (
        (axis.yaxis.get_majorticklocs(), axis.yaxis.get_major_ticks),
        (axis.yaxis.get_minorticklocs(), axis.yaxis.get_minor_ticks),
    ):
        for location, tick in zip(locations, ticks(len(locations))):
            text = tick.label1.get_text().strip()
            if low - margin <= location <= high + margin and tick.label1.get_visible() and text:
                labels.add(text)
    return labels


def _dashes(line: Line2D):
    """The line's on-off pattern (unscaled), or its style name if matplotlib keeps none."""
    return getattr(line, "_unscaled_dash_pattern", line.get_linestyle())


def _has_marker(line: Line2D) -> bool:
    return line.get_marker() not in (None, "", " ", "None", "none")


def _stays_visible(lower: Line2D, upper: Line2D) -> bool:
    """Whether ``lower`` still shows where ``upper`` (drawn after it) coincides with it."""
    if _has_marker(lower) and lower.get_marker() != upper.get_marker():
        return True
    gaps = upper.get_linestyle() not in ("-", "solid")
    if gaps and (_dashes(upper) != _dashes(lower) or upper.get_linewidth() != lower.get_linewidth()):
        return True  # the lower shows through the upper's gaps (patterns scale with width: they drift apart)
    return lower.get_linewidth() - upper.get_linewidth() >= MIN_RIM


def _display(axis: Axes, x, y) -> np.ndarray:
    with np.errstate(all="ignore"):
        xy = np.column_stack([np.asarray(x, dtype=float), np.asarray(y, dtype=float)])
        return axis.transData.transform(xy)


def _name(line: Line2D) -> str:
    """The line's legend label, or its colour for an unlabelled one."""
    label = str(line.get_label())
    return f"{line.get_color()} line" if label.startswith("_") else label


def _check_lines(axis: Axes, lines: list[Line2D], where: str) -> None:
    height = axis.bbox.height
    order = {id(line): (line.get_zorder(), k) for k, line in enumerate(axis.lines)}  # matplotlib's drawing order
    for first, second in combinations(lines, 2):
        x1, x2 = np.asarray(first.get_xdata(), float), np.asarray(second.get_xdata(), float)
        if x1.shape != x2.shape or not np.array_equal(x1, x2, equal_nan=True):
            continue
        y1, y2 = _display(axis, x1, first.get_ydata())[:, 1], _display(axis, x2, second.get_ydata())[:, 1]
        with np.errstate(invalid="ignore"):
            close = np.abs(y1 - y2) <= COINCIDE * height
        if np.count_nonzero(close) < STRETCH * len(x1):
            continue
        lower, upper = sorted((first, second), key=lambda line: order[id(line)])
        assert _stays_visible(lower, upper), (
            f"{where}: {_name(lower)!r} is hidden under {_name(upper)!r} where they coincide "
            f"(styles {lower.get_linestyle()}/{lower.get_linewidth()} and {upper.get_linestyle()}/"
            f"{upper.get_linewidth()})"
        )


def _filled(cloud: PathCollection) -> bool:
    return len(cloud.get_facecolor()) > 0


def _check_clouds(axis: Axes, clouds: list[PathCollection], where: str) -> None:
    scale = min(axis.bbox.width, axis.bbox.height)
    order = {id(cloud): (cloud.get_zorder(), k) for k, cloud in enumerate(axis.collections)}
    for first, second in combinations(clouds, 2):
        a = first.get_offset_transform().transform(first.get_offsets())
        b = second.get_offset_transform().transform(second.get_offsets())
        near_a = np.isfinite(cKDTree(b).query(a, distance_upper_bound=COINCIDE * scale)[0])
        near_b = np.isfinite(cKDTree(a).query(b, distance_upper_bound=COINCIDE * scale)[0])
        if max(near_a.mean(), near_b.mean()) < STRETCH:
            continue
        lower, upper = sorted((first, second), key=lambda cloud: order[id(cloud)])
        shapes = [cloud.get_paths()[0].vertices for cloud in (lower, upper)]
        same_shape = shapes[0].shape == shapes[1].shape and np.allclose(*shapes)
        nested = lower.get_sizes().min() >= MIN_SIZE_RATIO * upper.get_sizes().max()
        assert not same_shape or _filled(lower) != _filled(upper) or nested, (
            f"{where}: the points of {lower.get_label()!r} are hidden under those of {upper.get_label()!r} (same "
            f"marker, fill and size {lower.get_sizes()[0]:g} / {upper.get_sizes()[0]:g})"
        )


def _check_legend(axis: Axes, lines: list[Line2D], clouds: list[PathCollection], renderer, where: str) -> None:
    legend = axis.get_legend()
    if legend is None or not legend.get_visible():
        return
    box = legend.get_window_extent(renderer)
    points = [_display(axis, line.get_xdata(), line.get_ydata()) for line in lines]
    points += [cloud.get_offset_transform().transform(cloud.get_offsets()) for cloud in clouds]
    xy = np.concatenate(points)
    inside = (xy[:, 0] > box.x0) & (xy[:, 0] < box.x1) & (xy[:, 1] > box.y0) & (xy[:, 1] < box.y1)
    assert not inside.any(), f"{where}: the legend covers {np.count_nonzero(inside)} data points"


# ------------------------------------------------------------------------------------------------ the checker
def test_the_checker_catches_hidden_equal_traces_missing_units_and_bare_log_ticks():
    """Two equal traces in the same style, a bare log axis, no unit: each rejected; the shared styles pass."""
    t = np.linspace(0.0, 1.0, 50)
    force = 5.0 + np.sin(3 * t)
    figure = Figure()
    axis = figure.subplots()
    axis.plot(t, force, lw=1.0, label="a")
    axis.plot(t, force, lw=1.0, label="b")
    axis.set(xlabel="t [s]", ylabel="force [N]")
    with pytest.raises(AssertionError, match="'a' is hidden under 'b'"):
        assert_readable(figure)
    good = plots.force_figure({"a": (t, force, None), "b": (t, force, None), "c": (t, force + 1e-4, 5.0)})
    assert_readable(good)
    axis.set(ylabel="force")
    with pytest.raises(AssertionError, match="states no unit"):
        assert_readable(figure)
    bare = Figure()
    axis = bare.subplots()
    axis.plot(t, 0.086 + 0.06 * t**3, label="fitness")  # 0.086-0.146: matplotlib labels 0.09 and 0.1 only
    axis.set(xlabel="generation", ylabel="fitness [N]", yscale="log")
    with pytest.raises(AssertionError, match="y tick labels"):
        assert_readable(bare)
    plots.readable_log_axis(axis.yaxis)
    assert_readable(bare)


def test_trace_styles_nest_equal_traces():
    styles = plots.trace_styles(9)
    widths = [style["linewidth"] for style in styles]
    assert widths == sorted(widths, reverse=True) and len(set(widths)) == 9 and styles[0]["linestyle"] == "-"
    assert all(style["linestyle"] != "-" for style in styles[1:])
    assert [style["zorder"] for style in styles] == sorted(style["zorder"] for style in styles)
    assert plots.trace_styles(1)[0]["linestyle"] == "-" and plots.trace_styles(0) == []


# ------------------------------------------------------------------------------------------------ the figures
def cone_figure() -> tuple[Figure, dict]:
    """chapter5_cones.png from two short runs (1.8 s; the cone binds at 1.3 s) of the 1 kg box."""
    from bhgrasp.scenarios.grasp_demo import run_grasp_demo

    runs = {
        "QP 1.0 kg": run_grasp_demo(1.0, 0.5, "smc-adaptive", 1.8).trajectory,
        "G^+ 1.0 kg": run_grasp_demo(1.0, 0.5, "smc-adaptive", 1.8, distribution="pinv").trajectory,
    }
    return plots.cone_margin_figure(runs, "commanded forces' cone margin, 1 kg box"), runs


def tuning_figure() -> Figure:
    """chapter4_tuning.png from short CMA-ES runs on a cheap fitness with the chapter's floor (0.086 N), standing in
    for the impedance tuning (minutes)."""
    from bhgrasp.tuning import cma_es

    def fitness(x):
        return 0.086 + 0.08 * float(np.sum((np.asarray(x) - 0.3) ** 2))

    traces = {}
    for start in ((-0.3, -0.3), (0.7, 0.7), (-1.0, 1.0)):
        for seed in (1, 2):
            result = cma_es(
                fitness,
                np.array(start),
                0.5,
                seed=seed,
                max_generations=30,
                executor="serial",
                bounds=([-2.0, -1.0], [1.0, 2.0]),
            )
            traces[f"from {list(start)}, seed {seed}"] = (np.arange(result.generations), result.generation_best, None)
    return plots.force_case_figure(SimpleNamespace(key="tuning", title="CMA-ES tuning (short runs)", traces=traces))


def f3_figures() -> tuple[dict[str, Figure], object]:
    """chapter3_f3_*.png of the F3 case at 0.15 x its durations (0.45 s runs), and the case."""
    from bhgrasp.thesis.chapter3 import f3_hosm

    case = f3_hosm(scale=0.15)
    return plots.case_figures(case), case


def demo_figure() -> Figure:
    """bhgrasp demo's grasp_demo.png of a 1.5 s demo run."""
    from bhgrasp.scenarios.grasp_demo import demo_figure, run_grasp_demo

    return demo_figure(run_grasp_demo(duration=1.5), bh.BarrettHand())


def workspace_figure() -> Figure:
    """bhgrasp tour's workspace.png at 500 samples per finger (as tests/test_cli.py runs the tour)."""
    from bhgrasp.scenarios.tour import workspace_figure

    return workspace_figure(bh.BarrettHand(), 500, 3)


def test_chapter5_cone_figure_is_linear_and_shows_both_distributions():
    """chapter5_cones.png: was a symlog axis labelled only "0" and "-10^0", and the QP trace lay under the equal
    G^+ trace until the cone binds (1.3 s): both caught (tick labels; 'QP 1.0 kg' hidden under 'G^+ 1.0 kg')."""
    figure, runs = cone_figure()
    axis = figure.axes[0]
    assert axis.get_yscale() == "linear"
    for line, traj in zip(axis.lines, runs.values()):  # the data unchanged: the margins from the grasp on
        np.testing.assert_array_equal(line.get_ydata(), traj.log["cone_margin"][_grasping(traj)])
    assert np.min(axis.lines[1].get_ydata()) < 0.0 <= np.min(axis.lines[0].get_ydata()) + 1e-9  # G^+ leaves the cone
    assert_readable(figure)


def test_chapter4_tuning_figure_labels_its_log_axis():
    """chapter4_tuning.png: the log axis (less than a decade) showed two labels, "10^-1" and "9x10^-2", and the
    converged runs' equal traces hid each other: both caught."""
    figure = tuning_figure()
    axis = figure.axes[0]
    assert axis.get_yscale() == "log" and axis.get_xlabel() == "generation"
    assert_readable(figure)


def test_chapter3_f3_noise_figure_tells_its_nine_controllers_apart_and_says_what_it_shows():
    """chapter3_f3_1_noise.png: nine runs in one style each (they coincide after the transient), error and torque
    panels without a y label, and the title "... with and without noise ... - with sensor noise": all caught.  Now
    three blocks of three runs, each on its own scale (CTC's 8 deg error flattened the sliding laws' 0.5 deg)."""
    figures, case = f3_figures()
    assert list(figures) == ["chapter3_f3_0_clean.png", "chapter3_f3_1_noise.png"]
    noisy = figures["chapter3_f3_1_noise.png"]
    title = noisy._suptitle.get_text()
    assert "with and without" not in title and title.endswith("- with sensor noise")
    assert figures["chapter3_f3_0_clean.png"]._suptitle.get_text().endswith("- without sensor noise")
    for name in ("CTC", "SMC", "ASMC", "HOSM", "HOSMA"):
        assert name in title
    assert len(noisy.axes) == 3 * 2 * 3  # three blocks (CTC/SMC/ASMC, HOSM A-C, HOSMA A-C) of two joints
    for block in range(3):
        errors = noisy.axes[6 * block + 1]
        assert len({(line.get_linewidth(), _dashes(line)) for line in errors.lines}) == 3
    drawn = [line.get_label() for axis in noisy.axes[::6] for line in axis.lines[:3]]  # each block's positions
    assert sorted(drawn) == sorted(run.name for run in case.runs.values() if run.noise)
    assert_readable(noisy)


def test_demo_figure_shows_f1_beside_f2():
    """bhgrasp demo's grasp_demo.png: F1's force was a 3 pt solid line under F2's 2 pt solid one (a 0.5 pt
    hairline each side), and the pose error's 'about y' lay under 'about z' in the same style: both caught."""
    assert_readable(demo_figure())


def test_tour_workspace_figure_shows_f1_and_keeps_its_legends_off_the_points():
    """bhgrasp tour's workspace.png: in the side view F1's points (the mirror image of F2's in x, so the same
    y-z points) lay under F2's in the same marker and size, and the legend covered points: both caught."""
    figure = workspace_figure()
    f1, f2 = figure.axes[1].collections[:2]
    np.testing.assert_allclose(f1.get_offsets(), f2.get_offsets(), atol=1e-12)  # the same points: F1 must show
    assert_readable(figure)
