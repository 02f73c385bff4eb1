"""Computed torque in fingertip (Cartesian) space with the workspace dynamics of thesis (2.35)-(2.37).

For a finger with joints q_f and fingertip Jacobian J (world frame), the workspace dynamics are

    M_x = J^-T M_f J^-1,   C_x x_dot = J^-T (C q_dot)_f - M_x J_dot q_dot,   G_x = J^-T G_f,
    tau_f = J^T (M_x (x_dd_d - Kv e_x_dot - Kp e_x) + C_x x_dot + G_x),

which gives the Cartesian error dynamics e_x_dd + Kv e_x_dot + Kp e_x = 0 under an exact model.  A finger with
fewer joints than 3 (the Barrett F3: proximal and distal only) moves its tip in a plane; its task is then the
tip position within the column space of J (an orthonormal basis B, J_t = B^T J), and the reference must lie in
that plane.  Joints outside the controlled fingers are held by joint-space computed torque.

The whole chain (the joint-space terms tip position, J, M_f, G_f, C q_dot, J_dot q_dot; the SVD, inverse and products
that turn them into B, J_t, M_x, C_x, G_x; the computed torque) runs in a compiled kernel (``src/workspace.cpp``)
when ``bhgrasp._core`` loads.  Its Python twins are :func:`_finger_terms_python` (equal to the bit),
:func:`_workspace_dynamics` and :func:`_fingertip_torque` (NumPy: equal to round-off, tests/test_workspace_kernels.py).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
import pinocchio as pin

from bhgrasp._native import kernel
from bhgrasp._validation import as_vector
from bhgrasp.controllers.base import Controller, gain_matrix
from bhgrasp.errors import InputError
from bhgrasp.hand import Hand
from bhgrasp.sim.state import State
from bhgrasp.trajectories import Reference


@dataclass(frozen=True)
class WorkspaceDynamics:
    """The workspace dynamics of one finger at (q, q_dot), in task coordinates x_t = B^T x.

    Attributes:
        basis: (3, r) orthonormal basis B of the directions the fingertip can move in (r = min(3, n_f)).
        jacobian: (r, n_f) task Jacobian J_t = B^T J_f.
        mass: (r, r) M_x [kg].
        coriolis: (r,) C_x x_dot [N].
        gravity: (r,) G_x [N].
    """

    basis: np.ndarray
    jacobian: np.ndarray
    mass: np.ndarray
    coriolis: np.ndarray
    gravity: np.ndarray


def workspace_dynamics(hand: Hand, q: Any, v: Any, finger: str) -> WorkspaceDynamics:
    """Thesis (2.35)-(2.37) for ``finger`` of ``hand`` at (q [rad], v [rad/s]); world frame.

    Raises:
        InputError: If the finger's Jacobian is singular (stretched finger) at ``q``.
    """
    q, v = as_vector(q, "q", hand.nq), as_vector(v, "v", hand.nv)
    index = hand.finger_indices(finger)
    terms = _workspace(hand, q, v, finger, index, hand.fingers.index(finger), _kernel(hand))
    return WorkspaceDynamics(*(np.array(value) for value in (terms.basis, terms.task_jacobian, terms.mass,
                                                              terms.coriolis, terms.gravity)))  # fmt: skip


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


def _workspace(hand: Hand, q: np.ndarray, v: np.ndarray, finger: str, index: np.ndarray, number: int,
               kernel: Any) -> Any:  # fmt: skip
    """The workspace terms of ``finger`` at validated (q [rad], v [rad/s]), world frame: a :class:`_Workspace`.

    ``index`` are the finger's joint indices, ``number`` its place in ``hand.fingers``, ``kernel`` the hand's
    :func:`_kernel`: its ``workspace`` (a ``_core.WorkspaceTerms``, the same fields) for a finger of at most 3 joints,
    else :func:`_workspace_dynamics` (its twin).

    Raises:
        InputError: If the finger's Jacobian is singular (stretched finger) at ``q``.
    """
    if kernel is None or len(index) > 3:
        return _workspace_dynamics(hand, q, v, finger, index, number)
    if hand._base_at_origin:
        rotation, translation = _IDENTITY, _ORIGIN
    else:
        placement = hand.base_placement
        rotation, translation = placement.rotation, placement.translation
    terms = kernel.workspace(number, hand._model_gravity, rotation, translation, q, v)
    if terms.singular:
        raise _singular(finger, q[index], len(index))
    return terms


_IDENTITY, _ORIGIN = np.eye(3), np.zeros(3)  # the placement of a hand base at the world origin


def _singular(finger: str, angles: np.ndarray, rank: int) -> InputError:
    return InputError(f"finger {finger!r} is at a singular configuration q = {angles} (J has rank < {rank})")


def _workspace_dynamics(
    hand: Hand, q: np.ndarray, v: np.ndarray, finger: str, index: np.ndarray, number: int
) -> _Workspace:
    """:func:`_workspace` in NumPy: the twin of the compiled ``FingerDynamics.workspace``.

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
    return _Workspace(positions[number], jacobian_all, basis, task_jacobian, 0.5 * (mass_x + mass_x.T), coriolis_x,
                      inverse.T @ gravity_f)  # fmt: skip


def _fingertip_torque(
    terms: Any, velocity: np.ndarray, x_d: np.ndarray, xd_d: np.ndarray, xdd_d: np.ndarray, kp: np.ndarray,
    kv: np.ndarray,
) -> np.ndarray:  # fmt: skip
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
    """The hand's compiled ``_core.FingerDynamics``, built on first use; ``None`` if ``bhgrasp._core`` is missing.

    It holds a copy of the hand's model (the hand's inertias must not change in place afterwards); gravity is passed at
    every call.
    """

    def build(core: Any) -> Any:
        model = hand.model
        frames = [model.getFrameId(frame) for frame in hand.fingertip_frames.values()]
        return core.FingerDynamics(model.saveToString(), frames,
                                   [hand.finger_indices(finger).tolist() for finger in hand.fingers])  # fmt: skip

    return kernel(hand, "FingerDynamics", build)


class WorkspaceComputedTorque(Controller):
    """Fingertip computed torque for some fingers (Cartesian references, world frame), joint CTC for other joints.

    Logged: ``x_d`` and ``x_error`` (fingers stacked, 3 each) [m].
    """

    def __init__(
        self,
        nominal: Hand,
        references: Mapping[str, Reference],
        kp: Any = 400.0,
        kv: Any = 160.0,
        q_rest: Any = None,
    ) -> None:
        """Set up the controller.

        Args:
            nominal: The controller's model of the hand.
            references: Finger -> fingertip position reference (size 3, world frame [m]).
            kp, kv: Cartesian gains [1/s^2], [1/s] (scalar, (3,) or (3, 3) SPD), also used for held joints.
            q_rest: Configuration at which other joints are held (default: where :meth:`reset` finds them).
        """
        super().__init__()
        if not isinstance(nominal, Hand):
            raise InputError(f"`nominal` must be a bhgrasp Hand, got {nominal!r}")
        if not references:
            raise InputError("`references` must map at least one finger to a Cartesian reference")
        self.nominal = nominal
        self.references: dict[str, Reference] = {}
        used: set[int] = set()
        for finger, reference in references.items():
            index = nominal.finger_indices(finger)  # validates the name
            if used & set(index.tolist()):
                raise InputError(f"finger {finger!r} shares joints with another controlled finger")
            used |= set(index.tolist())
            if not isinstance(reference, Reference) or reference.size != 3:
                raise InputError(f"references[{finger!r}] must be a Reference of size 3 [m], got {reference!r}")
            self.references[finger] = reference
        self.kp = gain_matrix(kp, 3, "kp")
        self.kv = gain_matrix(kv, 3, "kv")
        self._other = np.array([i for i in range(nominal.nv) if i not in used], dtype=int)
        self._joint_kp = float(np.trace(self.kp)) / 3.0
        self._joint_kv = float(np.trace(self.kv)) / 3.0
        self.q_rest = None if q_rest is None else as_vector(q_rest, "q_rest", nominal.nq)
        self._hold = self.q_rest
        self._fingers = [(finger, reference, nominal.finger_indices(finger), nominal.fingers.index(finger))
                         for finger, reference in self.references.items()]  # fmt: skip

    def reset(self, state: State) -> None:
        """Hold uncontrolled joints at ``q_rest`` or at the state's configuration."""
        q = as_vector(state.q, "state.q", self.nominal.nq)
        self._hold = q.copy() if self.q_rest is None else self.q_rest

    def __call__(self, t: float, state: State) -> np.ndarray:
        """Joint torques [N m] for the fingertip references at time ``t`` [s]."""
        hand = self.nominal
        q, v = as_vector(state.q, "state.q", hand.nq), as_vector(state.v, "state.v", hand.nv)
        return self._control(t, state, q, v)

    def _workspaces(self, q: np.ndarray, v: np.ndarray) -> dict[str, Any]:
        """Every controlled finger's :func:`_workspace` at validated (q, v): the fingertip, Jacobian and dynamics."""
        hand, kernel = self.nominal, _kernel(self.nominal)
        return {finger: _workspace(hand, q, v, finger, index, number, kernel)
                for finger, _, index, number in self._fingers}  # fmt: skip

    def _control(
        self, t: float, state: State, q: np.ndarray, v: np.ndarray, workspace: Mapping[str, Any] | None = None
    ) -> np.ndarray:
        """:meth:`__call__` for the state's validated ``q`` and ``v`` (an outer loop that checked them calls this).

        ``workspace``: :meth:`_workspaces` at (q, v), if the caller has them.
        """
        hand = self.nominal
        if self._hold is None:
            self.reset(state)
        if workspace is None:
            workspace = self._workspaces(q, v)
        tau = np.zeros(hand.nv)
        targets, errors = [], []
        for finger, reference, index, _ in self._fingers:
            x_d, xd_d, xdd_d = reference(t)
            terms = workspace[finger]
            tau[index] = terms.torque(v[index], x_d, xd_d, xdd_d, self.kp, self.kv)
            targets.append(x_d)
            errors.append(terms.position - x_d)
        if len(self._other):
            other = self._other
            acceleration = np.zeros(hand.nv)  # fingers are separate chains: M has no finger-to-finger blocks
            acceleration[other] = -self._joint_kv * v[other] - self._joint_kp * (q - self._hold)[other]
            tau[other] = pin.rnea(hand.model, hand.data, q, v, acceleration)[other]  # hand.inverse_dynamics, unchecked
        self.log["x_d"], self.log["x_error"] = _stacked(targets), _stacked(errors)
        if not math.isfinite(tau @ tau) and not np.isfinite(tau).all():  # the product: one cheap test per call
            raise InputError(f"WorkspaceComputedTorque produced non-finite torques {tau} at t = {t} s")
        return tau


def _stacked(arrays: list[np.ndarray]) -> np.ndarray:
    """``np.concatenate(arrays)``, for one array (one finger controlled) a cheaper copy."""
    return arrays[0].copy() if len(arrays) == 1 else np.concatenate(arrays)


__all__ = ["WorkspaceComputedTorque", "WorkspaceDynamics", "workspace_dynamics"]
