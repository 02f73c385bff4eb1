"""A hand's rigid-body dynamics: CRBA, RNEA, ABA, Coriolis, external forces, regressors, perturbed copies.

Free functions over a :class:`~bhgrasp.model.hand.Hand` (which offers each as a method of the same name): Pinocchio's
dynamics algorithms and the Slotine-Li terms of the sliding and adaptive laws; ``bhgrasp._core.HandDynamics``
(``src/dynamics.cpp``) is the compiled twin of :func:`slotine_li_torque`.

With mimic joints (:mod:`bhgrasp.model.couplings`), which Pinocchio's ABA and regressors do not support, forward
dynamics solve M a = tau - b and the regressors are G^T Y on the independent twin (:attr:`Hand.twin`).
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
from bhgrasp.model.hand_description import HandDescription as Hand


def compiled_dynamics(hand: Hand) -> Any:
    """The compiled ``_core.HandDynamics`` of the hand's model, built on first use; ``None`` on the Python engine.

    It holds a copy of the model: the hand's inertias must not be changed in place afterwards (:func:`perturbed`
    makes a new hand); gravity is passed at every call.
    """
    return kernel(hand, "HandDynamics", lambda core: core.HandDynamics(hand.model.saveToString()))


def total_mass(hand: Hand) -> float:
    """Mass of every body, base included [kg]."""
    return float(sum(inertia.mass for inertia in hand.model.inertias))


def mass_matrix(hand: Hand, q: Any) -> np.ndarray:
    """Joint-space inertia matrix M(q) (CRBA), full symmetric, shape (nv, nv) [kg m^2]."""
    mass = pin.crba(hand.model, hand.data, hand.check_q(q)).copy()  # CRBA fills the upper triangle
    lower = _lower_triangle(hand.model.nv)
    mass[lower] = mass.T[lower]
    return mass


def nonlinear_effects(hand: Hand, q: Any, v: Any) -> np.ndarray:
    """Coriolis, centrifugal and gravity torques C(q, v) v + G(q), shape (nv,) [N m]."""
    return pin.nonLinearEffects(hand.model, hand.data, hand.check_q(q), hand.check_v(v, "v")).copy()


def gravity_torques(hand: Hand, q: Any) -> np.ndarray:
    """Gravity torques G(q), shape (nv,) [N m] (the torques that hold the hand still)."""
    return pin.computeGeneralizedGravity(hand.model, hand.data, hand.check_q(q)).copy()


def coriolis_matrix(hand: Hand, q: Any, v: Any) -> np.ndarray:
    """Coriolis matrix C(q, v), shape (nv, nv), with M_dot - 2 C skew-symmetric (thesis (2.27))."""
    q, v = hand.check_q(q), hand.check_v(v, "v")
    if hand.couplings:  # Pinocchio 4.1's is wrong with mimic joints: G^T C_twin(G q + c, G v) G
        twin, data, mapping = hand.twin
        g = mapping.velocity
        return g.T @ pin.computeCoriolisMatrix(twin, data, mapping.configuration(q), g @ v) @ g
    return pin.computeCoriolisMatrix(hand.model, hand.data, q, v).copy()


def forward_dynamics(hand: Hand, q: Any, v: Any, tau: Any, f_ext: Any = None) -> np.ndarray:
    """Joint accelerations (ABA) under joint torques ``tau`` [N m] and optional external forces.

    Args:
        f_ext: ``None``, or one force per joint (``njoints`` entries, index 0 = universe) in each joint's
            local frame, as ``pinocchio.Force`` objects or an array (njoints, 6) of (linear, angular);
            :meth:`external_forces` builds it from forces on frames.
    """
    q, v, tau = hand.check_q(q), hand.check_v(v, "v"), hand.check_v(tau, "tau")
    if hand.couplings:  # Pinocchio's ABA has no mimic joints: solve M a = tau - (C v + G - J^T f_ext)
        bias = inverse_dynamics(hand, q, v, np.zeros(hand.model.nv), f_ext)
        return np.linalg.solve(mass_matrix(hand, q), tau - bias)
    if f_ext is None:
        return pin.aba(hand.model, hand.data, q, v, tau).copy()
    return pin.aba(hand.model, hand.data, q, v, tau, _fext(hand, f_ext)).copy()


def inverse_dynamics(hand: Hand, q: Any, v: Any, a: Any, f_ext: Any = None) -> np.ndarray:
    """Joint torques (RNEA) that produce accelerations ``a`` [rad/s^2]; ``f_ext`` as in :meth:`forward_dynamics`."""
    q, v, a = hand.check_q(q), hand.check_v(v, "v"), hand.check_v(a, "a")
    if f_ext is None:
        return pin.rnea(hand.model, hand.data, q, v, a).copy()
    return pin.rnea(hand.model, hand.data, q, v, a, _fext(hand, f_ext)).copy()


def external_forces(hand: Hand, q: Any, forces: Mapping[str, Any]) -> pin.StdVec_Force:
    """Convert world-frame forces on frames into Pinocchio's per-joint ``f_ext``.

    Args:
        forces: Frame name -> force [N], shape (3,), applied at the frame origin, or wrench (6,) =
            (force [N], torque [N m]) about the frame origin; both in world coordinates.
    """
    pin.framesForwardKinematics(hand.model, hand.data, hand.check_q(q))
    f_ext = pin.StdVec_Force()
    for _ in range(hand.model.njoints):
        f_ext.append(pin.Force.Zero())
    rotation = hand.base.rotation  # base <- world is rotation.T
    for frame, value in forces.items():
        frame_id = hand.frame_id(frame)
        wrench = _wrench(value, f"forces[{frame!r}]")
        force_at_frame = pin.Force(rotation.T @ wrench[:3], rotation.T @ wrench[3:])
        frame_origin = pin.SE3(np.eye(3), hand.data.oMf[frame_id].translation)
        joint = hand.model.frames[frame_id].parentJoint
        f_ext[joint] += hand.data.oMi[joint].actInv(frame_origin.act(force_at_frame))
    return f_ext


def regressor(hand: Hand, q: Any, v: Any, a: Any) -> np.ndarray:
    """Joint-torque regressor Y(q, v, a), shape (nv, 10 * n_bodies): ``Y @ inertial_parameters() == rnea``.

    Columns come in blocks of 10 per joint body (Pinocchio's dynamic parameters: m, m c, I at the joint
    origin).  For the Slotine-Li form Y(q, qdot, qdot_r, qddot_r) see :meth:`slotine_li_regressor`.
    """
    q, v, a = hand.check_q(q), hand.check_v(v, "v"), hand.check_v(a, "a")
    return _torque_regressor(hand, q, v, a)


def _torque_regressor(hand: Hand, q: np.ndarray, v: np.ndarray, a: np.ndarray) -> np.ndarray:
    """Pinocchio's joint-torque regressor, or G^T Y_twin(G q + c, G v, G a) with mimic joints (which it refuses).

    The twin is the independent one of :mod:`bhgrasp.model.couplings` (tau = G^T tau_twin, the bodies in one order).
    """
    if not hand.couplings:
        return pin.computeJointTorqueRegressor(hand.model, hand.data, q, v, a).copy()
    twin, data, mapping = hand.twin
    twin.gravity.linear = hand.model.gravity.linear  # the hand's gravity may have been set since
    g = mapping.velocity
    return g.T @ pin.computeJointTorqueRegressor(twin, data, mapping.configuration(q), g @ v, g @ a)


def slotine_li_torque(hand: Hand, q: Any, v: Any, v_r: Any, a_r: Any) -> np.ndarray:
    """M(q) a_r + C(q, v) v_r + G(q) [N m], the model term of sliding and adaptive laws (thesis (3.39)-(3.40)).

    C is the Christoffel-symbol Coriolis matrix (bilinear and symmetric in its velocity arguments, with
    M_dot - 2 C skew-symmetric), obtained by polarisation of RNEA's velocity-product torques h(w) = C(q, w) w:
    C(q, v) v_r = (h(v + v_r) - h(v - v_r)) / 4.  Three RNEA passes, no matrix is formed.
    """
    q, v, v_r, a_r = hand.check_q(q), hand.check_v(v, "v"), hand.check_v(v_r, "v_r"), hand.check_v(a_r, "a_r")
    kernel = compiled_dynamics(hand)
    if kernel is None:
        return _slotine_li_torque_python(hand, q, v, v_r, a_r)
    return kernel.slotine_li_torque(hand.base.gravity, q, v, v_r, a_r)


def _slotine_li_torque_python(hand: Hand, q: np.ndarray, v: np.ndarray, v_r: np.ndarray, a_r: np.ndarray) -> np.ndarray:
    """:meth:`slotine_li_torque` through Pinocchio's Python API (the twin of the compiled ``HandDynamics``)."""
    model, data, zero = hand.model, hand.data, np.zeros(hand.model.nv)
    plus = pin.rnea(model, data, q, v + v_r, zero).copy()
    minus = pin.rnea(model, data, q, v - v_r, zero)  # gravity cancels in the difference
    return pin.rnea(model, data, q, zero, a_r) + 0.25 * (plus - minus)


def slotine_li_regressor(hand: Hand, q: Any, v: Any, v_r: Any, a_r: Any) -> np.ndarray:
    """Y(q, v, v_r, a_r), shape (nv, 10 n_bodies): ``Y @ inertial_parameters() == slotine_li_torque(...)``.

    Pinocchio's regressor takes (q, v, a) and gives M a + C(q, v) v + G; the adaptive laws need the
    reference velocity in the Coriolis term, so this builds it from three regressors by the same polarisation
    as :meth:`slotine_li_torque`.
    """
    q, v, v_r, a_r = hand.check_q(q), hand.check_v(v, "v"), hand.check_v(v_r, "v_r"), hand.check_v(a_r, "a_r")
    zero = np.zeros(hand.model.nv)
    plus = _torque_regressor(hand, q, v + v_r, zero)
    minus = _torque_regressor(hand, q, v - v_r, zero)
    return _torque_regressor(hand, q, zero, a_r) + 0.25 * (plus - minus)


def inertial_parameters(hand: Hand) -> np.ndarray:
    """Dynamic parameters of every moving body, shape (10 * n_bodies,).

    Per body: (m, mc_x, mc_y, mc_z, I_xx, I_xy, I_yy, I_xz, I_yz, I_zz), inertia about the joint origin, in
    the joint frame (Pinocchio's ``Inertia.toDynamicParameters``).
    """
    inertias = hand.model.inertias
    return np.concatenate([inertias[j].toDynamicParameters() for j in range(1, hand.model.njoints)])


def _fext(hand: Hand, f_ext: Any) -> pin.StdVec_Force:
    njoints = hand.model.njoints
    if isinstance(f_ext, pin.StdVec_Force) or (
        isinstance(f_ext, Sequence) and f_ext and isinstance(f_ext[0], pin.Force)
    ):
        if len(f_ext) != njoints:
            raise InputError(f"`f_ext` must hold {njoints} forces (one per joint, universe first), got {len(f_ext)}")
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


def perturbed(
    hand: Hand,
    mass_scale: float | Sequence[float] = 1.0,
    payload: tuple[str, float] | None = None,
    name: str | None = None,
) -> Hand:
    """A copy of this hand with different inertial parameters: a controller's nominal model, or a plant.

    Kinematics, limits and fingertips are unchanged; the copy has its own Pinocchio model and data.

    Args:
        mass_scale: Factor on each moving body's mass and rotational inertia (centre of mass unchanged): one
            number, or one per body in joint order (``nv`` values for a hand of 1-DOF joints, plus one per mimic
            joint).  0.7 is a nominal model that underestimates every body by 30 %.
        payload: ``(frame, mass [kg])``: a point mass rigidly attached at that frame's origin, e.g. an unknown
            load at a fingertip.
        name: Display name (default: this hand's name with the perturbation).

    Raises:
        InputError: Non-positive or non-finite scales, a negative payload, or an unknown frame.
    """
    n_bodies = hand.model.njoints - 1
    uniform = np.ndim(mass_scale) == 0
    scales = as_vector(np.full(n_bodies, mass_scale) if uniform else mass_scale, "mass_scale", n_bodies)
    if np.any(scales <= 0.0):
        raise InputError(f"`mass_scale` must be positive and finite, got {mass_scale!r}")
    model = pin.Model(hand.model)
    for joint, scale in enumerate(scales, start=1):
        inertia = model.inertias[joint]
        model.inertias[joint] = pin.Inertia(scale * inertia.mass, inertia.lever.copy(), scale * inertia.inertia)
    label = f"mass x{float(mass_scale):g}" if uniform else "masses scaled"
    if payload is not None:
        frame, mass = payload
        frame_id = hand.frame_id(frame)
        mass = float(mass)
        if not np.isfinite(mass) or mass < 0.0:
            raise InputError(f"payload mass must be a finite number >= 0 [kg], got {payload[1]!r}")
        placement = model.frames[frame_id].placement  # frame in its parent joint's frame
        joint = model.frames[frame_id].parentJoint
        point = pin.Inertia(mass, placement.translation.copy(), np.zeros((3, 3)))
        model.inertias[joint] = model.inertias[joint] + point
        label += f", {mass:g} kg at {frame}"
    return hand.with_model(model, name or f"{hand.name} ({label})")


@functools.cache
def _lower_triangle(nv: int) -> tuple[np.ndarray, np.ndarray]:
    """Indices of the strictly lower triangle of an (nv, nv) matrix."""
    return np.tril_indices(nv, -1)


def _wrench(value: Any, name: str) -> np.ndarray:
    """A force (3,) or wrench (6,) as a wrench (6,) = (force, torque)."""
    size = np.size(value)
    wrench = as_vector(np.ravel(value) if size in (3, 6) else value, name, 6 if size == 6 else 3)
    return wrench if size == 6 else np.concatenate((wrench, np.zeros(3)))
