"""Performance metrics against closed-form truths: step responses, RMS and total variation of sines, spectra."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

from bhgrasp.errors import InputError
from bhgrasp.metrics import (
    StepResponse,
    TrackingError,
    chattering_index,
    control_effort,
    force_error,
    high_frequency_power,
    step_response,
    tracking_error,
)


def uniform(duration: float, h: float, t0: float = 0.0) -> np.ndarray:
    return t0 + h * np.arange(round(duration / h) + 1)


def second_order(t: np.ndarray, zeta: float, wn: float) -> np.ndarray:
    """Unit step response of wn^2 / (s^2 + 2 zeta wn s + wn^2), zeta < 1."""
    wd = wn * np.sqrt(1.0 - zeta**2)
    return 1.0 - np.exp(-zeta * wn * t) * (np.cos(wd * t) + zeta / np.sqrt(1.0 - zeta**2) * np.sin(wd * t))


# --- step_response ---------------------------------------------------------------------------------------------


def test_second_order_overshoot_and_peak_time_match_the_closed_form() -> None:
    zeta, wn, h = 0.3, 10.0, 1e-4
    t = uniform(5.0, h)
    result = step_response(t, second_order(t, zeta, wn), target=1.0)
    assert isinstance(result, StepResponse) and result.overshoot_percent.shape == (1,)
    # Sampled peak: the true peak lies within h/2 of a sample, so the peak value is low by at most
    # |y''(tp)| (h/2)^2 / 2 < wn^2 (h/2)^2 / 2 = 1.25e-7 (1.25e-5 %), and the peak time is off by at most h/2.
    overshoot = 100.0 * np.exp(-zeta * np.pi / np.sqrt(1.0 - zeta**2))
    assert result.overshoot_percent[0] == pytest.approx(overshoot, abs=1.3e-5)
    assert result.peak_time[0] == pytest.approx(np.pi / (wn * np.sqrt(1.0 - zeta**2)), abs=h / 2 + 1e-12)
    envelope = np.exp(-zeta * wn * t[-1]) / np.sqrt(1.0 - zeta**2)  # |y(T) - 1| <= envelope
    assert 0.0 <= result.steady_state_error[0] <= envelope
    # The underdamped 2 % settling time lies below the envelope estimate ln(1 / (0.02 sqrt(1 - zeta^2))) / (zeta wn).
    assert 0.0 < result.settling_time[0] <= np.log(1.0 / (0.02 * np.sqrt(1.0 - zeta**2))) / (zeta * wn)


def test_first_order_rise_and_settling_times_match_the_closed_form() -> None:
    tau, h = 0.5, 1e-3
    t = uniform(5.0, h)
    result = step_response(t, 1.0 - np.exp(-t / tau), target=1.0)
    # Linear interpolation of a crossing errs by at most h^2 |y''| / (8 |y'|) = h^2 / (8 tau) = 2.5e-7 s.
    assert result.rise_time[0] == pytest.approx(tau * np.log(9.0), abs=3e-7)
    assert result.settling_time[0] == pytest.approx(tau * np.log(50.0), abs=3e-7)
    assert result.overshoot_percent[0] == 0.0
    assert result.steady_state_error[0] == pytest.approx(np.exp(-5.0 / tau), rel=1e-12)
    assert result.peak_time[0] == pytest.approx(5.0)  # monotone: the extremum is the last sample


def test_downward_multichannel_step_with_offset_time_and_explicit_start() -> None:
    tau, h, t0 = np.array([0.5, 0.25]), 1e-3, 10.0
    t = uniform(5.0, h, t0)
    # Channel 0 steps 2 -> -1 (downwards), channel 1 steps 0 -> 4; both first order.
    shape = 1.0 - np.exp(-(t[:, None] - t0) / tau)
    start, target = np.array([2.0, 0.0]), np.array([-1.0, 4.0])
    y = start + (target - start) * shape
    result = step_response(t, y, target, start=start)
    assert result.rise_time.shape == (2,)
    np.testing.assert_allclose(result.rise_time, tau * np.log(9.0), atol=1e-6)
    np.testing.assert_allclose(result.settling_time, tau * np.log(50.0), atol=1e-6)  # measured from t[0]
    np.testing.assert_allclose(result.overshoot_percent, 0.0)
    np.testing.assert_allclose(result.peak_time, 5.0)


def test_settling_band_and_rise_fractions_are_parameters() -> None:
    tau, h = 1.0, 1e-3
    t = uniform(10.0, h)
    result = step_response(t, 1.0 - np.exp(-t / tau), target=1.0, band=0.05, rise=(0.05, 0.95))
    assert result.settling_time[0] == pytest.approx(tau * np.log(20.0), abs=1e-6)
    assert result.rise_time[0] == pytest.approx(tau * np.log(0.95 / 0.05), abs=1e-6)


def test_overshooting_response_settles_on_the_upper_edge_of_the_band() -> None:
    # y = 1 + 0.5 exp(-t) from start 0: starts above the band and enters it through 1.02 at t = ln 25.
    t = uniform(8.0, 1e-3)
    result = step_response(t, 1.0 + 0.5 * np.exp(-t), target=1.0, start=0.0)
    assert result.settling_time[0] == pytest.approx(np.log(25.0), abs=1e-6)
    assert result.overshoot_percent[0] == pytest.approx(50.0)
    assert result.peak_time[0] == 0.0 and result.rise_time[0] == 0.0


def test_never_settling_and_already_settled_responses() -> None:
    t = uniform(2.0, 1e-3)
    oscillating = step_response(t, 1.0 + 0.5 * np.sin(2 * np.pi * 3 * t + 0.1), target=1.0, start=0.0)
    assert oscillating.settling_time[0] == np.inf
    settled = step_response(t, np.full_like(t, 1.01), target=1.0, start=0.0)
    assert settled.settling_time[0] == 0.0 and settled.rise_time[0] == 0.0
    never_rises = step_response(t, 0.5 * (1.0 - np.exp(-t)), target=1.0, start=0.0)
    assert never_rises.rise_time[0] == np.inf and never_rises.settling_time[0] == np.inf


def test_zero_step_names_the_channel() -> None:
    t = uniform(1.0, 0.01)
    y = np.column_stack([t, np.full_like(t, 3.0)])
    with pytest.raises(InputError, match="channel 1"):
        step_response(t, y, target=[1.0, 3.0])
    with pytest.raises(InputError, match="channel 0"):
        step_response(t, t, target=1.0, start=1.0)


@pytest.mark.parametrize(("band", "rise"), [(0.0, (0.1, 0.9)), (1.0, (0.1, 0.9)), (0.02, (0.9, 0.1)), (0.02, (0.1,))])
def test_bad_band_or_rise_fractions_raise(band: float, rise: tuple) -> None:
    t = uniform(1.0, 0.01)
    with pytest.raises(InputError, match="band|rise"):
        step_response(t, t, target=1.0, band=band, rise=rise)


# --- control_effort and tracking_error: trapezoidal RMS ----------------------------------------------------------


def test_control_effort_of_sines_over_whole_periods() -> None:
    # Over whole periods the trapezoidal rule integrates a uniformly sampled sine squared exactly.
    t = uniform(2.0, 1e-3)
    amplitude, offset = np.array([0.7, 3.0]), 0.4
    u = np.column_stack([amplitude[0] * np.sin(2 * np.pi * 2.5 * t), offset + amplitude[1] * np.cos(2 * np.pi * t)])
    effort = control_effort(t, u)
    assert effort.shape == (2,)
    np.testing.assert_allclose(effort, [amplitude[0] / np.sqrt(2), np.sqrt(offset**2 + amplitude[1] ** 2 / 2)])
    assert control_effort(t, np.full_like(t, -2.0)) == pytest.approx([2.0], rel=1e-15)


def test_rms_is_a_time_average_not_a_sample_mean() -> None:
    # Error e(t) = t over [0, 1]: rms = 1 / sqrt(3).  Dense samples on [0, 0.5] would bias a sample mean low
    # (to about 0.30).  The trapezoidal rule overestimates the integral of t^2 by h^3 / 6 per interval: 8.3e-6 over
    # the 50 sparse ones (h = 0.01), i.e. 2.5e-5 relative on the mean square, 1.25e-5 on the rms.
    t = np.concatenate([np.linspace(0.0, 0.5, 5001)[:-1], np.linspace(0.5, 1.0, 51)])
    result = tracking_error(t, t, np.zeros_like(t))
    assert result.rms[0] == pytest.approx(1.0 / np.sqrt(3.0), rel=2e-5)
    assert np.sqrt(np.mean(t**2)) < 0.35  # what a sample mean would have given


def test_non_uniform_sampling_gives_the_rms_of_the_continuous_signal() -> None:
    # e = A sin(2 pi f t) over whole periods: rms A / sqrt 2.  Trapezoidal error on the mean of e^2 is at most
    # max(h)^2 max|(e^2)''| / 12 = max(h)^2 2 A^2 (2 pi f)^2 / 12.
    amplitude, frequency = 1.5, 1.0
    rng = np.random.default_rng(3)
    t_uniform = uniform(2.0, 1e-3)
    t_random = np.sort(np.concatenate([[0.0, 2.0], rng.uniform(0.0, 2.0, 1500)]))
    bound = np.diff(t_random).max() ** 2 * 2 * amplitude**2 * (2 * np.pi * frequency) ** 2 / 12
    true = amplitude / np.sqrt(2.0)
    for t in (t_uniform, t_random):
        error = tracking_error(t, amplitude * np.sin(2 * np.pi * frequency * t), np.zeros_like(t))
        assert error.rms[0] == pytest.approx(true, abs=bound / (2 * true) + 1e-12)  # d(rms) = d(ms) / (2 rms)
    assert bound / (2 * true) < 1e-3  # the comparison is tight


# --- tracking_error: percentages ---------------------------------------------------------------------------------


def test_tracking_percentages_use_the_range_of_the_desired_signal() -> None:
    t = uniform(2.0, 1e-3)
    desired = 2.0 + 3.0 * np.sin(2 * np.pi * 2.5 * t)  # range 6 (the peaks are samples)
    result = tracking_error(t, desired + 0.3, desired)
    assert isinstance(result, TrackingError)
    np.testing.assert_allclose([result.max_abs, result.rms, result.final_abs], 0.3, rtol=1e-12)
    np.testing.assert_allclose([result.max_percent, result.rms_percent], 5.0, rtol=1e-12)


def test_tracking_scale_is_the_range_over_the_whole_run_even_with_a_start_time() -> None:
    # Desired ramps 0 -> 10 during [0, 1], then holds; the error is 1 before t = 1, 0.5 from t = 1 on.
    t = uniform(2.0, 1e-3)
    desired = 10.0 * np.minimum(t, 1.0)
    actual = desired + np.where(t < 1.0, 1.0, 0.5)
    result = tracking_error(t, actual, desired, start_time=1.0)
    assert result.max_abs[0] == pytest.approx(0.5) and result.rms[0] == pytest.approx(0.5)
    assert result.max_percent[0] == pytest.approx(5.0) and result.rms_percent[0] == pytest.approx(5.0)
    assert tracking_error(t, actual, desired).max_abs[0] == pytest.approx(1.0)


def test_tracking_scale_falls_back_to_the_final_value_then_to_nan() -> None:
    t = uniform(1.0, 0.01)
    desired = np.column_stack([np.full_like(t, -4.0), np.zeros_like(t)])  # constant channels
    result = tracking_error(t, desired + 0.2, desired)
    assert result.max_percent[0] == pytest.approx(5.0) and result.rms_percent[0] == pytest.approx(5.0)
    assert np.isnan(result.max_percent[1]) and np.isnan(result.rms_percent[1])  # undefined, no warning
    assert result.max_abs[1] == pytest.approx(0.2)


def test_explicit_scale_scalar_or_per_channel_and_scalar_desired() -> None:
    t = uniform(1.0, 0.01)
    actual = np.column_stack([np.full_like(t, 1.1), np.full_like(t, 0.8)])
    np.testing.assert_allclose(tracking_error(t, actual, 1.0, scale=2.0).max_percent, [5.0, 10.0])
    np.testing.assert_allclose(tracking_error(t, actual, 1.0, scale=[1.0, 4.0]).max_percent, [10.0, 5.0])
    one_d = tracking_error(t, actual[:, 0], 1.0)
    assert one_d.max_abs.shape == (1,) and one_d.max_percent == pytest.approx([10.0])


def test_force_error_is_relative_to_the_set_point() -> None:
    # 5 N set-point; after contact at t = 0.5 s the force oscillates 0.5 N around it (whole periods).
    t = uniform(1.5, 1e-3)
    force = np.where(t < 0.5, 0.0, 5.0 + 0.5 * np.sin(2 * np.pi * 2.0 * (t - 0.5)))
    result = force_error(t, force, 5.0, start_time=0.5)
    assert result.max_percent[0] == pytest.approx(10.0, rel=1e-12)
    assert result.rms_percent[0] == pytest.approx(10.0 / np.sqrt(2.0), rel=1e-12)
    assert result.final_abs[0] == pytest.approx(0.0, abs=1e-12)
    assert np.isnan(force_error(t, force, 0.0).max_percent[0])


# --- chattering_index ----------------------------------------------------------------------------------------------


def test_chattering_index_of_a_sine_is_4_a_f() -> None:
    amplitude, frequency = 0.7, 2.5
    t = uniform(2.0, 1e-3)  # 5 whole periods; the extrema at (2 j + 1) / 10 s are samples
    index = chattering_index(t, amplitude * np.sin(2 * np.pi * frequency * t))
    assert index == pytest.approx([4 * amplitude * frequency], rel=1e-12)


def test_chattering_index_of_bang_bang_switching_every_sample_is_2_k_over_h() -> None:
    k, h = 3.0, 1e-3
    t = uniform(1.0, h)
    smooth = 0.5 * np.sin(2 * np.pi * 2.5 * t)
    bang_bang = k * (-1.0) ** np.arange(t.size)
    index = chattering_index(t, np.column_stack([bang_bang, smooth]))
    np.testing.assert_allclose(index, [2 * k / h, 4 * 0.5 * 2.5], rtol=1e-12)
    # Chattering only after t = 0.6 s: the start time isolates it.
    late = np.where(t >= 0.6, bang_bang, 0.0)
    assert chattering_index(t, late, start_time=0.6) == pytest.approx([2 * k / h], rel=1e-9)


# --- high_frequency_power ----------------------------------------------------------------------------------------


def test_high_frequency_power_of_a_two_tone_mixture() -> None:
    # Power splits as the squared amplitudes; Welch's Hann-windowed 0.256 s segments hold 1.28 periods of the
    # 5 Hz tone, so its estimated power depends slightly on phase (measured ~2e-4): tolerance 1e-3.
    t = uniform(2.0, 1e-3)[:-1]
    low, high = np.sin(2 * np.pi * 5.0 * t), np.sin(2 * np.pi * 200.0 * t)
    u = np.column_stack([low + high, low + 0.5 * high, low, 3.0 + high, np.full_like(t, 7.0)])
    fraction = high_frequency_power(t, u, cutoff=50.0)
    np.testing.assert_allclose(fraction, [0.5, 0.2, 0.0, 1.0, 0.0], atol=1e-3)
    assert np.all((fraction >= 0.0) & (fraction <= 1.0))
    late = high_frequency_power(t, np.where(t >= 1.0, high, low), cutoff=50.0, start_time=1.0)
    assert late == pytest.approx([1.0], abs=1e-3)


def test_high_frequency_power_needs_uniform_sampling_and_a_cutoff_below_nyquist() -> None:
    t = uniform(1.0, 1e-3)
    u = np.sin(2 * np.pi * 5.0 * t)
    jittered = t.copy()
    jittered[10] += 1e-5
    with pytest.raises(InputError, match="uniformly sampled"):
        high_frequency_power(jittered, u, cutoff=50.0)
    with pytest.raises(InputError, match="Nyquist"):
        high_frequency_power(t, u, cutoff=500.0)
    with pytest.raises(InputError, match="cutoff"):
        high_frequency_power(t, u, cutoff=0.0)


# --- input validation ------------------------------------------------------------------------------------------


def _metrics(t: object, signal: object) -> list:
    return [
        lambda: tracking_error(t, signal, signal),
        lambda: force_error(t, signal, signal),
        lambda: step_response(t, signal, target=10.0),
        lambda: control_effort(t, signal),
        lambda: chattering_index(t, signal),
        lambda: high_frequency_power(t, signal, cutoff=1.0),
    ]


@pytest.mark.parametrize(
    ("t", "signal", "message"),
    [
        ([0.0, 0.1, np.nan], [1.0, 2.0, 3.0], r"`t` must be finite"),
        ([0.0, 0.1, 0.2], [1.0, np.inf, 3.0], r"must be finite"),
        ([0.0, 0.1, 0.2], [1.0, 2.0], r"must have shape \(3,\) or \(3, k\).*got shape \(2,\)"),
        ([0.0, 0.1, 0.2], np.ones((3, 2, 1)), r"got shape \(3, 2, 1\)"),
        ([0.0, 0.1, 0.2], np.ones((3, 0)), r"k >= 1.*got shape \(3, 0\)"),
        ([0.0, 0.1, 0.1], [1.0, 2.0, 3.0], r"`t` must be strictly increasing, got t\[1\] = 0.1 then t\[2\] = 0.1"),
        ([0.0, 0.2, 0.1], [1.0, 2.0, 3.0], r"strictly increasing"),
        ([], [], r"`t` must hold at least 2 sample times, got shape \(0,\)"),
        ([[0.0, 0.1]], [1.0, 2.0], r"`t` must have shape a 1-D array"),
        ([0.0, 0.1], ["a", "b"], r"must be numeric"),
    ],
)
def test_bad_inputs_raise_input_error_naming_the_argument(t: object, signal: object, message: str) -> None:
    for call in _metrics(t, signal):
        with pytest.raises(InputError, match=message):
            call()


def test_mismatched_reference_and_parameters_raise() -> None:
    t = uniform(1.0, 0.01)
    two = np.ones((t.size, 2))
    with pytest.raises(InputError, match=r"`desired` must have as many channels"):
        tracking_error(t, two, np.ones((t.size, 3)))
    with pytest.raises(InputError, match=r"`desired` must have shape \(101,\)"):
        tracking_error(t, two, np.ones(50))
    with pytest.raises(InputError, match=r"`desired` must be finite"):
        force_error(t, two, np.full((t.size, 2), np.nan))
    with pytest.raises(InputError, match=r"`scale` must be a scalar or have shape \(2,\)"):
        tracking_error(t, two, two, scale=[1.0, 2.0, 3.0])
    with pytest.raises(InputError, match=r"`scale` must be > 0"):
        tracking_error(t, two, two, scale=[1.0, 0.0])
    with pytest.raises(InputError, match=r"`target` must be a scalar or have shape \(2,\)"):
        step_response(t, two, target=[1.0, 2.0, 3.0])
    with pytest.raises(InputError, match=r"`start_time` = 2.0 s leaves 0 sample"):
        chattering_index(t, two, start_time=2.0)
    with pytest.raises(InputError, match=r"`start_time` must be a finite number"):
        tracking_error(t, two, two, start_time=np.nan)


def test_importing_metrics_does_not_import_scipy() -> None:
    code = "import sys, bhgrasp.metrics; assert not any(m.startswith('scipy') for m in sys.modules)"
    subprocess.run([sys.executable, "-c", code], check=True)
