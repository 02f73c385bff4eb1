"""Performance metrics of a controlled run: tracking and force error, step response, control effort, chattering.

Plain functions on numpy arrays, independent of the simulator.  Every function takes the sample times ``t``
(shape (N,), strictly increasing, seconds) and one or more signals of shape (N,) or (N, k): a 1-D signal is one
channel, and results are per channel, always of shape (k,) (k = 1 for a 1-D signal).  Time averages use the
trapezoidal rule over time, so non-uniformly sampled records are weighted correctly.  Results are in the units
of the signal unless stated otherwise.  One module per family: :mod:`~bhgrasp.metrics.tracking`,
:mod:`~bhgrasp.metrics.step`, :mod:`~bhgrasp.metrics.effort`, on the checked signals of :mod:`~bhgrasp.metrics.signals`.
"""

from bhgrasp.metrics.effort import chattering_index, control_effort, high_frequency_power
from bhgrasp.metrics.step import StepResponse, step_response
from bhgrasp.metrics.tracking import TrackingError, force_error, tracking_error

__all__ = [
    "StepResponse",
    "TrackingError",
    "chattering_index",
    "control_effort",
    "force_error",
    "high_frequency_power",
    "step_response",
    "tracking_error",
]
