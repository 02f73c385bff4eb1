"""A fingertip reference in the world turned into a joint reference of a whole hand (closed-form IK, Jacobian)."""

from __future__ import annotations

from typing import Any

import numpy as np

from bhgrasp._validation import as_positive, as_vector, require_name
from bhgrasp.errors import InputError, ModelError
from bhgrasp.model.hand import Hand
from bhgrasp.model.ik import finger_ik
from bhgrasp.motion.trajectories import Reference, Sample


class CartesianReference(Reference):
    """A fingertip reference in the world [m] turned into a joint reference of the whole hand (size ``nv``).

    At each time the finger's joints come from the closed-form :func:`~bhgrasp.model.ik.finger_ik`, seeded with the
    previous solution (``q_rest`` at first and after :meth:`reset`) so that the IK branch stays continuous along
    the path.  With ``J`` the finger's columns of :meth:`Hand.fingertip_jacobian` (world-aligned):
    ``qdot = J^+ xdot`` and ``qddot = J^+ (xddot - Jdot qdot)``, where ``Jdot qdot`` is the classical fingertip
    acceleration at zero joint acceleration, in the world.  ``J^+`` is a least-squares solve, so a finger with
    two joints works: its fingertip (e.g. Barrett F3, proximal and distal only) moves in a fixed plane, and the
    Cartesian reference must lie in that plane (as a straight line between two reachable in-plane points does);
    a point farther than ``plane_tolerance`` from it raises :class:`~bhgrasp.errors.UnreachableError` from
    ``finger_ik``.  Every other joint is held at ``q_rest`` with zero velocity and acceleration.

    Evaluation is stateful (the IK seed) and uses the hand's Pinocchio data: one reference per thread.  Near a
    finger singularity (stretched finger) ``J`` is ill-conditioned and the joint rates grow accordingly.
    """

    def __init__(
        self, hand: Hand, finger: str, reference: Reference, q_rest: Any, *, plane_tolerance: float = 1e-6
    ) -> None:
        """Build the joint reference.

        Args:
            hand: A hand whose finger is Barrett-like (optional spread, then two parallel-axis joints) and whose
                joints are all 1-DOF (``nq == nv``).
            finger: Finger name, e.g. ``"F1"``.
            reference: Fingertip position reference of size 3, world frame [m].
            q_rest: Hand configuration [rad], shape (nq,): the other joints' positions and the first IK seed.
            plane_tolerance: Largest distance [m] of the target from a two-joint finger's plane.

        Raises:
            InputError: Not a :class:`Hand`, unknown finger, a reference not of size 3, a bad ``q_rest`` or
                ``plane_tolerance``.
            ModelError: The hand has joints with ``nq != nv``.
        """
        if not isinstance(hand, Hand):
            raise InputError(f"`hand` must be a bhgrasp Hand, got {type(hand).__name__}")
        require_name(finger, hand.fingers, "finger")
        if not isinstance(reference, Reference) or reference.size != 3:
            got = f"size {reference.size}" if isinstance(reference, Reference) else type(reference).__name__
            raise InputError(f"`reference` must be a Reference of size 3 (fingertip position [m]), got {got}")
        if hand.nq != hand.nv:
            raise ModelError(f"CartesianReference needs nq == nv (1-DOF joints), got nq={hand.nq}, nv={hand.nv}")
        self.hand = hand
        self.finger = finger
        self.reference = reference
        self.q_rest = as_vector(q_rest, "q_rest", hand.nq).copy()
        self.plane_tolerance = as_positive(plane_tolerance, "plane_tolerance")
        self._indices = hand.finger_indices(finger)
        self._seed = self.q_rest.copy()

    @property
    def size(self) -> int:
        """``hand.nv``: one component per joint."""
        return self.hand.nv

    def reset(self) -> None:
        """Seed the next IK with ``q_rest`` again (e.g. before replaying the reference from its start)."""
        self._seed = self.q_rest.copy()

    def __call__(self, t: float) -> Sample:
        """Joint position [rad], velocity [rad/s] and acceleration [rad/s^2] at time ``t`` [s].

        Raises:
            InputError: ``t`` is not finite.
            UnreachableError: The fingertip target is out of reach, or out of a two-joint finger's plane.
        """
        x, xdot, xddot = self.reference(t)
        hand, indices = self.hand, self._indices
        solution = finger_ik(hand, self.finger, x, q0=self._seed, plane_tolerance=self.plane_tolerance)
        q = solution.apply(self.q_rest)
        self._seed = q.copy()
        jacobian = hand.fingertip_jacobian(q, self.finger)[:, indices]
        v = np.zeros(hand.nv)
        v[indices] = np.linalg.lstsq(jacobian, xdot, rcond=None)[0]
        a = np.zeros(hand.nv)
        bias = hand.fingertip_bias_acceleration(q, v, self.finger)
        a[indices] = np.linalg.lstsq(jacobian, xddot - bias, rcond=None)[0]
        return q, v, a


__all__ = ["CartesianReference"]
