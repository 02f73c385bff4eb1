"""HandDynamics: rigid-body dynamics of a hand (CRBA, RNEA, ABA, Coriolis, external forces, regressors).

The third of the hand's layers (:mod:`bhgrasp.model.hand_model`): Pinocchio's dynamics algorithms and the Slotine-Li
terms of the sliding and adaptive laws; ``bhgrasp._core.HandDynamics`` (``src/dynamics.cpp``) is the compiled
twin of :meth:`HandDynamics.slotine_li_torque`.  Every method is a method of :class:`~bhgrasp.model.hand.Hand`.

With mimic joints (:mod:`bhgrasp.model.couplings`), which Pinocchio's ABA and regressors do not support, forward
dynamics solve M a = tau - b and the regressors are G^T Y on the independent twin.
"""

from __future__ import annotations

import functools
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import pinocchio as pin

from bhgrasp._native import kernel
from bhgrasp._validation import as_array, as_vector
from bhgrasp.errors import InputError
from bhgrasp.model.couplings import TwinMap, independent_model, twin_map
from bhgrasp.model.hand_kinematics import HandKinematics


class HandDynamics(HandKinematics):
    """A :class:`~bhgrasp.model.hand_kinematics.HandKinematics` with rigid-body dynamics (Pinocchio's algorithms)."""

    def _dynamics(self) -> Any:
        """The compiled ``_core.HandDynamics`` of this hand's model, built on first use; ``None`` on the Python engine.

        It holds a copy of the model: the hand's inertias must not be changed in place afterwards
        (:meth:`perturbed` makes a new hand); gravity is passed at every call.
        """
        return kernel(self, "HandDynamics", lambda core: core.HandDynamics(self._model.saveToString()))

    # ------------------------------------------------------------------ dynamics
    def mass_matrix(self, q: Any) -> np.ndarray:
        """Joint-space inertia matrix M(q) (CRBA), full symmetric, shape (nv, nv) [kg m^2]."""
        mass = pin.crba(self._model, self._data, self._q(q)).copy()  # CRBA fills the upper triangle
        mass[self._lower_triangle] = mass.T[self._lower_triangle]
        return mass

    def nonlinear_effects(self, q: Any, v: Any) -> np.ndarray:
        """Coriolis, centrifugal and gravity torques C(q, v) v + G(q), shape (nv,) [N m]."""
        return pin.nonLinearEffects(self._model, self._data, self._q(q), self._v(v, "v")).copy()

    def gravity_torques(self, q: Any) -> np.ndarray:
        """Gravity torques G(q), shape (nv,) [N m] (the torques that hold the hand still)."""
        return pin.computeGeneralizedGravity(self._model, self._data, self._q(q)).copy()

    def coriolis_matrix(self, q: Any, v: Any) -> np.ndarray:
        """Coriolis matrix C(q, v), shape (nv, nv), with M_dot - 2 C skew-symmetric (thesis (2.27))."""
        q, v = self._q(q), self._v(v, "v")
        if self.couplings:  # Pinocchio 4.1's is wrong with mimic joints: G^T C_twin(G q + c, G v) G
            twin, data, mapping = self._twin
            g = mapping.velocity
            return g.T @ pin.computeCoriolisMatrix(twin, data, mapping.configuration(q), g @ v) @ g
        return pin.computeCoriolisMatrix(self._model, self._data, q, v).copy()

    def forward_dynamics(self, q: Any, v: Any, tau: Any, f_ext: Any = None) -> np.ndarray:
        """Joint accelerations (ABA) under joint torques ``tau`` [N m] and optional external forces.

        Args:
            f_ext: ``None``, or one force per joint (``njoints`` entries, index 0 = universe) in each joint's
                local frame, as ``pinocchio.Force`` objects or an array (njoints, 6) of (linear, angular);
                :meth:`external_forces` builds it from forces on frames.
        """
        q, v, tau = self._q(q), self._v(v, "v"), self._v(tau, "tau")
        if self.couplings:  # Pinocchio's ABA has no mimic joints: solve M a = tau - (C v + G - J^T f_ext)
            bias = self.inverse_dynamics(q, v, np.zeros(self._model.nv), f_ext)
            return np.linalg.solve(self.mass_matrix(q), tau - bias)
        if f_ext is None:
            return pin.aba(self._model, self._data, q, v, tau).copy()
        return pin.aba(self._model, self._data, q, v, tau, self._fext(f_ext)).copy()

    def inverse_dynamics(self, q: Any, v: Any, a: Any, f_ext: Any = None) -> np.ndarray:
        """Joint torques (RNEA) that produce accelerations ``a`` [rad/s^2]; ``f_ext`` as in :meth:`forward_dynamics`."""
        q, v, a = self._q(q), self._v(v, "v"), self._v(a, "a")
        if f_ext is None:
            return pin.rnea(self._model, self._data, q, v, a).copy()
        return pin.rnea(self._model, self._data, q, v, a, self._fext(f_ext)).copy()

    def external_forces(self, q: Any, forces: Mapping[str, Any]) -> pin.StdVec_Force:
        """Convert world-frame forces on frames into Pinocchio's per-joint ``f_ext``.

        Args:
            forces: Frame name -> force [N], shape (3,), applied at the frame origin, or wrench (6,) =
                (force [N], torque [N m]) about the frame origin; both in world coordinates.
        """
        pin.framesForwardKinematics(self._model, self._data, self._q(q))
        f_ext = pin.StdVec_Force()
        for _ in range(self._model.njoints):
            f_ext.append(pin.Force.Zero())
        rotation = self._placement.rotation  # base <- world is rotation.T
        for frame, value in forces.items():
            frame_id = self._frame_id(frame)
            wrench = _wrench(value, f"forces[{frame!r}]")
            force_at_frame = pin.Force(rotation.T @ wrench[:3], rotation.T @ wrench[3:])
            frame_origin = pin.SE3(np.eye(3), self._data.oMf[frame_id].translation)
            joint = self._model.frames[frame_id].parentJoint
            f_ext[joint] += self._data.oMi[joint].actInv(frame_origin.act(force_at_frame))
        return f_ext

    def regressor(self, q: Any, v: Any, a: Any) -> np.ndarray:
        """Joint-torque regressor Y(q, v, a), shape (nv, 10 * n_bodies): ``Y @ inertial_parameters() == rnea``.

        Columns come in blocks of 10 per joint body (Pinocchio's dynamic parameters: m, m c, I at the joint
        origin).  For the Slotine-Li form Y(q, qdot, qdot_r, qddot_r) see :meth:`slotine_li_regressor`.
        """
        q, v, a = self._q(q), self._v(v, "v"), self._v(a, "a")
        return self._torque_regressor(q, v, a)

    def _torque_regressor(self, q: np.ndarray, v: np.ndarray, a: np.ndarray) -> np.ndarray:
        """Pinocchio's joint-torque regressor, or G^T Y_twin(G q + c, G v, G a) with mimic joints (which it refuses).

        The twin is the independent one of :mod:`bhgrasp.model.couplings` (tau = G^T tau_twin, the bodies in one order).
        """
        if not self.couplings:
            return pin.computeJointTorqueRegressor(self._model, self._data, q, v, a).copy()
        twin, data, mapping = self._twin
        twin.gravity.linear = self._model.gravity.linear  # the hand's gravity may have been set since
        g = mapping.velocity
        return g.T @ pin.computeJointTorqueRegressor(twin, data, mapping.configuration(q), g @ v, g @ a)

    @functools.cached_property
    def _twin(self) -> tuple[pin.Model, pin.Data, TwinMap]:
        """The independent twin of a hand with mimic joints, its data and the map to it (built on first use)."""
        twin = independent_model(self._model)
        return twin, twin.createData(), twin_map(self._model, twin)

    def slotine_li_torque(self, q: Any, v: Any, v_r: Any, a_r: Any) -> np.ndarray:
        """M(q) a_r + C(q, v) v_r + G(q) [N m], the model term of sliding and adaptive laws (thesis (3.39)-(3.40)).

        C is the Christoffel-symbol Coriolis matrix (bilinear and symmetric in its velocity arguments, with
        M_dot - 2 C skew-symmetric), obtained by polarisation of RNEA's velocity-product torques h(w) = C(q, w) w:
        C(q, v) v_r = (h(v + v_r) - h(v - v_r)) / 4.  Three RNEA passes, no matrix is formed.
        """
        q, v, v_r, a_r = self._q(q), self._v(v, "v"), self._v(v_r, "v_r"), self._v(a_r, "a_r")
        kernel = self._dynamics()
        if kernel is None:
            return self._slotine_li_torque_python(q, v, v_r, a_r)
        return kernel.slotine_li_torque(self._model_gravity, q, v, v_r, a_r)

    def _slotine_li_torque_python(self, q: np.ndarray, v: np.ndarray, v_r: np.ndarray, a_r: np.ndarray) -> np.ndarray:
        """:meth:`slotine_li_torque` through Pinocchio's Python API (the twin of the compiled ``HandDynamics``)."""
        model, data, zero = self._model, self._data, np.zeros(self._model.nv)
        plus = pin.rnea(model, data, q, v + v_r, zero).copy()
        minus = pin.rnea(model, data, q, v - v_r, zero)  # gravity cancels in the difference
        return pin.rnea(model, data, q, zero, a_r) + 0.25 * (plus - minus)

    def slotine_li_regressor(self, q: Any, v: Any, v_r: Any, a_r: Any) -> np.ndarray:
        """Y(q, v, v_r, a_r), shape (nv, 10 n_bodies): ``Y @ inertial_parameters() == slotine_li_torque(...)``.

        Pinocchio's regressor takes (q, v, a) and gives M a + C(q, v) v + G; the adaptive laws need the
        reference velocity in the Coriolis term, so this builds it from three regressors by the same polarisation
        as :meth:`slotine_li_torque`.
        """
        q, v, v_r, a_r = self._q(q), self._v(v, "v"), self._v(v_r, "v_r"), self._v(a_r, "a_r")
        zero = np.zeros(self._model.nv)
        plus = self._torque_regressor(q, v + v_r, zero)
        minus = self._torque_regressor(q, v - v_r, zero)
        return self._torque_regressor(q, zero, a_r) + 0.25 * (plus - minus)

    def inertial_parameters(self) -> np.ndarray:
        """Dynamic parameters of every moving body, shape (10 * n_bodies,).

        Per body: (m, mc_x, mc_y, mc_z, I_xx, I_xy, I_yy, I_xz, I_yz, I_zz), inertia about the joint origin, in
        the joint frame (Pinocchio's ``Inertia.toDynamicParameters``).
        """
        inertias = self._model.inertias
        return np.concatenate([inertias[j].toDynamicParameters() for j in range(1, self._model.njoints)])

    def _fext(self, f_ext: Any) -> pin.StdVec_Force:
        njoints = self._model.njoints
        if isinstance(f_ext, pin.StdVec_Force) or (
            isinstance(f_ext, Sequence) and f_ext and isinstance(f_ext[0], pin.Force)
        ):
            if len(f_ext) != njoints:
                raise InputError(
                    f"`f_ext` must hold {njoints} forces (one per joint, universe first), got {len(f_ext)}"
                )
            for i, force in enumerate(f_ext):
                as_vector(force.vector, f"f_ext[{i}]", 6)
            if isinstance(f_ext, pin.StdVec_Force):
                return f_ext
            vector = pin.StdVec_Force()
            for force in f_ext:
                vector.append(force)
            return vector
        array = as_array(f_ext, "f_ext", (njoints, 6))
        vector = pin.StdVec_Force()
        for row in array:
            vector.append(pin.Force(row[:3], row[3:]))
        return vector


def _wrench(value: Any, name: str) -> np.ndarray:
    """A force (3,) or wrench (6,) as a wrench (6,) = (force, torque)."""
    size = np.size(value)
    wrench = as_vector(np.ravel(value) if size in (3, 6) else value, name, 6 if size == 6 else 3)
    return wrench if size == 6 else np.concatenate((wrench, np.zeros(3)))
