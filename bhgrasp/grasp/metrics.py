"""Grasp quantities read back from a recorded :class:`~bhgrasp.data.trajectory.Trajectory`: forces, slip, slides."""

from __future__ import annotations

import numpy as np

from bhgrasp._validation import as_real
from bhgrasp.data import Trajectory
from bhgrasp.grasp.sensing import ContactSensing
from bhgrasp.model.hand import Hand
from bhgrasp.model.hand_kinematics import point_jacobians


def finger_of(hand: Hand, link: str) -> str | None:
    """The finger whose joints move the link frame ``link``, or ``None`` (palm, environment)."""
    return ContactSensing(hand).finger_of(link)


def finger_normal_forces(hand: Hand, traj: Trajectory) -> np.ndarray:
    """(N, n_fingers) measured normal force [N] of each finger on the objects (sum over its contact points)."""
    forces = np.zeros((len(traj), len(hand.fingers)))
    if not len(traj.contact_pair) or not len(traj.pair_bodies):
        return forces
    objects = set(traj.object_names)
    sensing = ContactSensing(hand)
    fingers = [sensing.finger_of(str(link)) if str(other) in objects else None for link, other in traj.pair_bodies]
    column = np.array([-1 if finger is None else hand.fingers.index(finger) for finger in fingers])[traj.contact_pair]
    sample = np.repeat(np.arange(len(traj)), np.diff(traj.contact_offsets))
    force, normal = traj.contact_force, traj.contact_normal
    pressed = force[:, 0] * normal[:, 0] + force[:, 1] * normal[:, 1] + force[:, 2] * normal[:, 2]  # f . n per row
    on_finger = column >= 0
    np.add.at(forces, (sample[on_finger], column[on_finger]), pressed[on_finger])  # in row order, as a loop adds
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


def sliding_distances(hand: Hand, traj: Trajectory, start_time: float = 0.0) -> dict[str, float]:
    """How far each hand link slid on the objects from ``start_time`` [s]: link name -> distance [m].

    Sample k holds the contacts of the step that ended at t_k (and q, v, the object's pose and twist then).  Its
    sliding contact points (``Trajectory.contact_sticking`` False) between a link and an object move against the
    object at the relative tangential speed |(I - n n^T)(J_p(q) v - v_o - omega_o x (p - x_o))| (the link's material
    point at p against the object's; v_o at the object's origin x_o); the link's fastest point times
    t_k - t_(k-1) is added to its distance (the points of a link move as one body, so its patch counts once).  A
    patch whose edge reaches the Coulomb limit while its other points stick (partial slip, Johnson's *Contact
    Mechanics* 7.2) moves little; a link whose whole contact slides adds its sliding speed.  Links that never slid
    are left out.
    """
    start_time = as_real(start_time, "start_time", nonnegative=False)
    objects = list(traj.object_names)
    distances: dict[str, float] = {}
    first = max(int(np.searchsorted(traj.t, start_time)), 1)  # the first sample has no step behind it
    for k in range(first, len(traj.t)):
        rows = np.arange(traj.contact_offsets[k], traj.contact_offsets[k + 1])
        rows = rows[~traj.contact_sticking[rows]]
        if len(rows) == 0:
            continue
        bodies = traj.pair_bodies[traj.contact_pair[rows]]
        on = np.array([other in objects and hand.model.existFrame(str(link)) for link, other in bodies], dtype=bool)
        if not on.any():
            continue
        rows, bodies = rows[on], bodies[on]
        links = [str(link) for link in bodies[:, 0]]
        points, normals = traj.contact_point[rows], traj.contact_normal[rows]
        hand_velocity = point_jacobians(hand, traj.q[k], links, points) @ traj.v[k]
        index = np.array([objects.index(str(other)) for other in bodies[:, 1]])
        twist, origin = traj.object_twist[k, index], traj.object_position[k, index]
        relative = hand_velocity - twist[:, :3] - np.cross(twist[:, 3:], points - origin)
        relative -= np.sum(relative * normals, axis=1)[:, None] * normals
        speed, interval = np.linalg.norm(relative, axis=1), float(traj.t[k] - traj.t[k - 1])
        for link in set(links):
            fastest = max(s for name, s in zip(links, speed) if name == link)
            distances[link] = distances.get(link, 0.0) + fastest * interval
    return distances


__all__ = ["finger_normal_forces", "finger_of", "sliding_distances", "slip_events", "slip_events_after"]
