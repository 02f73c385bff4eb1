"""Contact forces within the joints' torque limits: less squeeze, the same wrench.

A distribution's contact forces f (n, 3) (contact frames (t1, t2, n), on the object) split into the part that exerts
the wrench and an internal part the grasp map cancels:

    f = f_w + f_i,   f_w = G^+ G f,   G f_i = 0,

so f(beta) = f_w + beta f_i exerts the same wrench G f for every beta.  beta = 1 is the distribution's answer; a
smaller beta squeezes less, which unloads the joints that press the object (a thumb opposing two fingers carries
their sum), and needs more friction: the forces leave the cones the distribution kept them in.  A controller's joint
torques are affine in the contact forces it commands (tau = tau_0 + J_h^T f for a computed-torque law; the
SMC-adaptive law's force feedback is linear in them too), so with tau(1) and tau(0), those of f and f_w,

    tau(beta) = tau(0) + beta (tau(1) - tau(0)).

:func:`internal_scale` picks the largest beta in [beta_min, 1] that keeps every |tau_j(beta)| within its limit
L_j, where beta_min is the least squeeze with which every contact still presses (no normal force below 0; 0 where
f_w's normals alone are all >= 0).  The limit comes before the distribution's least normal force, a preference: a
contact at it loses squeeze with the others.  When no beta in that range keeps every joint within its limit, the
beta with the smallest largest ratio |tau_j| / L_j over the joints beta moves (the largest such beta when several
have it; a joint whose torque does not depend on the squeeze cannot be helped by it).  A joint
torque clipped by the drive, one finger pressing less than the others, pushes the object out of balance; scaled
this way the fingers press less together.
"""

from __future__ import annotations

import numpy as np

from bhgrasp.errors import InputError


def split_internal(grasp_map: np.ndarray, forces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(f_w, f_i), both shaped like ``forces`` (n, 3): the part G^+ G f that exerts the wrench, and the rest.

    Args:
        grasp_map: G (6, 3n), contact frames to the object's wrench (as :attr:`GraspContacts.grasp_map
            <bhgrasp.controllers.grasping.GraspContacts.grasp_map>`).
        forces: (n, 3) contact forces [N].
    """
    flat = np.asarray(forces, dtype=float).ravel()
    grasp_map = np.asarray(grasp_map, dtype=float)
    if grasp_map.shape != (6, flat.size):
        raise InputError(f"`grasp_map` must be (6, {flat.size}) for {flat.size // 3} contacts, got {grasp_map.shape}")
    wrench_part = np.linalg.pinv(grasp_map) @ (grasp_map @ flat)
    shape = np.shape(forces)
    return wrench_part.reshape(shape), (flat - wrench_part).reshape(shape)


def internal_scale(
    torque: np.ndarray,
    wrench_torque: np.ndarray,
    limits: np.ndarray,
    normals: np.ndarray,
    wrench_normals: np.ndarray,
) -> float:
    """The squeeze fraction beta in [0, 1] that keeps the joints within their limits (module docstring).

    Args:
        torque: tau(1) (nv,) [N m], the joint torques with the distribution's forces (finite).
        wrench_torque: tau(0) (nv,) [N m], with their wrench part f_w alone (finite).
        limits: L (nv,) [N m], every entry > 0 (``inf`` for a joint without a limit).
        normals: The distribution's normal forces (n,) [N].
        wrench_normals: f_w's normal forces (n,) [N].
    """
    torque, wrench_torque = np.asarray(torque, dtype=float), np.asarray(wrench_torque, dtype=float)
    limits = np.asarray(limits, dtype=float)
    if np.all(np.abs(torque) <= limits):
        return 1.0
    internal = np.asarray(normals, dtype=float) - wrench_normals
    lowest = 0.0
    for base, slope in zip(wrench_normals, internal):
        if slope > 0.0:  # beta >= -f_w,n / f_i,n keeps this contact pressing
            lowest = max(lowest, -base / slope)
    lowest = min(lowest, 1.0)
    slope = (torque - wrench_torque) / limits
    base = wrench_torque / limits
    # joints whose torque beta moves (none of a joint without a limit); one it does not move cannot be helped
    moved = np.isfinite(limits) & (np.abs(slope) > 1e-12 * np.maximum(1.0, np.abs(base)))
    if not moved.any():
        return 1.0
    base, slope = base[moved], slope[moved]
    # the largest ratio r(beta) = max_j |base_j + beta slope_j| is convex and piecewise linear: its least value over
    # [lowest, 1] is at an end or where two of its lines cross; below 1 any beta of the interval r <= 1 will do
    candidates = [lowest, 1.0]
    for sign in (1.0, -1.0):
        candidates += list((sign - base) / slope)
    lines = np.concatenate((slope, -slope)), np.concatenate((base, -base))
    for i in range(len(lines[0])):
        for j in range(i + 1, len(lines[0])):
            if lines[0][i] != lines[0][j]:
                candidates.append((lines[1][j] - lines[1][i]) / (lines[0][i] - lines[0][j]))
    betas = np.unique(np.clip([c for c in candidates if np.isfinite(c)], lowest, 1.0))
    ratios = np.max(np.abs(base[None, :] + betas[:, None] * slope[None, :]), axis=1)
    worst = np.maximum(ratios, 1.0)
    best = worst.min()
    return float(betas[worst <= best * (1.0 + 1e-12)].max())


__all__ = ["internal_scale", "split_internal"]
