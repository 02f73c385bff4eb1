"""Figures draw the run's own numbers (the plotted lines are the logged data, in the stated units)."""

from __future__ import annotations

import numpy as np
import pytest

import bhgrasp as bh
from bhgrasp import plots
from bhgrasp.plots.joint import _running_mean
from bhgrasp.scenarios.joint_tracking import f3_case


@pytest.fixture(scope="module")
def asmc():
    return f3_case("ASMC", noise=False, duration=0.4).trajectory


def test_log_figure_draws_sliding_variables_and_estimates(asmc):
    figure = plots.log_figure({"ASMC": asmc}, "s", [6, 7], ["F3 q2", "F3 q3"], "s [rad/s]", "sliding variables")
    lines = [axis.lines[0] for axis in figure.axes]
    np.testing.assert_array_equal(lines[1].get_ydata(), asmc.log["s"][:, 7])
    np.testing.assert_array_equal(lines[0].get_xdata(), asmc.t)
    estimates = plots.log_figure({"ASMC": asmc}, "theta", [0], ["m F1 knuckle"], "[kg]")
    np.testing.assert_array_equal(estimates.axes[0].lines[0].get_ydata(), asmc.log["theta"][:, 0])
    with pytest.raises(bh.InputError, match="no logged 'force'"):
        plots.log_figure({"ASMC": asmc}, "force", [0], ["f"], "[N]")


def test_tracking_figure_shows_position_error_and_torque_in_degrees_and_newton_metres(asmc):
    figure = plots.tracking_figure({"ASMC": asmc}, [7], ["F3 q3"])
    position, error, torque = figure.axes
    np.testing.assert_allclose(position.lines[0].get_ydata(), np.degrees(asmc.q[:, 7]))
    np.testing.assert_allclose(error.lines[0].get_ydata(), np.degrees(asmc.q[:, 7] - asmc.log["q_d"][:, 7]))
    np.testing.assert_allclose(torque.lines[0].get_ydata(), asmc.u[:, 7])  # the commanded joint torque


def test_tracking_figure_keeps_the_reference_and_every_torque_visible(asmc):
    """Paper figures (issue 18): the reference drawn once, black, above the runs; raw torques faint behind their
    20 ms running means, so one chattering law's band does not hide the others."""
    chattering = f3_case("HOSM-C", noise=True, duration=0.4).trajectory
    figure = plots.tracking_figure({"ASMC": asmc, "HOSM-C": chattering}, [6, 7], ["F3 q2", "F3 q3"])
    for row in range(2):
        position, _, torque = figure.axes[3 * row : 3 * row + 3]
        reference = [line for line in position.lines if line.get_color() == "k"]
        assert len(reference) == 1 and reference[0].get_zorder() > max(
            line.get_zorder() for line in position.lines if line is not reference[0]
        )
        raw, mean = torque.lines[2], torque.lines[3]  # the chattering run's pair
        assert raw.get_alpha() <= 0.3 and mean.get_zorder() > raw.get_zorder()
        assert np.ptp(mean.get_ydata()) < np.ptp(raw.get_ydata())  # the mean is inside the band


def test_running_mean_keeps_a_constant_and_removes_a_chatter():
    t = np.arange(0.0, 1.0, 1e-3)
    np.testing.assert_allclose(_running_mean(t, np.full(t.shape, 0.3), 0.02), 0.3, rtol=1e-12)
    chatter = 0.5 + np.where(np.arange(len(t)) % 2, 1.0, -1.0)  # +-1 every sample around 0.5
    middle = _running_mean(t, chatter, 0.02)[20:-20]
    np.testing.assert_allclose(middle, 0.5, atol=0.06)  # 20 samples: one unpaired sample of 20 -> 1/20


def test_grasp_figure_marks_the_grasp_and_motion_and_keeps_equal_fingers_visible(tmp_path):
    """Equal F1 and F2 forces stay visible (nested widths); the grasp instant and the motion window are marked;
    legends sit beside the panels."""
    from bhgrasp.scenarios.grasp_demo import demo_figure, run_grasp_demo

    result = run_grasp_demo(duration=1.2)
    figure = demo_figure(result, bh.BarrettHand())
    forces = figure.axes[2]
    widths = [line.get_linewidth() for line in forces.lines if "measured" in str(line.get_label())]
    assert len(widths) == 3 and widths[0] > widths[1] > widths[2]
    for axis in figure.axes:
        spans = [patch for patch in axis.patches if patch.get_label() == "object motion"]
        assert len(spans) == 1
        np.testing.assert_allclose(spans[0].get_x(), result.motion_start)
        grasp = [line for line in axis.lines if line.get_label() == "grasp closed"]
        assert len(grasp) == 1 and grasp[0].get_xdata()[0] == result.grasp_time
        anchor = axis.get_legend().get_bbox_to_anchor().transformed(axis.transAxes.inverted())
        assert anchor.x0 >= 1.0  # outside the panel, over no trace
    assert f"t >= {result.grasp_time:.2f} s" in figure._suptitle.get_text()
