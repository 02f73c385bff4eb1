"""Computed torque in fingertip (Cartesian) space with the workspace dynamics of thesis (2.35)-(2.37).

For a finger with joints q_f and fingertip Jacobian J (world frame), the workspace dynamics are

    M_x = J^-T M_f J^-1,   C_x x_dot = J^-T (C q_dot)_f - M_x J_dot q_dot,   G_x = J^-T G_f,
    tau_f = J^T (M_x (x_dd_d - Kv e_x_dot - Kp e_x) + C_x x_dot + G_x),

which gives the Cartesian error dynamics e_x_dd + Kv e_x_dot + Kp e_x = 0 under an exact model.  A finger with
fewer joints than 3 (the Barrett F3: proximal and distal only) moves its tip in a plane; its task is then the
tip position within the column space of J (an orthonormal basis B, J_t = B^T J), and the reference must lie in
that plane.  Joints outside the controlled fingers are held by joint-space computed torque.

The whole chain (the joint-space terms, B, J_t, M_x, C_x, G_x and the computed torque) runs in a compiled kernel
(``src/workspace.cpp``) on the default engine (:mod:`bhgrasp._native`); :mod:`bhgrasp.controllers._workspace_terms`
holds it and its Python twins.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
import pinocchio as pin

from bhgrasp._validation import as_vector
from bhgrasp.controllers._workspace_terms import workspace_terms
from bhgrasp.controllers.base import Controller, gain_matrix
from bhgrasp.data import State
from bhgrasp.errors import InputError
from bhgrasp.model.hand import Hand
from bhgrasp.motion.trajectories import Reference


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
    terms = workspace_terms(hand, q, v, finger, index, hand.fingers.index(finger))
    return WorkspaceDynamics(
        *(np.array(value) for value in (terms.basis, terms.task_jacobian, terms.mass, terms.coriolis, terms.gravity))
    )


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
        self._fingers = [
            (finger, reference, nominal.finger_indices(finger), nominal.fingers.index(finger))
            for finger, reference in self.references.items()
        ]

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
        """Every controlled finger's workspace terms at validated (q, v): fingertip, Jacobian and dynamics."""
        hand = self.nominal
        return {
            finger: workspace_terms(hand, q, v, finger, index, number) for finger, _, index, number in self._fingers
        }

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
