"""The terms of the fingertip workspace dynamics (thesis (2.35)-(2.37)) per finger, and the fingertip computed torque.

What :mod:`bhgrasp.controllers.workspace` builds on: the compiled kernel ``_core.FingerDynamics``
(``src/workspace.cpp``: the joint-space terms tip position, J, M_f, G_f, C q_dot, J_dot q_dot; the SVD, inverse and
products that turn them into B, J_t, M_x, C_x, G_x; the computed torque) on the default engine (:mod:`bhgrasp._native`),
and its Python twins :func:`_finger_terms_python` (equal to the bit), :func:`_workspace_dynamics` and
:func:`_fingertip_torque` (NumPy: equal to round-off, tests/test_workspace_kernels.py).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from bhgrasp._native import kernel
from bhgrasp.errors import InputError
from bhgrasp.model.hand import Hand


@dataclass(frozen=True)
class _Workspace:
    """One finger's workspace terms and fingertip, world frame: the Python twin's form of ``_core.WorkspaceTerms``.

    Attributes: position [m] (3,) and jacobian (3, nv) of the fingertip; basis, task_jacobian, mass, coriolis and
    gravity as :class:`WorkspaceDynamics`' basis, jacobian, mass, coriolis and gravity; singular (always False here:
    the twin raises instead).  :meth:`torque` is the fingertip computed torque from them.
    """

    position: np.ndarray
    jacobian: np.ndarray
    basis: np.ndarray
    task_jacobian: np.ndarray
    mass: np.ndarray
    coriolis: np.ndarray
    gravity: np.ndarray
    singular: bool = False

    def torque(self, *args: Any) -> np.ndarray:
        """:func:`_fingertip_torque` of these terms (as ``_core.WorkspaceTerms.torque``)."""
        return _fingertip_torque(self, *args)


def workspace_terms(hand: Hand, q: np.ndarray, v: np.ndarray, finger: str, index: np.ndarray, number: int) -> Any:
    """The workspace terms of ``finger`` at validated (q [rad], v [rad/s]), world frame: a :class:`_Workspace`.

    ``index`` are the finger's joint indices and ``number`` its place in ``hand.fingers``.  From the hand's
    :func:`_kernel` (its ``workspace``: a ``_core.WorkspaceTerms``, the same fields) for a finger of at most 3 joints,
    else from :func:`_workspace_dynamics` (its twin).

    Raises:
        InputError: If the finger's Jacobian is singular (stretched finger) at ``q``.
    """
    kernel = _kernel(hand)
    if kernel is None or len(index) > 3:
        return _workspace_dynamics(hand, q, v, finger, index, number)
    base = hand.base
    rotation, translation = (_IDENTITY, _ORIGIN) if base.at_origin else (base.rotation, base.translation)
    terms = kernel.workspace(number, base.gravity, rotation, translation, q, v)
    if terms.singular:
        raise _singular(finger, q[index], len(index))
    return terms


_IDENTITY, _ORIGIN = np.eye(3), np.zeros(3)  # the placement of a hand base at the world origin


def _singular(finger: str, angles: np.ndarray, rank: int) -> InputError:
    return InputError(f"finger {finger!r} is at a singular configuration q = {angles} (J has rank < {rank})")


def _workspace_dynamics(
    hand: Hand, q: np.ndarray, v: np.ndarray, finger: str, index: np.ndarray, number: int
) -> _Workspace:
    """:func:`workspace_terms` in NumPy: the twin of the compiled ``FingerDynamics.workspace``.

    B spans the column space of J_f (left singular vectors), each column's largest entry made positive (a sign that
    changes nothing but makes B unique).
    """
    positions, jacobian_all, mass_f, gravity_f, velocity_f, bias = _finger_terms(hand, q, v, finger, number)
    jacobian = jacobian_all[:, index]
    u, singular, _ = np.linalg.svd(jacobian)
    rank = min(3, len(index))
    if singular[rank - 1] < 1e-6 * max(singular[0], 1e-12):
        raise _singular(finger, q[index], rank)
    basis = u[:, :rank]
    basis = basis * np.sign(basis[np.abs(basis).argmax(axis=0), np.arange(rank)])
    task_jacobian = basis.T @ jacobian
    inverse = np.linalg.inv(task_jacobian)
    mass_x = inverse.T @ mass_f @ inverse
    bias = basis.T @ bias
    coriolis_x = inverse.T @ velocity_f - mass_x @ bias
    return _Workspace(
        positions[number],
        jacobian_all,
        basis,
        task_jacobian,
        0.5 * (mass_x + mass_x.T),
        coriolis_x,
        inverse.T @ gravity_f,
    )


def _fingertip_torque(
    terms: Any,
    velocity: np.ndarray,
    x_d: np.ndarray,
    xd_d: np.ndarray,
    xdd_d: np.ndarray,
    kp: np.ndarray,
    kv: np.ndarray,
) -> np.ndarray:
    """tau_f [N m] of the fingertip computed torque (module docstring) from a finger's workspace ``terms``.

    ``velocity``: the finger's joint velocities q_dot_f; ``x_d``, ``xd_d``, ``xdd_d``: the reference [m], [m/s],
    [m/s^2]; ``kp``, ``kv``: the (3, 3) Cartesian gains.  The twin of the compiled ``WorkspaceTerms.torque``.
    """
    basis, task_jacobian = terms.basis, terms.task_jacobian
    error = terms.position - x_d
    error_dot = task_jacobian @ velocity - basis.T @ xd_d  # task coordinates: J_t q_dot_f = B^T x_dot
    kp_t, kv_t = basis.T @ kp @ basis, basis.T @ kv @ basis
    command = basis.T @ xdd_d - kv_t @ error_dot - kp_t @ (basis.T @ error)
    return task_jacobian.T @ (terms.mass @ command + terms.coriolis + terms.gravity)


Terms = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]


def _finger_terms(hand: Hand, q: np.ndarray, v: np.ndarray, finger: str, number: int) -> Terms:
    """The joint-space terms of ``finger`` (``hand.fingers[number]``) that (2.35)-(2.37) transform, world frame.

    (every fingertip position (n_fingers, 3) [m], the finger's fingertip Jacobian J (3, nv), M_f (n_f, n_f)
    [kg m^2], G_f (n_f,) [N m], C_f q_dot (n_f,) [N m], J_dot q_dot (3,) [m/s^2]), as the hand's methods give them.
    From the compiled kernel (``src/workspace.cpp``, one per hand, its own Pinocchio data) when ``bhgrasp._core``
    loads, otherwise from :func:`_finger_terms_python`: equal to the bit (tests/test_workspace_kernels.py).  The
    hand's base placement and gravity are read at every call.
    """
    kernel = _kernel(hand)
    if kernel is None:
        return _finger_terms_python(hand, q, v, finger, number)
    positions, jacobian, mass_f, gravity_f, velocity_f, bias = kernel.compute(number, hand.model.gravity.linear, q, v)
    placement = hand.base_placement
    if not placement.isIdentity(0.0):  # to the world frame, with the hand's own products
        rotation = placement.rotation
        positions = positions @ rotation.T + placement.translation
        jacobian = rotation @ jacobian
        bias = rotation @ bias
    return positions, jacobian, mass_f, gravity_f, velocity_f, bias


def _finger_terms_python(hand: Hand, q: np.ndarray, v: np.ndarray, finger: str, number: int) -> Terms:
    """:func:`_finger_terms` through the hand's methods (Pinocchio's Python API): the compiled kernel's twin."""
    index = hand.finger_indices(finger)
    gravity = hand.gravity_torques(q)
    return (
        hand.fingertip_positions(q),
        hand.fingertip_jacobian(q, finger),
        hand.mass_matrix(q)[np.ix_(index, index)],
        gravity[index],
        (hand.nonlinear_effects(q, v) - gravity)[index],
        hand.fingertip_bias_acceleration(q, v, finger),
    )


def _kernel(hand: Hand) -> Any:
    """The hand's compiled ``_core.FingerDynamics``, built on first use; ``None`` when the default engine is Python.

    It holds a copy of the hand's model (the hand's inertias must not change in place afterwards); gravity is passed at
    every call.
    """

    def build(core: Any) -> Any:
        model = hand.model
        frames = [model.getFrameId(frame) for frame in hand.fingertip_frames.values()]
        return core.FingerDynamics(
            model.saveToString(), frames, [hand.finger_indices(finger).tolist() for finger in hand.fingers]
        )

    return kernel(hand, "FingerDynamics", build)
