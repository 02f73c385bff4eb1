"""Second-order (path-level) check of an object motion in a grasp: the fingers followed along the whole path.

:mod:`~bhgrasp.grasp.manipulability` judges an offset at the start of the motion (first order, one contact per
finger).  Along a long turn the fingers reconfigure, and a link that was clear at the start may meet the object
beside the planned contact (a fingertip's distal link body beside its spherical pad, a proximal link, the palm): the
finger then touches at several points, its normal force splits among them and the planned contact's share may no
longer hold its tangential load.  :func:`path_contacts` foresees that before the motion is made:

1. The object follows the supervisor's path (:class:`~bhgrasp.motion.trajectories.PoseMotion` at blend b in [0, 1]):
   centre ``c(b) = c_0 + b dx``, rotation ``R(b) = exp(b dtheta) R_0``, so its twist per unit blend is the constant
   ``(dx, dtheta)`` at the moving centre (world).
2. The fingers keep their contacts without slipping; a spherical pad rolls, so the contact is re-found at each step
   (coal's nearest points between the pad's geometry and the object) and the joints take the Euler step
   ``J dq = (dx + dtheta x (p_i - c)) db + n_i (g_i - g_i0)`` in least squares: J (3n, nv) the stacked world
   Jacobians of the finger points at the contacts p_i (the first step is the first-order ``J_h^+ G^T`` twist of
   (5.19)), n_i the normal into the object and the last term holding each pad's signed gap g_i at its start value
   (the squeeze's penetration).  What the joints cannot make accumulates as a drift [m]: the sliding the path needs.
3. At each step coal's signed distance between every other hand collision geometry and the object: one that comes
   within ``tolerance`` (:data:`~bhgrasp.grasp.path_result.TOLERANCE`) is a new contact
   (:class:`~bhgrasp.grasp.path_result.PathTouch`); a joint outside its limits is reported too.

Cost: ``steps + 1`` kinematics passes and (number of hand geometries) distance queries per step, a few milliseconds.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import coal
import numpy as np
import pinocchio as pin

from bhgrasp._validation import as_array, as_real, as_vector
from bhgrasp.data import State
from bhgrasp.errors import InputError
from bhgrasp.grasp.path_result import TOLERANCE, PathContacts, PathTouch
from bhgrasp.grasp.probes import coal_transform, contact_geometries, pressed_face
from bhgrasp.grasp.sensing import ContactSensing
from bhgrasp.model.hand import Hand

LIMIT_TOLERANCE = 2e-3  # [rad] joint motion past a limit that counts as leaving it: 0.2 mm at a 0.1 m lever, the
# first-order check's sliding tolerance (a joint held on its stop that far makes its contact slide no more than that)
STEPS = 40  # path steps: 0.025 of the blend, 7.5 mrad of a 0.3 rad turn


def path_contacts(
    hand: Hand,
    q: Any,
    points: Any,
    links: Sequence[str],
    shape: coal.CollisionGeometry,
    pose: pin.SE3,
    offset: Any,
    steps: int = STEPS,
    tolerance: float = TOLERANCE,
    labels: Sequence[str] | None = None,
) -> PathContacts:
    """Follow the object's motion by ``offset`` with the contacts rolling without slip; see the module docstring.

    Args:
        hand: The hand (its ``collision_model()`` is checked).
        q: Joint positions [rad] when the motion starts (clipped to the limits: a sensed joint past its stop is on it).
        points: (n, 3) contact points [m], world (e.g. the sensed ones): each picks the geometry on its link's joint
            nearest to it (the pad) as a planned contact.
        links: The hand frame carrying each contact.
        shape: The object's coal shape, placed by ``pose``.
        pose: The object's pose when the motion starts (world <- object); its origin is the motion's centre.
        offset: (dx [m], dtheta [rad]), world: the motion the controller will track (e.g. the supervisor's plan).
        steps: Path steps (blends 0, 1/steps, ..., 1).
        tolerance: Signed distance [m] below which another geometry counts as meeting the object
            (:data:`~bhgrasp.grasp.path_result.TOLERANCE`).
        labels: A name per contact (default: the links).
    """
    q, points, offset, tolerance = _checked(hand, q, points, links, pose, offset, steps, tolerance)
    links = list(links)
    model, data, geometry = hand.model, pin.Data(hand.model), hand.collision_model()
    geometry_data, items = pin.GeometryData(geometry), geometry.geometryObjects
    pads = contact_geometries(hand, geometry, q, points, links)
    others = [g for g in range(len(items)) if g not in pads]
    fractions = np.linspace(0.0, 1.0, int(steps) + 1)
    path_q, gaps = np.empty((len(fractions), hand.nq)), np.empty((len(fractions), len(pads)))
    drift, clearance = np.zeros((len(fractions), len(pads))), np.empty((len(fractions), len(others)))
    request, result = coal.DistanceRequest(), coal.DistanceResult()
    touches: dict[int, PathTouch] = {}
    limit: tuple[float, str] | None = None
    contacts, normals, centre = np.empty((len(pads), 3)), np.empty((len(pads), 3)), pose.translation
    for k, b in enumerate(fractions):
        if k:
            q, missed = _roll(
                hand, q, links, contacts, normals, centre, offset, gaps[k - 1] - gaps[0], b - fractions[k - 1]
            )
            drift[k] = drift[k - 1] + missed
        rotation, centre = pin.exp3(b * offset[3:]) @ pose.rotation, pose.translation + b * offset[:3]
        placed_object = coal.Transform3s(rotation, centre)
        pin.updateGeometryPlacements(model, data, geometry, geometry_data, q)
        placed = [coal_transform(hand.base_placement * placement) for placement in geometry_data.oMg]
        _pad_contacts(items, pads, placed, shape, placed_object, request, result, gaps[k], contacts, normals)
        path_q[k] = q
        outside = (q < hand.lower - LIMIT_TOLERANCE) | (q > hand.upper + LIMIT_TOLERANCE)
        if limit is None and outside.any():
            limit = (float(b), hand.joint_names[int(np.argmax(outside))])
        for column, g in enumerate(others):
            result.clear()
            distance = coal.distance(items[g].geometry, placed[g], shape, placed_object, request, result)
            clearance[k, column] = distance
            if distance < tolerance and g not in touches:
                touches[g] = _touch(model, items, g, pads, contacts, result, distance, b, offset, shape, rotation)
    return PathContacts(
        fractions,
        path_q,
        gaps,
        drift,
        clearance,
        tuple(items[g].name for g in others),
        tuple(touches.values()),
        limit,
        offset.copy(),
        tuple(labels) if labels is not None else tuple(links),
        float(tolerance),
    )


def _checked(hand: Hand, q, points, links, pose, offset, steps, tolerance) -> tuple:
    """:func:`path_contacts`' inputs checked: q, points (n, 3), offset (6,), tolerance [m].

    q is clipped to the limits (a sensed joint past its stop is on it); at least one contact and one step, an SE3 pose.
    """
    q = np.clip(as_vector(q, "q", hand.nq), hand.lower, hand.upper)  # sensed joints past a stop are on it (noise)
    tolerance = as_real(tolerance, "tolerance")
    points = as_array(points, "points", (len(links), 3))
    offset = as_vector(offset, "offset", 6)
    if len(points) == 0 or int(steps) < 1:
        raise InputError(f"need at least one contact and one step, got {len(points)} contacts and steps={steps}")
    if not isinstance(pose, pin.SE3):
        raise InputError(f"`pose` must be a pinocchio.SE3, got {type(pose).__name__}")
    return q, points, offset, tolerance


def _roll(hand: Hand, q, links, contacts, normals, centre, offset, gap_change, db: float) -> tuple:
    """One Euler step in the blend: J dq = (dx + dtheta x (p - c)) db + n (gap - gap_0), by least squares.

    Returns the joints after it and each contact's miss [m] (what the step could not make).
    """
    demand = (offset[:3] + np.cross(offset[3:], contacts - centre)) * db
    demand += normals * gap_change[:, None]
    jacobian = hand.point_jacobians(q, links, contacts).reshape(-1, hand.nv)
    step = np.linalg.lstsq(jacobian, demand.reshape(-1), rcond=1e-10)[0]
    return q + step, np.linalg.norm((jacobian @ step).reshape(-1, 3) - demand, axis=1)


def _pad_contacts(items, pads, placed, shape, placed_object, request, result, gaps, contacts, normals) -> None:
    """Each pad's gap [m], contact point and normal now, written into ``gaps``, ``contacts``, ``normals``.

    The pads roll: the contact point moves on both bodies.
    """
    for i, g in enumerate(pads):
        result.clear()
        gaps[i] = coal.distance(items[g].geometry, placed[g], shape, placed_object, request, result)
        contacts[i] = 0.5 * (np.asarray(result.getNearestPoint1()) + np.asarray(result.getNearestPoint2()))
        normals[i] = result.normal


def _touch(model, items, g: int, pads: list[int], contacts, result, distance: float, b: float, offset, shape, rotation):
    """The :class:`PathTouch` of geometry ``g`` meeting the object at ``distance`` [m] at blend ``b``.

    ``result``: their distance query; ``pads`` and ``contacts``: the planned contacts' geometries and points.
    """
    witness = np.array(result.getNearestPoint1())
    same_joint = [i for i, pad in enumerate(pads) if items[pad].parentJoint == items[g].parentJoint]
    spacing = min((float(np.linalg.norm(witness - contacts[i])) for i in same_joint), default=np.inf)
    return PathTouch(
        float(b),
        float(b * np.linalg.norm(offset[3:])),
        items[g].name,
        model.frames[items[g].parentFrame].name,
        pressed_face(shape, rotation, result.normal),
        float(distance),
        witness,
        spacing,
    )


def sensed_path_contacts(
    hand: Hand,
    state: State,
    shape: coal.CollisionGeometry,
    offset: Any,
    steps: int = STEPS,
    tolerance: float = TOLERANCE,
) -> PathContacts:
    """:func:`path_contacts` at the contacts the fingers sense in ``state``, as the grasp supervisor plans from them.

    The contacts are :class:`~bhgrasp.grasp.sensing.ContactSensing`'s per finger (force-weighted point, the link that
    presses hardest), the object's pose is ``state.object_poses[0]`` (``shape``'s pose).

    Raises:
        InputError: Fewer than two fingers touch the object.
    """
    touching = {finger: c for finger, c in ContactSensing(hand).fingers(state).items() if c.link is not None}
    if len(touching) < 2:
        raise InputError(f"a path check needs two or more touching fingers, got {sorted(touching)}")
    contacts = list(touching.values())
    return path_contacts(
        hand,
        state.q,
        [c.point for c in contacts],
        [str(c.link) for c in contacts],
        shape,
        state.object_poses[0],
        offset,
        steps,
        tolerance,
        list(touching),
    )


__all__ = ["LIMIT_TOLERANCE", "STEPS", "path_contacts", "sensed_path_contacts"]
