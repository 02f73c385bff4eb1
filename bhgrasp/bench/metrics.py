"""A grasp-benchmark trial's record from its trajectory (:mod:`~bhgrasp.bench.protocol`).

The object's pose in the palm frame from the closed grasp before the lift through the shake (success, strict), the
lifted height, the grip (each finger's normal force on the object once lifted, no distal link on its stop), the
placement, the hand's contacts on the object (peak force, slip), the finger joints' peak torque against their
ratings, and why a trial failed.
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin

import bhgrasp as bh
from bhgrasp.bench.need import INFEASIBLE, protocol_need, rated_joints
from bhgrasp.bench.opening import top_down
from bhgrasp.bench.protocol import (
    DIRECTIONS,
    FORCE_LIMIT,
    FRICTION,
    HELD_AT,
    LIFT,
    LIFT_AT,
    LOOSE,
    SHAKE_TIME,
    STAND,
    STRICT,
    Trial,
)
from bhgrasp.bench.side import PINCH, approach_of, closing_fingers, trial_opening, trial_spread
from bhgrasp.bench.table import supports
from bhgrasp.data.trajectory import Trajectory
from bhgrasp.model.hand import STANDARD_GRAVITY

GRAVITY = -STANDARD_GRAVITY[2]  # [m/s^2] the simulated hand's (bhgrasp.model.hand)
NO_HEIGHT = (
    "no grasp height: from the knuckles on its top to 6 cm above, some finger first touches its top face (or, in a "
    "precision grasp, not with its fingertip), meets the stand first, or misses it (bench.height.grasp_clearance), "
    "and no side pinch is taken (bench.side: none qualifies, or the trial fixes its spread); run with the knuckles "
    "on its top"
)
STOP_MARGIN = 0.01  # [rad] a distal joint this close to its upper limit rests on its stop
PLACED = 0.002  # [m] placed: back within this of its resting height, the stand carrying at least half its weight


def evaluate(trial: Trial, trajectory, hand: bh.Hand, heading: float = 0.0) -> dict:
    """A trial's record from its trajectory.

    The approach, spread and opening (proximal angle [rad] of the open hand); lifted height; displacement and rotation
    in the palm frame from the closed grasp before the lift (the lift's sag counts) through the shake; the grip once
    lifted (each finger's normal force on the object against :func:`least_grip`, distal joints off their stops); the
    envelope (peak forces, finger joint torques against their ratings) and what the protocol's loads need of the
    ratings at the held grasp (``need_to_rating``, ``need_joint``: :mod:`~bhgrasp.bench.need`; the pushes turned
    ``heading`` [rad] with the hand); success (held, gripped, inside the envelope, within the thresholds, and placed
    back), slip, and why it failed.
    """
    t = trajectory.t
    closed = min(int(np.searchsorted(t, LIFT_AT - 1e-9)), len(t) - 1)
    held = min(int(np.searchsorted(t, HELD_AT - 1e-9)), len(t) - 1)
    shaken = min(int(np.searchsorted(t, HELD_AT + 6 * SHAKE_TIME - 1e-9)), len(t) - 1)
    positions, rotations = relative_poses(hand, trajectory)
    offsets = np.linalg.norm(positions[closed : shaken + 1] - positions[closed], axis=1)
    turns = np.array([np.linalg.norm(pin.log3(rotations[closed].T @ r)) for r in rotations[closed : shaken + 1]])
    lifted = float(trajectory.object_position[held, 0, 2] - trajectory.object_position[0, 0, 2])
    held_through = lifted > 0.5 * LIFT and t[-1] >= HELD_AT + 6 * SHAKE_TIME - 1e-9  # not stopped: still in the scene
    record = {
        "object": trial.item.name,
        "spec": trial.item.spec,
        "grasp": trial.grasp,
        "actuation": trial.actuation,
        "approach": approach_of(trial),
        "spread": trial_spread(trial),
        "opening": trial_opening(trial),
        "lifted": lifted,
        "max_displacement": float(offsets.max()),
        "max_rotation": float(turns.max()),
        "height_found": approach_of(trial) == "side"
        or top_down(trial.item, trial.preshape_spread, trial.grasp, trial.table) is not None,
        "approach_stopped": approach_stopped(trajectory),
    }
    record["approach_met"] = met_on_approach(trajectory, hand, record["approach_stopped"])
    record.update(contact_summary(trajectory, hand, held, shaken, supports(trial)))
    record.update(joint_load(trajectory, hand))
    record["need_to_rating"], record["need_joint"] = protocol_need(trajectory, hand, held, trial.item.mass, heading)
    forces = held_forces(trajectory, hand, held)
    record.update({f"held_force_{finger}": float(f) for finger, f in zip(hand.fingers, forces)})
    distal = [hand.joint_index(f"{finger}_distal") for finger in hand.fingers]
    stops = [f for f, j in zip(hand.fingers, distal) if trajectory.q[held, j] >= hand.upper[j] - STOP_MARGIN]
    record["on_stop"] = ", ".join(stops)
    closing = closing_fingers(trial)  # a side pinch's F3 stays open
    gripping = min(f for finger, f in zip(hand.fingers, forces) if finger in closing)
    record["gripped"] = bool(gripping >= least_grip(trial.item.mass, len(closing)) and not stops)
    record["inside_envelope"] = bool(
        max(record["peak_contact_force"], record["peak_stand_force"]) <= FORCE_LIMIT
        and record["torque_to_rating"] <= 1.0
    )
    final = trajectory.object_position[-1, 0, 2] - trajectory.object_position[0, 0, 2]
    resting = stand_support(trajectory, len(t) - 1, supports(trial)) >= 0.5 * trial.item.mass * GRAVITY
    record["placed"] = bool(held_through and abs(final) < PLACED and resting)  # set down on its stand and let go
    kept = held_through and record["inside_envelope"] and record["gripped"] and record["placed"]
    record["success"] = bool(kept and offsets.max() < LOOSE[0] and turns.max() < LOOSE[1])
    record["strict_success"] = bool(kept and offsets.max() < STRICT[0] and turns.max() < STRICT[1])
    record["failure"] = failure_reason(record, offsets, turns, t[closed : shaken + 1], float(t[-1]), trial.item.mass)
    return record


def approach_stopped(trajectory: Trajectory) -> float | None:
    """When the guarded approach stopped [s] (the hand met something on its way), or ``None``: it ran its course."""
    logged = trajectory.log.get("approach_stopped")
    return None if logged is None or not np.isfinite(logged).any() else float(np.nanmin(logged))


def met_on_approach(trajectory: Trajectory, hand: bh.Hand, stopped: float | None, window: float = 0.02) -> str:
    """What the hand met where its approach stopped, names, or '' (none recorded).

    The body of the pair the controller logged (``approach_met_pair``: the hand's hardest contact at the stop, an
    index into ``trajectory.pair_bodies``), else the bodies the hand touches in the samples from ``stopped`` [s] to
    ``window`` [s] after it (an impact may part before the next sample).
    """
    if stopped is None:
        return ""
    logged = trajectory.log.get("approach_met_pair")
    pair = np.nanmax(logged) if logged is not None and np.isfinite(logged).any() else -1.0
    if pair >= 0:
        a, b = (str(name) for name in trajectory.pair_bodies[int(pair)])
        return b if hand.model.existFrame(a) else a
    first, last = np.searchsorted(trajectory.t, [stopped - 1e-9, stopped + window])
    touched = set()
    for k in range(int(first), min(int(last) + 1, len(trajectory.t))):
        for a, b in trajectory.contacts_at(k)["bodies"]:
            if hand.model.existFrame(str(a)) != hand.model.existFrame(str(b)):
                touched.add(str(b) if hand.model.existFrame(str(a)) else str(a))
    return ", ".join(sorted(touched))


def least_grip(mass: float, fingers: int = 3) -> float:
    """The least normal force [N] each of the ``fingers`` that grip must press with, m g / (fingers mu).

    By friction alone (mu the protocol's :data:`~bhgrasp.bench.protocol.FRICTION`) that many such presses carry the
    object's weight (three, or a side pinch's two).
    """
    return mass * GRAVITY / (fingers * FRICTION)


def held_forces(trajectory, hand: bh.Hand, k: int) -> np.ndarray:
    """(3,) each finger's normal force [N] on the object at sample ``k``: its inner and outer links' contacts.

    The knuckles (on the palm's side of the proximal joints) do not grip: a knuckle pressing on an object's top is
    not a finger's hold.
    """
    contacts = trajectory.contacts_at(k)
    pressing = np.einsum("ij,ij->i", contacts["normal"], contacts["force"])  # along the normal, onto the object
    links = {f"{f}_{part}_link": i for i, f in enumerate(hand.fingers) for part in ("proximal", "distal")}
    totals = np.zeros(len(hand.fingers))
    for (a, b), force in zip(contacts["bodies"], pressing):
        if b == trajectory.object_names[0] and a in links:
            totals[links[a]] += max(float(force), 0.0)
    return totals


def stand_support(trajectory, k: int, stand: frozenset[str] = frozenset({STAND})) -> float:
    """The stand's upward push [N] on the object at sample ``k``.

    ``stand``: the bodies it stands on (among neighbours the table around the stand too, flush with it,
    :func:`~bhgrasp.bench.table.supports`: an object set down across their seam rests on both).
    """
    contacts = trajectory.contacts_at(k)
    obj = trajectory.object_names[0]
    rows = [i for i, (a, b) in enumerate(contacts["bodies"]) if {a, b} & stand and obj in (a, b)]
    return float(contacts["force"][rows, 2].sum()) if rows else 0.0


def relative_poses(hand: bh.Hand, trajectory) -> tuple[np.ndarray, np.ndarray]:
    """Per sample, the object's position [m] and rotation (3, 3) in the palm frame (the hand base's)."""
    positions, rotations = [], []
    for k in range(len(trajectory.t)):
        palm = hand.frame_placement(trajectory.q[k], "palm")
        rotation = pin.Quaternion(*np.roll(trajectory.object_quaternion[k, 0], 1)).toRotationMatrix()
        relative = palm.actInv(pin.SE3(rotation, trajectory.object_position[k, 0]))
        positions.append(relative.translation)
        rotations.append(relative.rotation)
    return np.array(positions), np.array(rotations)


def contact_summary(
    trajectory, hand: bh.Hand, held: int, shaken: int, stand: frozenset[str] = frozenset({STAND})
) -> dict:
    """The hand's peak force [N] on the object, its sliding contact samples while held, its peak force on the stand.

    Contacts of a hand link (body a) on the object (body b) count, not the stand's; "held" is the lift's end to the
    shake's end.  ``stand``: the bodies the hand may press instead (the stand; among neighbours the table too,
    :func:`~bhgrasp.bench.table.supports`).
    """
    links = {frame.name for frame in hand.model.frames}
    bodies = trajectory.pair_bodies[trajectory.contact_pair]
    on_object = np.array([a in links and b == trajectory.object_names[0] for a, b in bodies], dtype=bool)
    on_stand = np.array([(a in stand or b in stand) and (a in links or b in links) for a, b in bodies], dtype=bool)
    magnitudes = np.linalg.norm(trajectory.contact_force, axis=1)
    forces = magnitudes * on_object
    rows = slice(trajectory.contact_offsets[held], trajectory.contact_offsets[shaken + 1])
    loaded = (forces[rows] > 0.1) & ~trajectory.contact_sticking[rows]
    return {
        "peak_contact_force": float(forces.max(initial=0.0)),
        "slip_samples": int(loaded.sum()),
        "peak_stand_force": float((magnitudes * on_stand).max(initial=0.0)),
    }


def joint_load(trajectory, hand: bh.Hand) -> dict:
    """The finger joints' peak torque [N m] through the trial and its largest ratio to a joint's rating.

    The torques are the drive's with the worms' reactions; a rating is the hand's effort limit; the most loaded
    joint is named.
    """
    joints = rated_joints(hand)
    peaks = np.abs(trajectory.tau[:, joints]).max(axis=0)
    ratios = peaks / hand.effort_limit[joints]
    worst = int(np.argmax(ratios))
    return {
        "peak_joint_torque": float(peaks.max()),
        "torque_to_rating": float(ratios[worst]),
        "most_loaded_joint": hand.joint_names[joints[worst]],
    }


def failure_reason(
    record: dict, offsets: np.ndarray, turns: np.ndarray, times: np.ndarray, end: float, mass: float = 0.0
) -> str:
    """Why a trial failed ('' if it succeeded).

    No grasp height (:data:`NO_HEIGHT`, then the rest), not lifted, a finger not gripping (``mass`` [kg] sets the
    least grip) or on its stop, outside the envelope, the phase or push direction that moved the object too far
    (``times`` [s]: the samples of ``offsets`` and ``turns`` from before the lift), the object leaving the scene (the
    run's ``end`` [s] before the shake's), or not placed.
    """
    reason = _failure(record, offsets, turns, times, end, mass)
    if reason and record.get("approach_stopped") is not None and "approach stopped" not in reason:
        reason += f" ({_stopped(record)})"
    return f"{NO_HEIGHT}; {reason}" if reason and not record.get("height_found", True) else reason


def _stopped(record: dict) -> str:
    """Where the guarded approach stopped, as a failure's clause."""
    met = record.get("approach_met") or "something"
    return f"the approach stopped at {record['approach_stopped']:.2f} s, where the hand met {met}"


def _need(record: dict) -> str:
    """What the held grasp needed of the ratings at least (bench.need), as the envelope failure's last clause."""
    need, joint = record.get("need_to_rating"), record.get("need_joint")
    if joint == INFEASIBLE:
        return "; at the held grasp's contacts no forces inside the friction cones carry some protocol load at rest"
    if need is None:
        return ""
    return (
        f"; at the held grasp's contacts no forces inside the friction cones carry the protocol's loads at rest with "
        f"less than {need:.2f} x the ratings ({joint})"
    )


def _failure(record: dict, offsets: np.ndarray, turns: np.ndarray, times: np.ndarray, end: float, mass: float) -> str:
    """:func:`failure_reason` once the grasp height is known to exist, or not."""
    if record["lifted"] <= 0.5 * LIFT:
        reason = f"not lifted: the object rose {1e3 * record['lifted']:.0f} mm of the wrist's {1e3 * LIFT:.0f}"
        if record["peak_stand_force"] > 0.0:
            reason += f"; the fingers pressed the stand with up to {record['peak_stand_force']:.0f} N"
        if record.get("approach_stopped") is not None:
            reason += f"; {_stopped(record)}"
        return reason
    if record["success"]:
        return ""
    if record.get("on_stop"):
        return f"caged, not gripped: the distal joint of {record['on_stop']} rests on its stop"
    closing = PINCH if record.get("approach") == "side" else ("F1", "F2", "F3")
    weakest = min(closing, key=lambda f: record.get(f"held_force_{f}", np.inf))
    least = least_grip(mass, len(closing))
    if record.get(f"held_force_{weakest}", np.inf) < least:
        return (
            f"not gripped: {weakest} presses the object with {record[f'held_force_{weakest}']:.2f} N once lifted "
            f"(each finger needs {least:.2f} N to carry its weight by friction)"
        )
    if not record["inside_envelope"]:
        force = max(record["peak_contact_force"], record["peak_stand_force"])
        return (
            f"outside the real hand's envelope: peak contact {force:.0f} N (limit {FORCE_LIMIT:.0f}), "
            f"{record['most_loaded_joint']} at {record['torque_to_rating']:.2f} x its rating{_need(record)}"
        )
    moved = np.flatnonzero((offsets >= LOOSE[0]) | (turns >= LOOSE[1]))
    if len(moved) == 0:
        if end < HELD_AT + 6 * SHAKE_TIME - 1e-9:
            return f"the object left the scene at {end:.2f} s"
        return "not placed: the object did not end resting on its stand at its height after the release"
    k = int(moved[0])
    if times[k] <= HELD_AT:
        when = "during the lift"
    else:  # push k's samples are (HELD_AT + k SHAKE_TIME, HELD_AT + (k + 1) SHAKE_TIME] (bench.trial.run_protocol)
        when = f"under the {DIRECTIONS[min(math.ceil((times[k] - HELD_AT) / SHAKE_TIME - 1e-9) - 1, 5)]} push"
    return f"moved {1e3 * offsets[k]:.0f} mm / {math.degrees(turns[k]):.0f} deg {when}"


__all__ = [
    "NO_HEIGHT",
    "approach_stopped",
    "contact_summary",
    "evaluate",
    "failure_reason",
    "held_forces",
    "joint_load",
    "least_grip",
    "met_on_approach",
    "relative_poses",
]
