"""Contact frames, the grasp map G, the hand Jacobian J_h and the grasp constraint residual.

Thesis chapter 5, (5.1)-(5.19), re-derived (the printed equations have typos).  Conventions:

* Contact i is a point ``p_i`` (world, [m]) with a unit normal ``n_i`` pointing INTO the object: the direction
  in which the finger pushes.  Its contact frame ``R_i = [t1_i, t2_i, n_i]`` (columns, world coordinates) is
  right-handed and orthonormal; :func:`contact_frames` fixes the tangents.
* Point contact with friction: the finger applies the force ``R_i f_i`` [N] to the object, with
  ``f_i = (f_t1, f_t2, f_n)`` in the contact frame inside the friction cone
  ``FC_i = {sqrt(f_t1^2 + f_t2^2) <= mu f_n}`` (5.6).  Contact forces are stacked ``f = (f_1, ..., f_n)``, (3n,).
* The object wrench is ``(force [N], torque [N m] about a reference point r)``, world-aligned, e.g. about the
  object's centre of mass: ``wrench = G f`` with the grasp map ``G = [G_1 ... G_n]``,
  ``G_i = [[R_i], [skew(p_i - r) R_i]]`` (6, 3) (5.8)-(5.12).
* The object twist ``x_dot_o = (v_r, omega)`` [m/s, rad/s] is the velocity of the object point at ``r`` and the
  angular velocity, world-aligned.  The contact point of the object moves with ``v_r + omega x (p_i - r)``, in
  contact coordinates ``G_i^T x_dot_o``: ``G^T`` is the dual (velocity) map of ``G``.
* The hand Jacobian ``J_h`` (3n, nv) maps joint velocities to the velocities of the finger points at the contacts
  in contact coordinates, ``R_i^T J_p,i v`` (5.14)-(5.17).  A contact that neither slips nor separates (no
  rolling either: the point is fixed on both bodies) imposes the grasp constraint ``G^T x_dot_o = J_h v`` (5.19).

Against the printed thesis: the lever in (5.10) is ``p_i - r`` (reference to contact), with the selection
``W_i`` of (5.5) keeping only the force columns of ``A_i``; for point contacts ``J_h,i`` of (5.17)/(5.19) is
(3, nv), not (6, l), and ``B_i`` reduces to ``R_i^T [I, -skew(p_i - o)]`` acting on the link's spatial velocity.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from bhgrasp._native import default_core
from bhgrasp._validation import as_array, as_vector
from bhgrasp.errors import InputError
from bhgrasp.model.hand import Hand

TANGENT_SWITCH = 0.9  # |n . x| above which the tangent t1 is built from the world y-axis instead of the x-axis
ZERO_NORMAL = 1e-12  # a normal shorter than this is rejected as zero


def contact_frames(normals: Any) -> np.ndarray:
    """Right-handed orthonormal contact frames ``R_i = [t1_i, t2_i, n_i]`` (columns, world), shape (n, 3, 3).

    ``n_i`` is the normalised normal.  ``t1_i`` is the world x-axis projected onto the tangent plane and
    normalised, ``t1 = normalise(a - (a . n) n)`` with ``a = x``, unless the normal is within about 26 degrees of
    the x-axis (``|n_x| > 0.9``), where ``a = y``; ``t2 = n x t1``.  So the frame is deterministic, depends
    continuously on the normal except across the switch ``|n_x| = 0.9``, and is the identity for ``n = +z``.

    Args:
        normals: Contact normals (world, pointing into the object), shape (n, 3); need not be unit vectors.

    Raises:
        InputError: Wrong shape, or a zero or non-finite normal (the message names the contact index).
    """
    normals = _rows(normals, "normals")
    core = default_core()
    if core is None:
        return unit_normal_frames(_unit_normals(normals))
    frames, zero = core.contact_frames(
        normals, ZERO_NORMAL, TANGENT_SWITCH
    )  # src/sensing.cpp, unit_normal_frames' twin
    if zero >= 0:
        _unit_normals(normals)  # raises InputError naming the zero normals
    return frames.reshape(-1, 3, 3)


def unit_normal_frames(unit: np.ndarray) -> np.ndarray:
    """:func:`contact_frames` of validated unit normals (n, 3): t1, t2 = n x t1 written out component-wise."""
    switch = np.abs(unit[:, 0]) > TANGENT_SWITCH
    axis = np.zeros_like(unit)
    axis[~switch, 0] = 1.0
    axis[switch, 1] = 1.0
    t1 = axis - np.einsum("ij,ij->i", axis, unit)[:, None] * unit
    t1 /= np.sqrt(np.einsum("ij,ij->i", t1, t1))[:, None]
    frames = np.empty((unit.shape[0], 3, 3))
    frames[:, :, 0], frames[:, :, 2] = t1, unit
    nx, ny, nz = unit.T
    ax, ay, az = t1.T
    frames[:, 0, 1], frames[:, 1, 1], frames[:, 2, 1] = ny * az - nz * ay, nz * ax - nx * az, nx * ay - ny * ax
    return frames


def grasp_map(points: Any, normals: Any, reference: Any) -> np.ndarray:
    """Grasp map ``G`` (6, 3n): object wrench (force [N], torque [N m] about ``reference``) = ``G f``.

    ``G_i = [[R_i], [skew(p_i - r) R_i]]`` with ``R_i`` from :func:`contact_frames`, so that the wrench is
    ``(sum R_i f_i, sum (p_i - r) x R_i f_i)`` (thesis (5.8)-(5.12)).

    Args:
        points: Contact points, world [m], shape (n, 3).
        normals: Contact normals into the object, world, shape (n, 3).
        reference: Point the torque is taken about (e.g. the object's centre of mass), world [m], shape (3,).
    """
    points, normals = _contacts(points, normals)
    return grasp_map_from_frames(points, contact_frames(normals), as_vector(reference, "reference", 3))


def grasp_map_from_frames(points: np.ndarray, frames: np.ndarray, reference: np.ndarray) -> np.ndarray:
    """:func:`grasp_map` from validated points (n, 3) and their contact frames (n, 3, 3)."""
    levers = _skew_rows(points - reference)  # (n, 3, 3)
    blocks = np.concatenate([frames, levers @ frames], axis=1)  # (n, 6, 3)
    return blocks.transpose(1, 0, 2).reshape(6, 3 * points.shape[0])


def hand_jacobian(hand: Hand, q: Any, points: Any, links: Sequence[str] | str, normals: Any) -> np.ndarray:
    """Hand Jacobian ``J_h`` (3n, nv): velocities of the finger points at the contacts, in contact coordinates.

    Rows ``3i:3i+3`` are ``R_i^T J_p,i`` where ``J_p,i = J_lin - skew(p_i - o) J_ang`` is the world translational
    Jacobian of the point ``p_i`` fixed on link frame ``links[i]`` (origin ``o``), thesis (5.14)-(5.17).  With
    the object twist at the reference of :func:`grasp_map`, a fixed contact obeys ``G^T x_dot_o = J_h v`` (5.19).

    Args:
        hand: The hand.
        q: Configuration, shape (nq,).
        points: Contact points, world [m], shape (n, 3), at configuration ``q``.
        links: Frame name of the link carrying each contact (e.g. ``"F3_distal_link"``), n names; a single name
            puts every contact on that link.
        normals: Contact normals into the object, world, shape (n, 3).

    Raises:
        InputError: Bad shapes or values, a wrong number of links, or an unknown frame name.
    """
    points, normals = _contacts(points, normals)
    count = points.shape[0]
    if isinstance(links, str):
        links = [links] * count
    if not isinstance(links, Sequence) or len(links) != count or not all(isinstance(link, str) for link in links):
        raise InputError(f"`links` must be {count} frame name(s), one per contact, got {links!r}")
    return _hand_jacobian(hand, q, points, links, contact_frames(normals))


def _hand_jacobian(hand: Hand, q: Any, points: np.ndarray, links: Sequence[str], frames: np.ndarray) -> np.ndarray:
    """:func:`hand_jacobian` from validated points, link names and contact frames (n, 3, 3)."""
    jacobians = hand.point_jacobians(q, links, points)  # (n, 3, nv), one kinematics pass
    return np.einsum("nji,njk->nik", frames, jacobians).reshape(3 * len(links), hand.nv)


def grasp_constraint_residual(grasp_matrix: Any, jacobian: Any, object_twist: Any, v: Any) -> np.ndarray:
    """Residual of the grasp constraint (5.19), ``J_h v - G^T x_dot_o``, shape (3n,) [m/s], contact coordinates.

    Zero when every contact point is fixed on both the finger and the object (no slip, no rolling).

    Args:
        grasp_matrix: ``G`` (6, 3n) from :func:`grasp_map`.
        jacobian: ``J_h`` (3n, nv) from :func:`hand_jacobian`.
        object_twist: ``(v_r [m/s], omega [rad/s])`` of the object at the reference point, world-aligned, (6,).
        v: Joint velocities, shape (nv,).
    """
    grasp_matrix = checked_grasp_matrix(grasp_matrix)
    jacobian = as_array(jacobian, "jacobian", (grasp_matrix.shape[1], None))
    twist = as_vector(object_twist, "object_twist", 6)
    v = as_vector(v, "v", jacobian.shape[1])
    return jacobian @ v - grasp_matrix.T @ twist


def checked_grasp_matrix(value: Any) -> np.ndarray:
    """``value`` as a grasp matrix G (6, 3n), n >= 1 (InputError otherwise)."""
    matrix = as_array(value, "grasp_matrix", (6, None))
    if matrix.shape[1] == 0 or matrix.shape[1] % 3:
        raise InputError(f"`grasp_matrix` must have shape (6, 3n) with n >= 1, got shape {matrix.shape}")
    return matrix


def _rows(value: Any, name: str) -> np.ndarray:
    try:
        array = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError) as error:
        raise InputError(f"`{name}` must be a numeric array of shape (n, 3), got {value!r}") from error
    if array.ndim != 2 or array.shape[1] != 3 or array.shape[0] < 1:
        raise InputError(f"`{name}` must have shape (n, 3) with n >= 1 contacts, got shape {array.shape}")
    if not np.isfinite(array).all():
        bad = np.flatnonzero(~np.all(np.isfinite(array), axis=1))
        raise InputError(f"`{name}` must be finite, got NaN/inf at contact index {bad.tolist()[:5]}")
    return array


def _unit_normals(normals: Any) -> np.ndarray:
    normals = _rows(normals, "normals")
    lengths = np.sqrt(np.einsum("ij,ij->i", normals, normals))
    bad = np.flatnonzero(lengths < ZERO_NORMAL)
    if bad.size:
        raise InputError(f"`normals` must be non-zero, got a zero normal at contact index {bad.tolist()[:5]}")
    return normals / lengths[:, None]


def _contacts(points: Any, normals: Any) -> tuple[np.ndarray, np.ndarray]:
    points, normals = _rows(points, "points"), _rows(normals, "normals")
    if points.shape != normals.shape:
        raise InputError(
            f"`points` and `normals` must have the same shape (n, 3), got {points.shape} and {normals.shape}"
        )
    return points, normals


def _skew_rows(vectors: np.ndarray) -> np.ndarray:
    result = np.zeros((vectors.shape[0], 3, 3))
    x, y, z = vectors.T
    result[:, 0, 1], result[:, 0, 2] = -z, y
    result[:, 1, 0], result[:, 1, 2] = z, -x
    result[:, 2, 0], result[:, 2, 1] = -y, x
    return result


__all__ = [
    "checked_grasp_matrix",
    "contact_frames",
    "grasp_constraint_residual",
    "grasp_map",
    "grasp_map_from_frames",
    "hand_jacobian",
    "unit_normal_frames",
]
