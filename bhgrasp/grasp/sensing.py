"""What a controller reads from sensed contacts: per-finger contact forces and their joint reaction torques.

A :class:`~bhgrasp.data.state.State` lists contacts as (body a, body b) with body a a hand link frame, the normal from a
to b and the force on b (the object).  Here contacts are grouped by finger (the finger whose joints move the link)
and turned into the force the finger exerts on the object, its normal component, and the joint torques J^T F the
contact forces produce (thesis (4.8), tau_d = J_f^T F_c).
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field

import numpy as np

from bhgrasp._native import default_core
from bhgrasp._validation import as_array, as_vector
from bhgrasp.data import State
from bhgrasp.model.hand import Hand


@dataclass(frozen=True)
class FingerContact:
    """The contacts of one finger at one instant (world frame).

    Attributes:
        force: Total force the finger exerts on the object(s) [N], (3,).
        normal_force: Sum of the normal components n . F [N] (>= 0 while pressing).
        normal: Force-weighted mean unit normal from finger to object, or zeros without contact.
        count: Number of contact points.
        point: Force-weighted mean contact point [m] of the pressing contacts (zeros without any).
        link: Link frame of the contact that presses hardest (``None`` without any).
    """

    force: np.ndarray
    normal_force: float
    normal: np.ndarray
    count: int
    point: np.ndarray = field(default_factory=lambda: np.zeros(3))
    link: str | None = None

    @property
    def touching(self) -> bool:
        """Whether the finger has at least one contact that presses."""
        return self.count > 0 and self.normal_force > 0.0


class ContactSensing:
    """Groups a state's contacts by finger; built once per hand (maps link frames to fingers)."""

    def __init__(self, hand: Hand) -> None:
        """Map every frame attached to a finger's joints to that finger."""
        self.hand = hand
        model = hand.model
        self._finger_of: dict[str, str] = {}
        base = {model.getJointId(name) for name in hand.base_joints}
        for finger in hand.fingers:  # the joints that carry the tip (a mimic joint's body included), not the mount's
            tip = model.frames[model.getFrameId(hand.fingertip_frames[finger])]
            joints = set(model.supports[tip.parentJoint][1:]) - base
            for frame in model.frames:
                if frame.parentJoint in joints:
                    self._finger_of.setdefault(frame.name, finger)
        self._empty = FingerContact(np.zeros(3), 0.0, np.zeros(3), 0)
        self._finger_index = {link: self.hand.fingers.index(finger) for link, finger in self._finger_of.items()}
        self._joint_of: dict[str, int] = {}  # frame name -> its parent joint (the first frame of a name, as getFrameId)
        for frame in model.frames:
            self._joint_of.setdefault(frame.name, frame.parentJoint)

    def finger_rows(self, links: Iterable[str]) -> np.ndarray:
        """The index in ``hand.fingers`` of each link frame's finger (-1: the palm or a frame of no finger), int64."""
        index = self._finger_index
        return np.array([index.get(link, -1) for link in links], dtype=np.int64)

    def finger_of(self, link: str) -> str | None:
        """The finger a link frame belongs to (``None`` for the palm or a frame of no finger)."""
        return self._finger_of.get(link)

    def fingers(self, state: State, body: str | None = None) -> dict[str, FingerContact]:
        """Per finger (every finger of the hand), its contacts in ``state`` (with ``body`` only, if given).

        Sums in the compiled kernel (``src/sensing.cpp``) on the default engine (:mod:`bhgrasp._native`), else in
        :meth:`_fingers_python` (the same sums; tests/test_sensing_kernels.py holds them together).
        """
        core = default_core()
        if core is None:
            return self._fingers_python(state, body)
        bodies = state.contact_bodies
        index = self._finger_index
        finger = np.array(
            [index.get(link, -1) if body is None or other == body else -1 for link, other in bodies], dtype=np.int64
        )
        fingers = self.hand.fingers
        if not len(finger):
            return dict.fromkeys(fingers, self._empty)
        sums = core.finger_contacts(
            finger, len(fingers), state.contact_points, state.contact_normals, state.contact_forces
        )
        force, normal_force, normal, count = sums.force, sums.normal_force, sums.normal, sums.count
        point, strongest = sums.point, sums.strongest
        result = {}
        for f, name in enumerate(fingers):
            if not count[f]:
                result[name] = self._empty
                continue
            row = int(strongest[f])
            result[name] = FingerContact(
                force[f].copy(),
                float(normal_force[f]),
                normal[f].copy(),
                int(count[f]),
                point[f].copy(),
                bodies[row][0] if row >= 0 else None,
            )
        return result

    def _fingers_python(self, state: State, body: str | None = None) -> dict[str, FingerContact]:
        """:meth:`fingers` in NumPy (the readable twin of the compiled sums)."""
        grouped: dict[str, list[int]] = {finger: [] for finger in self.hand.fingers}
        for k, (link, other) in enumerate(state.contact_bodies):
            finger = self._finger_of.get(link)
            if finger is not None and (body is None or other == body):
                grouped[finger].append(k)
        result = {}
        for finger, rows in grouped.items():
            if not rows:
                result[finger] = self._empty
                continue
            forces, normals = state.contact_forces[rows], state.contact_normals[rows]
            components = np.einsum("ij,ij->i", forces, normals)
            weights = np.maximum(components, 0.0)
            pressing = weights.sum() > 0.0
            mean = (weights @ normals) if pressing else normals.sum(axis=0)
            norm = np.linalg.norm(mean)
            normal = mean / norm if norm > 0.0 else np.zeros(3)
            point = weights @ state.contact_points[rows] / weights.sum() if pressing else np.zeros(3)
            link = state.contact_bodies[rows[int(np.argmax(weights))]][0] if pressing else None
            result[finger] = FingerContact(forces.sum(axis=0), float(components.sum()), normal, len(rows), point, link)
        return result

    def reaction_torques(self, state: State) -> np.ndarray:
        """Joint torques the contact forces exert on the hand, sum of J_p^T F_on_hand over contacts [N m], (nv,).

        J_p is the translational Jacobian of the contact point on its link; F_on_hand = -(force on the object). The
        hand's dynamics read M q_dd + C q_d + G = tau + this.  Summed in the compiled kernel (``src/dynamics.cpp``) on
        the default engine (:mod:`bhgrasp._native`), else in :meth:`_reaction_torques_python` (equal to round-off:
        tests/test_sensing_kernels.py).
        """
        hand = self.hand
        joint_of = self._joint_of
        rows = [k for k, (link, _) in enumerate(state.contact_bodies) if link in joint_of]
        if not rows:
            return np.zeros(hand.nv)
        kernel = hand.compiled_dynamics()
        if kernel is None:
            return self._reaction_torques_python(state)
        q = as_vector(state.q, "state.q", hand.nq)
        placement = hand.base_placement
        joints = [joint_of[state.contact_bodies[k][0]] for k in rows]
        points = state.contact_points[rows]
        if not np.isfinite(points).all():
            as_array(points, "points", (len(rows), 3))  # raises, as Hand.point_jacobians does
        return kernel.contact_torques(
            placement.rotation, placement.translation, q, joints, points, state.contact_forces[rows]
        )

    def _reaction_torques_python(self, state: State) -> np.ndarray:
        """:meth:`reaction_torques` by the hand's point Jacobians (the compiled sum's twin).

        Through :meth:`~bhgrasp.model.hand.Hand.point_jacobians`.
        """
        hand = self.hand
        rows = [
            k
            for k, (link, _) in enumerate(state.contact_bodies)
            if link in self._finger_of or hand.model.existFrame(link)
        ]
        if not rows:
            return np.zeros(hand.nv)
        links = [state.contact_bodies[k][0] for k in rows]
        jacobians = hand.point_jacobians(state.q, links, state.contact_points[rows])  # (n, 3, nv)
        return -np.einsum("nij,ni->j", jacobians, state.contact_forces[rows])


__all__ = ["ContactSensing", "FingerContact"]
