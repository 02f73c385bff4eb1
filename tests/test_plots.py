"""Figures draw the run's own numbers (the plotted lines are the logged data, in the stated units)."""

from __future__ import annotations

import numpy as np
import pytest

import bhgrasp as bh
from bhgrasp import plots
from bhgrasp.experiments.chapter3 import f3_case


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
