"""The ideal object loop: a free rigid body receives exactly the wrench the SMC-adaptive law commands.

This is the setting of the thesis' Lyapunov argument (5.61)-(5.65) with Delta F_o = 0 (no fingers, no contact
compliance): what it proves there must hold here to integration accuracy, which makes the loop a test of the law's
object level (regressor, Coriolis form, the adaptation's sign and gains, the composite term) independent of the hand.

Dynamics at the COM (world): m v_dot = F + m g, d/dt (I_w omega) = tau, R_dot = skew(omega) R.  RK4 steps of ``dt``
hold the commanded wrench (zero-order hold, as the simulator holds torques); the composite law measures the wrench of
the step that just ended, as a force sensor would.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from bhgrasp._validation import as_positive
from bhgrasp.controllers.adaptive_grasp import SMCAdaptiveGrasp
from bhgrasp.controllers.grasp_lyapunov import object_lyapunov
from bhgrasp.controllers.object_regressors import object_parameters
from bhgrasp.data import State
from bhgrasp.errors import InputError
from bhgrasp.model.objects import RigidObject


@dataclass
class ObjectLoopRun:
    """Samples of an ideal-loop run (N cycles).

    Times [s], the object's pose and twist, the law's s_o, estimate, P^-1, commanded wrench, V_o's two terms
    (:func:`~bhgrasp.controllers.grasp_lyapunov.object_lyapunov`), and 1/2 |W Delta sigma|_Q^2 [W] of the composite
    law (0 without it, or before it identifies).
    """

    t: np.ndarray
    rotation: np.ndarray
    position: np.ndarray
    twist: np.ndarray
    sliding: np.ndarray
    estimate: np.ndarray
    information: np.ndarray
    wrench: np.ndarray
    kinetic: np.ndarray
    parameter_term: np.ndarray
    prediction_power: np.ndarray

    @property
    def lyapunov(self) -> np.ndarray:
        """V_o (N,) [J]: 1/2 s_o^T M_o s_o + 1/2 Delta sigma^T P^-1 Delta sigma."""
        return self.kinetic + self.parameter_term

    def dissipation(self, k_o: np.ndarray) -> np.ndarray:
        """s_o^T k_o s_o (N,) [W]: V_o's rate in this loop for the thesis' law (5.52)."""
        return np.einsum("ij,j,ij->i", self.sliding, k_o, self.sliding)


def _derivative(state: tuple, force: np.ndarray, torque: np.ndarray, body: RigidObject, gravity: np.ndarray) -> tuple:
    """d/dt (x, v, R, h): the Newton-Euler equations with h = I_w omega the angular momentum (world)."""
    _, velocity, rotation, momentum = state
    omega = rotation @ np.linalg.solve(body.inertia, rotation.T @ momentum)
    return velocity, force / body.mass + gravity, pin.skew(omega) @ rotation, torque


def _advance(state: tuple, rates: tuple, h: float) -> tuple:
    return tuple(value + h * rate for value, rate in zip(state, rates))


def ideal_object_loop(
    law: SMCAdaptiveGrasp, body: RigidObject, start: pin.SE3, duration: float, dt: float = 1e-4
) -> ObjectLoopRun:
    """Run ``law``'s object level (:meth:`~SMCAdaptiveGrasp.object_law`) on ``body`` from ``start`` at rest.

    Args:
        law: The controller; its ``reference`` (object pose path) must be set.  Its estimate starts from its nominal
            object; the true object is ``body``.
        body: The true object (mass [kg], body inertia about the COM [kg m^2]).
        start: Initial pose (world <- body).
        duration: Simulated time [s].
        dt: Step [s] (also the law's cycle).
    """
    if law.reference is None:
        raise InputError("the ideal loop needs the law's `reference` (an object pose path) set")
    dt, duration = as_positive(dt, "dt"), as_positive(duration, "duration")
    gravity, k = law.gravity, round(duration / dt)
    state = (start.translation.copy(), np.zeros(3), start.rotation.copy(), np.zeros(3))
    q0, v0 = law.nominal.neutral(), np.zeros(law.nominal.nv)
    columns: dict[str, list] = {name: [] for name in ObjectLoopRun.__dataclass_fields__}
    applied, previous = np.zeros(6), None
    for step in range(k + 1):
        t = step * dt
        position, velocity, rotation, momentum = state
        omega = rotation @ np.linalg.solve(body.inertia, rotation.T @ momentum)
        twist = np.concatenate((velocity, omega))
        sensed = State(t, q0, v0, object_poses=(pin.SE3(rotation, position),), object_twists=twist[None])
        cycle = 0.0 if previous is None else t - previous
        wrench, regressor, sliding, _, _ = law.object_law(t, cycle, sensed)
        power = 0.0
        if law.identification is not None:
            error = np.array(law.object_estimate) - object_parameters(body.mass, body.inertia)  # before the update
            law.identify(cycle, sensed, regressor, sliding, measured=(applied, True))
            filtered = law.identification.filtered_regressor
            if law.identification.identifying:
                power = 0.5 * np.sum(law.identification.weights * (filtered @ error) ** 2)
        previous = t
        information = law.parameter_information()
        kinetic, parameter = object_lyapunov(
            body.mass, body.inertia, rotation, sliding, law.object_estimate, information
        )
        for name, value in (
            ("t", t),
            ("rotation", rotation),
            ("position", position),
            ("twist", twist),
            ("sliding", sliding),
            ("estimate", np.array(law.object_estimate)),
            ("information", information),
            ("wrench", wrench),
            ("kinetic", kinetic),
            ("parameter_term", parameter),
            ("prediction_power", power),
        ):
            columns[name].append(np.array(value, dtype=float))
        force, torque = wrench[:3], wrench[3:]
        k1 = _derivative(state, force, torque, body, gravity)
        k2 = _derivative(_advance(state, k1, dt / 2), force, torque, body, gravity)
        k3 = _derivative(_advance(state, k2, dt / 2), force, torque, body, gravity)
        k4 = _derivative(_advance(state, k3, dt), force, torque, body, gravity)
        rates = tuple((a + 2 * b + 2 * c + d) / 6 for a, b, c, d in zip(k1, k2, k3, k4))
        state = _advance(state, rates, dt)
        u, _, vt = np.linalg.svd(state[2])  # back onto SO(3)
        state = (state[0], state[1], u @ vt, state[3])
        applied = wrench
    return ObjectLoopRun(**{name: np.array(values) for name, values in columns.items()})


__all__ = ["ObjectLoopRun", "ideal_object_loop"]
