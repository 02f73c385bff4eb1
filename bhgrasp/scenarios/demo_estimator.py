"""The object estimator the grasp demo builds for ``estimator="hand"`` (:mod:`bhgrasp.controllers.object_estimator`)."""

from __future__ import annotations

from typing import Any

from bhgrasp._validation import as_vector
from bhgrasp.controllers.object_estimator import EstimatorSettings, HeldObjectEstimator
from bhgrasp.scenarios.box_grasp import BoxGrasp


def demo_estimator(setup: BoxGrasp, pose_noise: Any) -> HeldObjectEstimator:
    """The demo's object estimator, its tracker's noise ``pose_noise`` (the default's for a zero or absent part)."""
    default = EstimatorSettings().tracker
    sigma = default if pose_noise is None else as_vector(pose_noise, "pose_noise", 2)
    tracker = tuple(float(value) if value > 0.0 else fallback for value, fallback in zip(sigma, default))
    body = setup.simulator.scene.object_names[0]
    return HeldObjectEstimator(setup.hand, EstimatorSettings(tracker=tracker), body=body)


__all__ = ["demo_estimator"]
