"""A grasp-benchmark trial's record from its trajectory (:mod:`~bhgrasp.bench.protocol`).

The object's pose in the palm frame through the shake against the held pose (success, strict), the lifted height,
the placement, the hand's contacts on the object (peak force, slip) and the finger pucks' (or joints') peak torque,
and why a trial failed.
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin

import bhgrasp as bh
from bhgrasp.bench.protocol import DIRECTIONS, FORCE_LIMIT, HELD_AT, LIFT, LOOSE, SHAKE_TIME, STAND, STRICT, Trial


def evaluate(trial: Trial, trajectory, hand: bh.Hand) -> dict:
    """A trial's record from its trajectory.

    Lifted height, displacement and rotation in the palm frame through the shake, the envelope (peak forces, finger
    joint torques against their ratings), success, placement, slip, and why it failed.
    """
    t = trajectory.t
    held = min(int(np.searchsorted(t, HELD_AT - 1e-9)), len(t) - 1)
    shaken = min(int(np.searchsorted(t, HELD_AT + 6 * SHAKE_TIME - 1e-9)), len(t) - 1)
    positions, rotations = relative_poses(hand, trajectory)
    offsets = np.linalg.norm(positions[held : shaken + 1] - positions[held], axis=1)
    turns = np.array([np.linalg.norm(pin.log3(rotations[held].T @ r)) for r in rotations[held : shaken + 1]])
    lifted = float(trajectory.object_position[held, 0, 2] - trajectory.object_position[0, 0, 2])
    held_through = lifted > 0.5 * LIFT and t[-1] >= HELD_AT + 6 * SHAKE_TIME - 1e-9  # not stopped: still in the scene
    record = {
        "object": trial.item.name,
        "spec": trial.item.spec,
        "grasp": trial.grasp,
        "actuation": trial.actuation,
        "spread": trial.preshape_spread,
        "lifted": lifted,
        "max_displacement": float(offsets.max()),
        "max_rotation": float(turns.max()),
    }
    record.update(contact_summary(trajectory, hand, held, shaken))
    record.update(joint_load(trajectory, hand))
    record["inside_envelope"] = bool(
        max(record["peak_contact_force"], record["peak_stand_force"]) <= FORCE_LIMIT
        and record["torque_to_rating"] <= 1.0
    )
    kept = held_through and record["inside_envelope"]
    record["success"] = bool(kept and offsets.max() < LOOSE[0] and turns.max() < LOOSE[1])
    record["strict_success"] = bool(kept and offsets.max() < STRICT[0] and turns.max() < STRICT[1])
    final = trajectory.object_position[-1, 0, 2] - trajectory.object_position[0, 0, 2]
    record["placed"] = bool(record["success"] and abs(final) < 0.005)  # set down and let go at its resting height
    record["failure"] = failure_reason(record, offsets, turns, t[held : shaken + 1], float(t[-1]))
    return record


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


def contact_summary(trajectory, hand: bh.Hand, held: int, shaken: int) -> dict:
    """The hand's peak force [N] on the object, its sliding contact samples while held, its peak force on the stand.

    Contacts of a hand link (body a) on the object (body b) count, not the stand's; "held" is the lift's end to the
    shake's end.
    """
    links = {frame.name for frame in hand.model.frames}
    bodies = trajectory.pair_bodies[trajectory.contact_pair]
    on_object = np.array([a in links and b == trajectory.object_names[0] for a, b in bodies], dtype=bool)
    on_stand = np.array([STAND in (a, b) and (a in links or b in links) for a, b in bodies], dtype=bool)
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
    joints = [hand.joint_index(f"{f}_{j}") for f in hand.fingers for j in ("proximal", "distal")]
    peaks = np.abs(trajectory.tau[:, joints]).max(axis=0)
    ratios = peaks / hand.effort_limit[joints]
    worst = int(np.argmax(ratios))
    return {
        "peak_joint_torque": float(peaks.max()),
        "torque_to_rating": float(ratios[worst]),
        "most_loaded_joint": hand.joint_names[joints[worst]],
    }


def failure_reason(record: dict, offsets: np.ndarray, turns: np.ndarray, times: np.ndarray, end: float) -> str:
    """Why a trial failed ('' if it succeeded).

    Not lifted, the push direction that moved the object too far, or the object leaving the scene (the run's
    ``end`` [s] before the shake's).
    """
    if record["lifted"] <= 0.5 * LIFT:
        reason = f"not lifted: the object rose {1e3 * record['lifted']:.0f} mm of the wrist's {1e3 * LIFT:.0f}"
        if record["peak_stand_force"] > 0.0:
            reason += f"; the fingers pressed the stand with up to {record['peak_stand_force']:.0f} N"
        return reason
    if record["success"]:
        return ""
    if not record["inside_envelope"]:
        force = max(record["peak_contact_force"], record["peak_stand_force"])
        return (
            f"outside the real hand's envelope: peak contact {force:.0f} N (limit {FORCE_LIMIT:.0f}), "
            f"{record['most_loaded_joint']} at {record['torque_to_rating']:.2f} x its rating"
        )
    moved = np.flatnonzero((offsets >= LOOSE[0]) | (turns >= LOOSE[1]))
    if len(moved) == 0:
        return f"the object left the scene at {end:.2f} s"
    k = int(moved[0])
    direction = DIRECTIONS[min(int((times[k] - HELD_AT) // SHAKE_TIME), 5)]
    return f"moved {1e3 * offsets[k]:.0f} mm / {math.degrees(turns[k]):.0f} deg under the {direction} push"


__all__ = ["contact_summary", "evaluate", "failure_reason", "joint_load", "relative_poses"]
