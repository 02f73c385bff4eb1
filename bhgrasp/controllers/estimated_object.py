"""A controller that reads the held object through a :class:`~bhgrasp.controllers.object_estimator.HeldObjectEstimator`.

``EstimatedObject(controller, estimator)`` stands where ``controller`` stood: each call it feeds the sensed state to
the estimator and hands ``controller`` the same state with the object's pose and twist replaced by the estimate
(the encoders, contacts and forces untouched).  Its log is the controller's, plus ``object_estimate`` (the
estimated position [m] and orientation's rotation vector log(R) [rad], world), ``object_estimate_sigma`` (its
standard deviations, position [m] then rotation [rad]) and ``object_held`` (1 while the rigid-grasp model carries
the estimate).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace
from typing import Any

import numpy as np
import pinocchio as pin

from bhgrasp.controllers.base import Controller
from bhgrasp.controllers.object_estimator import HeldObjectEstimator
from bhgrasp.data import State
from bhgrasp.errors import InputError


class EstimatedObject(Controller):
    """Wrap ``controller`` so that it sees the estimator's object pose and twist instead of the tracker's."""

    def __init__(self, controller: Callable[[float, State], Any], estimator: HeldObjectEstimator) -> None:
        super().__init__()
        if not isinstance(estimator, HeldObjectEstimator):
            raise InputError(f"`estimator` must be a HeldObjectEstimator, got {type(estimator).__name__}")
        self.controller, self.estimator = controller, estimator
        self._restart = True
        self.log = getattr(controller, "log", self.log)

    def reset(self, state: State) -> None:
        """Reset the controller with ``state``; the estimator restarts from the first *sensed* state it is given.

        (A simulator resets its controller with the true start state; the estimator must not start from it.)
        """
        self._restart = True
        if hasattr(self.controller, "reset"):
            self.controller.reset(state)

    def __call__(self, t: float, state: State) -> np.ndarray:
        """The controller's torques for ``state`` with the object's pose and twist estimated."""
        if self._restart:
            self.estimator.reset(state)
            self._restart = False
        self.estimator.step(state)
        estimated = self._estimated(state)
        pose = self.estimator.pose
        self.log["object_estimate"] = np.concatenate((pose.translation, pin.log3(pose.rotation)))
        self.log["object_estimate_sigma"] = np.sqrt(np.diag(self.estimator.covariance))
        self.log["object_held"] = np.array(float(self.estimator.holding))
        return self.controller(t, estimated)

    def _estimated(self, state: State) -> State:
        index = self.estimator.index
        poses = list(state.object_poses)
        poses[index] = self.estimator.pose
        twists = np.array(state.object_twists, dtype=float)
        twists[index] = self.estimator.twist
        return replace(state, object_poses=tuple(poses), object_twists=twists, object_time=None)  # estimated at t


__all__ = ["EstimatedObject"]
