"""The compiled engine of :class:`~bhgrasp.controllers.mount.MountServo`: a wrist servo on a pose path in one call.

``bhgrasp._core.WristServo`` (``src/wrist_servo.cpp``) evaluates what the Python twin evaluates each call once the
state is checked: the path's pose sample (:class:`~bhgrasp.motion.pose_references.PosePath` or one
:class:`~bhgrasp.motion.pose_references.PoseMotion`, optionally stopped by a
:class:`~bhgrasp.motion.held.HeldReference`), its mount coordinates, rates and accelerations
(:class:`~bhgrasp.motion.wrist.MountReference`), the inverse dynamics and the servo's torques.  It covers a servo
whose reference is such a path and whose load is not fed forward, with the fingers' rows zero or held.  The path is
copied when the servo is built; the hold time is read from the ``HeldReference`` at every call.
``tests/test_wrist_servo.py`` holds both engines in lockstep.
"""

from __future__ import annotations

import math
from types import ModuleType
from typing import Any, Protocol

import numpy as np

from bhgrasp.controllers._pose_path import path_arguments, pose_moves
from bhgrasp.model.hand import Hand
from bhgrasp.motion.held import HeldReference
from bhgrasp.motion.pose_references import PoseMotion
from bhgrasp.motion.trajectories import Reference
from bhgrasp.motion.wrist import MountReference


class ServoSetup(Protocol):
    """What the compiled servo reads of a :class:`~bhgrasp.controllers.mount.MountServo`."""

    nominal: Hand
    reference: Reference
    fingers: Any
    kp: np.ndarray
    kd: np.ndarray
    finger_kp: float
    finger_kd: float
    compensate_load: bool


def path_of(reference: Reference) -> tuple[list[PoseMotion], MountReference, HeldReference | None] | None:
    """The moves, the mount reference and the hold of a reference the compiled servo covers (else ``None``)."""
    held = reference if type(reference) is HeldReference else None
    mount = reference.reference if held is not None else reference
    if type(mount) is not MountReference:
        return None
    moves = pose_moves(mount.pose)
    return None if moves is None else (moves, mount, held)


def covers(servo: ServoSetup) -> list[str]:
    """What of ``servo``'s set-up the compiled engine does not cover (empty: all of it)."""
    uncovered = []
    if path_of(servo.reference) is None:
        uncovered.append("a reference other than a MountReference of a PosePath or PoseMotion (held or not)")
    if servo.compensate_load:
        uncovered.append("compensate_load=True")
    if callable(servo.fingers):
        uncovered.append("a finger controller")
    return uncovered


class CompiledWristServo:
    """``bhgrasp._core.WristServo`` built from a :class:`~bhgrasp.controllers.mount.MountServo` it covers."""

    def __init__(self, servo: ServoSetup, core: ModuleType) -> None:
        found = path_of(servo.reference)
        if found is None:
            raise ValueError("the compiled wrist servo does not cover this reference")
        moves, mount, self.held = found
        hand = servo.nominal
        self.kernel = core.WristServo(
            model=hand.model.saveToString(),
            gravity=np.array(hand.model.gravity.linear),
            **path_arguments(moves),
            origin_rotation=np.array(mount.origin.rotation),
            origin_translation=np.array(mount.origin.translation),
            kp=servo.kp,
            kd=servo.kd,
            hold_fingers=servo.fingers is None,
            finger_kp=float(servo.finger_kp),
            finger_kd=float(servo.finger_kd),
        )

    def held_at(self) -> float:
        """Where the path stopped [s], NaN if it did not."""
        held = None if self.held is None else self.held.held
        return math.nan if held is None else held

    def torques(self, t: float, q: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(joint torques, c_d, c - c_d) at ``t`` [s] for the checked (q, v)."""
        return self.kernel.torques(t, self.held_at(), q, v)

    def reference(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The mount coordinates, rates and accelerations at ``t`` [s] (the servo's reference)."""
        return self.kernel.reference(t, self.held_at())

    def reset(self) -> None:
        """The next call takes the fingers' hold."""
        self.kernel.reset()
