"""Chapter 4's laws as the thesis prints them, and the closed-form steady force that explains their error.

:func:`as_printed` turns an impedance law into thesis (4.20)-(4.26) as printed (no feed-forward J^T f_d n, the
filter's acceleration passed on); :func:`steady_force` is the balance at rest of impedance, environment and the
inner loop's stiffness (:func:`inner_loop_stiffness`), shifted by a static friction force's deflection
(:func:`friction_offset`); ``why_printed`` and :data:`PRINTED_NOTE` are the report's account of it.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from bhgrasp.controllers.impedance import ForceImpedance, ImpedanceLaw
from bhgrasp.controllers.workspace import workspace_dynamics
from bhgrasp.data import Trajectory
from bhgrasp.scenarios.finger_press import Setup

# Gamma = diag(gamma_1, gamma_2) of the printed gradient law (4.41) in our runs, [1/(m^2 s)] and [1/s]: gamma_2 dt =
# 0.1 keeps the explicit update stable at dt = 1 ms, gamma_1 = gamma_2 / (1 cm)^2 moves k_e as fast for a 1 cm
# lever.  (The thesis' gamma_1 = 0.0018, gamma_2 = 0.001 of F3 belong to its coordinates: here they leave the
# estimates where they start.)
PRINTED_GAMMA = (1e6, 100.0)


def as_printed(law: ImpedanceLaw) -> ImpedanceLaw:
    """``law`` as thesis (4.20)-(4.26) print it: the filter's acceleration passed on, X_c'' = X_d'' - dx''.

    Run it in an :class:`ImpedanceController` with ``feedforward=False`` (the thesis has no J^T f_d term).
    """
    law.feed_acceleration = True
    return law


def inner_loop_stiffness(setup: Setup, q: Any, kp: float) -> float:
    """k_p = Kp m_x(n) [N/m]: the static stiffness of the fingertip computed-torque loop along the normal.

    At rest under a force F on the fingertip the loop settles where Kp M_x (x_c - x) = F (task coordinates of
    :func:`~bhgrasp.controllers.workspace.workspace_dynamics`), so along n it is a spring of stiffness
    Kp / (n^T B M_x^-1 B^T n), i.e. Kp times the fingertip's effective mass along n.
    """
    dynamics = workspace_dynamics(setup.hand, q, np.zeros(setup.hand.nv), setup.finger)
    along = dynamics.basis.T @ setup.normal
    return float(kp / (along @ np.linalg.solve(dynamics.mass, along)))


def steady_force(
    desired: float, impedance: float, inner: float, estimate: float, feedforward: bool = False, offset: float = 0.0
) -> float:
    """Closed-form steady normal force [N] of (adaptive) FIM around a compliant inner loop.

    At rest along n: the impedance filter gives K_I dx = f - f_d; the reference is x_d = x^_e + f_d / k^_e
    ((4.26), (4.33)) with estimates consistent at the operating point, k^_e (x - x^_e) = f (true values for FIM,
    the converged estimates for adaptive FIM); the inner loop leaves x = x_c - (f - f_ff) / k_p - offset, with f_ff
    = f_d under the feed-forward J^T f_d n, else 0; and x_c = x_d - dx.  Eliminating x, x_c, dx:

        (f_d - f) (1/k^_e + 1/K_I) = (f - f_ff) / k_p + offset.

    The thesis' zero error (4.25) is the limit k_p -> infinity (X = X_c); the feed-forward gives f = f_d for any
    k_p when offset = 0.

    Args:
        desired: f_d [N].  impedance: K_I [N/m].  inner: k_p [N/m] (:func:`inner_loop_stiffness`).
        estimate: k^_e [N/m] (k_e for FIM).  feedforward: Whether J^T f_d n is added.
        offset: Extra inner-loop deflection [m] along n, e.g. from a static friction force (:func:`friction_offset`).
    """
    compliance = 1.0 / estimate + 1.0 / impedance
    forward = desired if feedforward else 0.0
    return float((desired * compliance + forward / inner - offset) / (compliance + 1.0 / inner))


def friction_offset(setup: Setup, q: Any, reaction: np.ndarray, force: float, kp: float) -> float:
    """Inner-loop deflection [m] along n caused by the contact beyond a normal force ``force`` through the tip centre.

    ``reaction`` is J_c^T F on the hand (the controller's logged ``reaction_torque``, nv); what a pure normal force
    f n would give, -J^T f n, is removed, and the rest (a static friction force along the face and its moment about
    the tip centre) deflects the inner loop by -B M_x^-1 J_t^-T tau / Kp.
    """
    hand, finger = setup.hand, setup.finger
    index = hand.finger_indices(finger)
    dynamics = workspace_dynamics(hand, q, np.zeros(hand.nv), finger)
    torque = np.asarray(reaction)[index] + hand.fingertip_jacobian(q, finger)[:, index].T @ (force * setup.normal)
    deflection = -dynamics.basis @ np.linalg.solve(dynamics.mass, np.linalg.solve(dynamics.jacobian.T, torque))
    return float(setup.normal @ deflection / kp)


def closed_form_force(
    setup: Setup, traj: Trajectory, force: np.ndarray, law: ForceImpedance, kp: float, feedforward: bool
) -> tuple[float, float, float]:
    """k_p, and the closed-form steady force of a finished run of ``law``: frictionless, with the measured friction."""
    window = slice(len(traj) - max(2, len(traj) // 20), None)  # the samples force_metrics' 'final' averages
    q = traj.q[-1]
    inner = inner_loop_stiffness(setup, q, kp)
    offset = friction_offset(
        setup, q, np.mean(traj.log["reaction_torque"][window], axis=0), float(np.mean(force[window])), kp
    )
    args = (law.force, law.stiffness, inner, law.environment_stiffness, feedforward)
    return inner, steady_force(*args), steady_force(*args, offset=offset)


CLOSED_FORM_HEADER = ["closed form [N]: frictionless", "closed form [N]: + measured friction"]
PRINTED_NOTE = (
    "'as printed': the thesis' law without our feed-forward J^T f_d n, with the filter's acceleration passed on"
    " (X_c'' = X_d'' - dx'', (4.20)-(4.21)); its adaptive form is the gradient law (4.41) (which our 'gradient'"
    " estimator implements exactly, x measured from the initial surface estimate) with a constant f_d and Gamma ="
    f" diag({PRINTED_GAMMA[0]:g} 1/(m^2 s), {PRINTED_GAMMA[1]:g} 1/s).  Read with its typos corrected: (4.22) is"
    " F_e - F_d = M_I dX'' + B_I dX' + K_I dX (printed F_d - F_e = M_I dX' + B_I dX' - K_I dX, which contradicts"
    " (4.24)); (4.24) writes m, b, k for M_I, B_I, K_I and e for e_f; (4.25) has a stray k, e_ss = K_I / (K_I +"
    " k_e) (f_d + k_e x_e - k_e x_d); (4.38)-(4.39) use f^ - f_d where (4.40)-(4.41) use f^ - f; (4.41) writes"
    " gamma_e for gamma_2."
)


def why_printed(
    kp: float, gains: float, impedance: float, k_e: float, desired: float, predicted: float, final: float
) -> str:
    """The report's explanation of the printed law's steady force error, with one run's numbers."""
    lag = (desired - final) * (1.0 / k_e + 1.0 / impedance)  # n . (x_c - x) at rest: filter + environment
    return (
        f"Why the printed law misses f_d: (4.22)-(4.26) assume the inner loop is exact, X = X_c.  Computed torque"
        f" without a force term holds the fingertip against a static contact force only through its PD action, a"
        f" spring k_p = Kp m_x(n) = {gains:g} x {kp / gains:.4f} kg = {kp:.2f} N/m along n (m_x(n): the fingertip's"
        f" effective mass along the normal, at the final pose).  In series with the environment and the impedance"
        f" the balance at rest gives f = f_d (1/k^_e + 1/K_I) / (1/k^_e + 1/K_I + 1/k_p) (:func:`steady_force`;"
        f" k^_e = k_e for FIM, the converged estimate for adaptive FIM; (4.25)'s zero error is the limit k_p ->"
        f" infinity): K_I = {impedance:g} N/m, k_e = {k_e:.0f} N/m give {predicted:.3f} N for {desired:g} N; the"
        f" run settles at {final:.3f} N with the commanded point X_c {100 * lag:.1f} cm beyond the fingertip along n."
        "  With the feed-forward J^T f_d n the inner loop has no error at f = f_d, and the same balance gives f_d."
        "  Static friction on the face (mu = 0.5) holds a tangential force whose inner-loop deflection along n"
        " (through M_x^-1 and the contact point's lever about the tip centre) shifts the balance; the last column"
        " adds it, computed from the measured contact torques (:func:`friction_offset`); it agrees with the final force"
        " to a few per cent, exactly where the run has come to rest (the stiffest runs still creep at the end)."
    )


__all__ = [
    "CLOSED_FORM_HEADER",
    "PRINTED_GAMMA",
    "PRINTED_NOTE",
    "as_printed",
    "closed_form_force",
    "friction_offset",
    "inner_loop_stiffness",
    "steady_force",
    "why_printed",
]
