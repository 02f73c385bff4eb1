"""Grasp quantities read back from a recorded :class:`~bhgrasp.data.trajectory.Trajectory`: forces and slip events."""

from __future__ import annotations

import numpy as np

from bhgrasp.data import Trajectory
from bhgrasp.grasp.sensing import ContactSensing
from bhgrasp.model.hand import Hand


def finger_of(hand: Hand, link: str) -> str | None:
    """The finger whose joints move the link frame ``link``, or ``None`` (palm, environment)."""
    return ContactSensing(hand).finger_of(link)


def finger_normal_forces(hand: Hand, traj: Trajectory) -> np.ndarray:
    """(N, n_fingers) measured normal force [N] of each finger on the objects (sum over its contact points)."""
    forces = np.zeros((len(traj), len(hand.fingers)))
    objects = set(traj.object_names)
    sensing = ContactSensing(hand)
    for k in range(len(traj)):
        contacts = traj.contacts_at(k)
        for (link, other), force, normal in zip(contacts["bodies"], contacts["force"], contacts["normal"]):
            finger = sensing.finger_of(link)
            if finger is not None and other in objects:
                forces[k, hand.fingers.index(finger)] += force @ normal
    return forces


def slip_events(hand: Hand, traj: Trajectory, start_time: float = 0.0) -> int:
    """Number of (sample, contact point) pairs between the hand and an object that slide, from ``start_time`` [s].

    A contact slides when its tangential force reached the Coulomb limit (``Trajectory.contact_sticking`` False);
    contacts with the fixed environment (a table, a pedestal) are not counted.
    """
    first = int(np.searchsorted(traj.t, start_time))
    rows = slice(traj.contact_offsets[first], traj.contact_offsets[-1])
    bodies = traj.pair_bodies[traj.contact_pair[rows]]
    on_hand = np.array([hand.model.existFrame(str(name)) for name in bodies[:, 0]], dtype=bool).reshape(-1)
    on_object = np.isin(bodies[:, 1], list(traj.object_names)) & on_hand
    return int(np.sum(on_object & ~traj.contact_sticking[rows]))


def slip_events_after(hand: Hand, traj: Trajectory, index: int) -> int:
    """:func:`slip_events` from the sample after ``index``.

    E.g. after the sample where a grasp controller took over: a sample's contacts come from the step the previous
    input drove (the approach's), so a pad that has just touched may still skid there.
    """
    return slip_events(hand, traj, float(traj.t[min(int(index) + 1, len(traj.t) - 1)]))


__all__ = ["finger_normal_forces", "finger_of", "slip_events", "slip_events_after"]
