"""The manipulable space of a grasp: which object motions its fingers can make, and how far.

Contacts that neither slide nor roll tie the object twist x_dot = (v, omega) (at the centre of mass, world) to the
joint velocities: G^T x_dot = J_h q_dot (5.19).  A twist the fingers can produce has G^T x_dot in the range of J_h;
the others need sliding or rolling.  For the BH8-280's three-fingertip pinch these span 5 of the 6 dimensions:
F3 cannot move along the palm's x-axis, so the object cannot either, except by turning about a vertical axis
through F3's contact.

:func:`manipulable_space` evaluates that at a grasp; :meth:`ManipulableSpace.check` refuses a requested offset (a
small motion (dx [m], dtheta [rad]) along a straight twist) before anything is simulated, with an
:class:`~bhgrasp.errors.UnreachableError` that names the missing direction, the sliding it would need per contact and
the nearest offset the grasp can make; it also refuses an offset whose joint motion q + P dx (first order, P =
J_h^+ G^T) leaves the joint limits, naming the joint.  All of it is first order about the grasp, which is what a
planner needs before committing to a motion; the closed loop then tracks the real path.

Twists mix metres and radians: distances between twists use x_s = (v, L omega), L the grasp's size (the largest
distance from the centre of mass to a contact), so that a rotation counts by how far it moves the contacts.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from bhgrasp._validation import as_array, as_positive, as_vector
from bhgrasp.errors import InputError, UnreachableError
from bhgrasp.grasp.frames import grasp_map, hand_jacobian
from bhgrasp.model.hand import Hand

SLIDE_TOLERANCE = 2e-4  # [m] contact sliding a checked offset may need (the tracking target is 0.5 mm)
RANK_TOLERANCE = 1e-9  # relative singular value below which a direction counts as missing
_AXES = (
    "translation along x",
    "translation along y",
    "translation along z",
    "rotation about x",
    "rotation about y",
    "rotation about z",
)


@dataclass(frozen=True)
class ManipulableSpace:
    """The object motions a grasp allows, at one configuration (world frame, twists at the centre of mass).

    Attributes:
        basis: (6, k) orthonormal basis of the allowed twists in scaled coordinates (v, L omega).
        missing: (6, 6 - k) orthonormal basis of the missing ones, same coordinates.
        length: L [m], the grasp's size.
        grasp: G (6, 3n); jacobian: J_h (3n, nv).
        joint_map: P = J_h^+ G^T (nv, 6): the joint motion of an allowed twist.
        q, lower, upper: the configuration and joint limits [rad].
        joints: joint names; contacts: a label per contact (e.g. the finger).
    """

    basis: np.ndarray
    missing: np.ndarray
    length: float
    grasp: np.ndarray
    jacobian: np.ndarray
    joint_map: np.ndarray
    q: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    joints: tuple[str, ...]
    contacts: tuple[str, ...]

    @property
    def dimension(self) -> int:
        """Number of independent object motions the grasp can make (6: any)."""
        return self.basis.shape[1]

    def _scale(self) -> np.ndarray:
        return np.concatenate((np.ones(3), np.full(3, self.length)))

    def nearest(self, offset: Any, length: float | None = None) -> np.ndarray:
        """The allowed offset closest to ``offset`` (dx [m], dtheta [rad]) in the metric (dx, ``length`` dtheta).

        ``length`` [m] weighs rotations against translations (default: the grasp's size L, the basis' own metric;
        e.g. 0.1 m when 5 mrad of rotation error matters as much as 0.5 mm of translation).
        """
        offset = as_vector(offset, "offset", 6)
        scale = self._scale()
        if length is not None:  # the same allowed subspace, orthonormal in the other metric
            other = np.concatenate((np.ones(3), np.full(3, as_positive(length, "length"))))
            basis, _ = np.linalg.qr(self.basis / scale[:, None] * other[:, None])
            scale = other
        else:
            basis = self.basis
        scaled = offset * scale
        return basis @ (basis.T @ scaled) / scale

    def sliding(self, offset: Any) -> np.ndarray:
        """Per contact, how far [m] it must slide or roll for ``offset`` (first order): |G_i^T dx - J_i dq|."""
        offset = as_vector(offset, "offset", 6)
        demand = self.grasp.T @ offset
        residual = demand - self.jacobian @ (self.joint_map @ offset)
        return np.linalg.norm(residual.reshape(-1, 3), axis=1)

    def joint_reach(self, offset: Any) -> tuple[float, str | None]:
        """The fraction of ``offset`` the joints make before one reaches a limit (first order), and that joint."""
        step = self.joint_map @ as_vector(offset, "offset", 6)
        room = np.where(step > 0.0, self.upper - self.q, self.q - self.lower)
        with np.errstate(divide="ignore", invalid="ignore"):
            fractions = np.where(np.abs(step) > 1e-15, room / np.abs(step), np.inf)
        index = int(np.argmin(fractions))
        return float(fractions[index]), (self.joints[index] if np.isfinite(fractions[index]) else None)

    def check(self, offset: Any, slide_tolerance: float = SLIDE_TOLERANCE) -> None:
        """Refuse ``offset`` if the fingers cannot make it without sliding, or without passing a joint limit.

        Raises:
            UnreachableError: The message names the missing direction (the axes it moves), the worst contact's
                sliding and the nearest offset without sliding (and a joint limit that one meets); or the joint whose
                limit the motion crosses.  Its ``result`` is that nearest offset (``None`` for a joint limit).
        """
        offset = as_vector(offset, "offset", 6)
        slides = self.sliding(offset)
        worst = int(np.argmax(slides)) if len(slides) else 0
        if len(slides) and slides[worst] > slide_tolerance:
            nearest = self.nearest(offset)
            missing = "; ".join(describe(direction) for direction in self.missing.T)
            fraction, joint = self.joint_reach(nearest)
            limited = "" if fraction >= 1.0 else f", though joint {joint} meets its limit {100 * fraction:.0f} % of it"
            raise UnreachableError(
                f"the grasp cannot move the object by {np.round(offset, 6).tolist()} (dx [m], dtheta [rad]) without "
                f"sliding: contact {self.contacts[worst]} would slide or roll {1e3 * slides[worst]:.2f} mm (allowed "
                f"{1e3 * slide_tolerance:.2f} mm). The fingers make {self.dimension} of the 6 object motions; missing: "
                f"{missing}. The nearest offset without sliding is {np.round(nearest, 6).tolist()}{limited}",
                nearest,
            )
        fraction, joint = self.joint_reach(offset)
        if fraction < 1.0:
            raise UnreachableError(
                f"the grasp cannot move the object by {np.round(offset, 6).tolist()} (dx [m], dtheta [rad]): joint "
                f"{joint} reaches its limit {100 * fraction:.0f} % of the way (first order)"
            )


def manipulable_space(
    hand: Hand,
    q: Any,
    points: Any,
    normals: Any,
    links: Sequence[str],
    com: Any,
    labels: Sequence[str] | None = None,
) -> ManipulableSpace:
    """The object motions the grasp can make: contacts (world) on ``links`` about the object's centre ``com`` [m].

    Args:
        hand: The hand.
        q: Joint positions [rad].
        points: (n, 3) contact points [m], world; normals: (n, 3) into the object.
        links: The hand link frame of each contact.
        com: The object's centre of mass [m], world (the twists' reference point).
        labels: A name per contact for messages (default: the links).
    """
    q = as_vector(q, "q", hand.nq)
    points = as_array(points, "points", (None, 3))
    com = as_vector(com, "com", 3)
    if len(points) == 0:
        raise InputError("`points` must hold at least one contact")
    grasp = grasp_map(points, normals, com)
    jacobian = hand_jacobian(hand, q, points, list(links), normals)
    length = as_positive(float(np.max(np.linalg.norm(points - com, axis=1))), "grasp size (contacts at the centre)")
    scale = np.concatenate((np.ones(3), np.full(3, length)))
    # allowed scaled twists y: G^T S^-1 y in range(J_h), i.e. (I - J_h J_h^+) G^T S^-1 y = 0
    u, singular, vt = np.linalg.svd(jacobian, full_matrices=False)
    rank = int(np.sum(singular > RANK_TOLERANCE * max(1.0, singular[0])))
    outside_range = np.eye(len(jacobian)) - u[:, :rank] @ u[:, :rank].T
    constraint = outside_range @ grasp.T / scale
    _, values, basis_t = np.linalg.svd(constraint)
    missing_count = int(np.sum(values > RANK_TOLERANCE * max(1.0, values[0] if len(values) else 0.0)))
    inverse = (vt[:rank].T / singular[:rank]) @ u[:, :rank].T  # J_h^+
    return ManipulableSpace(
        basis=basis_t[missing_count:].T,
        missing=basis_t[:missing_count].T,
        length=length,
        grasp=grasp,
        jacobian=jacobian,
        joint_map=inverse @ grasp.T,
        q=q.copy(),
        lower=hand.lower,
        upper=hand.upper,
        joints=hand.joint_names,
        contacts=tuple(labels) if labels is not None else tuple(links),
    )


def describe(direction: Any) -> str:
    """A direction of scaled twists (v, L omega) in words: the axes it moves (components above 5 % of the largest)."""
    direction = as_vector(direction, "direction", 6)
    size = np.abs(direction)
    if size.max() == 0.0:
        return "no motion"
    axes = [_AXES[i] for i in np.argsort(-size) if size[i] >= 0.05 * size.max()]
    return axes[0] if len(axes) == 1 else f"{', '.join(axes[:-1])} combined with {axes[-1]}"


__all__ = ["ManipulableSpace", "describe", "manipulable_space"]
