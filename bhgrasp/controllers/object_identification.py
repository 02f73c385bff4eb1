"""Composite adaptation of the object's parameters: the sensed contact wrench joins the tracking error.

The thesis' law (5.52) learns sigma_o = (m, I_xx, I_xy, I_xz, I_yy, I_yz, I_zz) from the object's sliding error
s_o alone.  Its closed loop (5.61) holds a term Delta F_o, the wrench the contacts fail to exert: whatever the
fingers do not deliver is learnt as mass or inertia (a 0.6 kg box told 0.3 kg wanders +-15 % while it turns, and its
inertia never settles).  Composite adaptation (Slotine & Li, "Composite adaptive control of robot manipulators",
Automatica 25(4), 1989; Applied Nonlinear Control, 1991, sec. 8.8) adds the prediction error of the wrench the hand
*measures* on the object, which does not depend on how well the forces are tracked.

Newton-Euler at the COM (world): F = d/dt(m v) - m g and tau = d/dt(I_w omega), I_w = R I R^T (their sum is
I_w alpha + omega x I_w omega).  Over a control step the momentum H sigma_o (H_k = R B_k R^T omega, B_k the inertia
basis) changes by the wrench the step held, which the sensed state after it reports.  Both sides pass through the
same first-order filter of rate lambda (started at zero), so that the filtered wrench y is exactly W sigma_o, with a
regressor of velocities only (no acceleration, no differentiated noise beyond the filter's):

    W = L[(H_k - H_k-1) / dt] - [g_f, 0; 0, 0],     y = L[w],    w = sum over the hand's contacts on the object of
    (f, (p - c) x f),   g_f = L[g].

With the prediction error e = W sigma_hat - y and Q = diag(I / force_sigma^2, I / torque_sigma^2) (the wrench's
assumed noise),

    sigma_hat_dot = -P (Y_o^T s_o + W^T Q e),      d/dt P^-1 = W^T Q W,      P(0) = Gamma_o,

so that V = 1/2 s_o^T M_o s_o + 1/2 Delta sigma^T P^-1 Delta sigma has V_dot = -s_o^T k_o s_o - 1/2 |W Delta
sigma|_Q^2 <= 0 when the object receives the commanded wrench (``tests/test_adaptation.py`` integrates that loop).
Steps are recursive least squares (P^-1 += dt W^T Q W first, then the update with the new P): stable at any dt.
Parameters whose Gamma_o rate is 0 stay fixed.

The measured wrench is the object's whole wrench only while the hand is all that touches it: a contact of the object
with anything else (its support) pauses the prediction term, and the filters restart when it is free again.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from bhgrasp._validation import as_positive
from bhgrasp.controllers.object_regressors import momentum_regressor
from bhgrasp.data import State
from bhgrasp.model.hand import Hand


def contact_wrench(state: State, frames: frozenset[str], held: str) -> tuple[np.ndarray, bool]:
    """The wrench (force [N], moment about the COM [N m], world) the hand's contacts exert on object ``held``.

    Also whether the hand is all that touches it (no contact of ``held`` with a body other than a hand frame).
    """
    com = state.object_poses[0].translation
    wrench, free = np.zeros(6), True
    for (a, b), point, force in zip(state.contact_bodies, state.contact_points, state.contact_forces):
        if b != held:
            continue
        if a not in frames:
            free = False
            continue
        wrench[:3] += force
        wrench[3:] += np.cross(point - com, force)
    return wrench, free


class ObjectIdentification:
    """Composite adaptation (module docstring) of an :class:`SMCAdaptiveGrasp`'s object estimate.

    ``log()`` gives ``identifying`` (1 while the prediction term runs), ``prediction_error`` (e, (6,), [N, N m]) and
    ``parameter_information`` (P^-1, (7, 7)).
    """

    def __init__(self, filter_rate: float = 10.0, force_sigma: float = 0.1, torque_sigma: float = 0.002) -> None:
        """Set up the estimator.

        Args:
            filter_rate: lambda [1/s] of the filter L.
            force_sigma: Assumed noise [N] of the measured contact force on the object (weights Q).
            torque_sigma: Assumed noise [N m] of the measured moment about its COM (weights Q).
        """
        self.filter_rate = as_positive(filter_rate, "filter_rate")
        self.force_sigma = as_positive(force_sigma, "force_sigma")
        self.torque_sigma = as_positive(torque_sigma, "torque_sigma")
        self._weights = np.repeat([self.force_sigma**-2, self.torque_sigma**-2], 3)
        self._frames: frozenset[str] = frozenset()
        self._held: str | None = None
        self.information: np.ndarray | None = None  # P^-1 over the learnt parameters
        self._clear()

    def bind(self, hand: Hand, rates: np.ndarray) -> None:
        """Attach to a controller: its hand's frames (contacts on them are measured) and Gamma_o (P(0))."""
        self._frames = frozenset(frame.name for frame in hand.model.frames)
        self._free = np.asarray(rates, dtype=float) > 0.0
        self._initial_information = np.diag(1.0 / np.asarray(rates, dtype=float)[self._free])
        self.reset()

    def reset(self) -> None:
        """Forget the data: P back to Gamma_o, filters cleared."""
        self.information = self._initial_information.copy()
        self._held = None
        self._clear()

    def _clear(self) -> None:
        self._previous: np.ndarray | None = None  # H of the last cycle
        self._rate_f = np.zeros((6, 7))
        self._wrench_f, self._gravity_f = np.zeros(6), np.zeros(3)
        self.filtered_regressor: np.ndarray | None = None  # W of the last cycle that identified
        self.identifying = False
        self.prediction_error = np.zeros(6)

    def update(
        self, estimate: np.ndarray, dt: float, state: State, regressor: np.ndarray, sliding: np.ndarray, gravity: Any
    ) -> np.ndarray:
        """The estimate after a grasp cycle of ``dt`` [s], from the sensed state: :meth:`step` with its wrench."""
        if self._held is None:
            self._held = self._object_name(state)
        wrench, free = contact_wrench(state, self._frames, self._held)
        pose = state.object_poses[0]
        return self.step(estimate, dt, pose.rotation, state.object_twists[0], wrench, free, regressor, sliding, gravity)

    def step(
        self,
        estimate: np.ndarray,
        dt: float,
        rotation: Any,
        twist: Any,
        wrench: Any,
        free: bool,
        regressor: np.ndarray,
        sliding: np.ndarray,
        gravity: Any,
    ) -> np.ndarray:
        """The estimate after one cycle: -P (Y_o^T s_o + W^T Q e) dt, as recursive least squares.

        Args:
            estimate: sigma_hat (7,) before the cycle.
            dt: Cycle time [s] (0 on the first grasp cycle: only the filters start).
            rotation, twist: The object's orientation (world <- body) and twist (v [m/s], omega [rad/s], world).
            wrench: Measured wrench on the object (force [N], moment about the COM [N m], world).
            free: Whether ``wrench`` is all the object receives (besides gravity).
            regressor: Y_o (6, 7) of the cycle; sliding: s_o (6,).
            gravity: g (3,) [m/s^2], world.
        """
        twist, wrench = np.asarray(twist, dtype=float), np.asarray(wrench, dtype=float)
        momentum = momentum_regressor(rotation, twist)
        step = np.zeros(7)
        step[self._free] = regressor[:, self._free].T @ sliding
        self.identifying = free and self._previous is not None and dt > 0.0
        if not free:  # the support takes a share of the wrench: pause, and restart the filters when free again
            self._clear()
        elif not self.identifying:  # the first free instant (or a repeated one): only remember the momentum
            self._previous = momentum
        else:
            alpha = 1.0 - np.exp(-self.filter_rate * dt)
            self._rate_f += alpha * ((momentum - self._previous) / dt - self._rate_f)
            self._previous = momentum
            self._wrench_f += alpha * (wrench - self._wrench_f)
            self._gravity_f += alpha * (np.asarray(gravity, dtype=float) - self._gravity_f)
            filtered = self._rate_f.copy()
            filtered[:3, 0] -= self._gravity_f
            self.filtered_regressor = filtered
            self.prediction_error = filtered @ estimate - self._wrench_f
            weighted = filtered[:, self._free] * self._weights[:, None]
            self.information += dt * (filtered[:, self._free].T @ weighted)
            step[self._free] += weighted.T @ self.prediction_error
        updated = np.array(estimate, dtype=float)
        updated[self._free] -= dt * np.linalg.solve(self.information, step[self._free])
        return updated

    def _object_name(self, state: State) -> str | None:
        """The object the hand touches: body b of the first contact on a hand frame."""
        for a, b in state.contact_bodies:
            if a in self._frames:
                return b
        return None

    @property
    def weights(self) -> np.ndarray:
        """diag(Q) (6,): 1 / force_sigma^2 [1/N^2] (x3), 1 / torque_sigma^2 [1/(N m)^2] (x3)."""
        return self._weights.copy()

    def information_matrix(self) -> np.ndarray:
        """P^-1 (7, 7): the information on sigma_o (zero rows and columns for the parameters held fixed)."""
        matrix = np.zeros((7, 7))
        matrix[np.ix_(self._free, self._free)] = self.information
        return matrix

    def log(self) -> dict[str, np.ndarray]:
        """``identifying``, ``prediction_error`` and ``parameter_information`` (P^-1) of the last cycle."""
        return {
            "identifying": np.array(float(self.identifying)),
            "prediction_error": self.prediction_error.copy(),
            "parameter_information": self.information_matrix(),
        }


__all__ = ["ObjectIdentification", "contact_wrench"]
