"""The grasp chosen for the motion asked, for any object: the first synthesised BH8-280 grasp that makes it.

The candidates are :func:`~bhgrasp.grasp.synthesis.grasp_candidates`' (best first: the Ferrari-Canny epsilon, then
whether and by how much the weight is held).  Those in force closure that hold the weight in their cones are checked
before anything is simulated: the requested offset must lie in the grasp's manipulable space at the planned contacts
(no contact slides or rolls, no joint passes its limit), keep the object off its pedestal, and keep the hand's other
shapes off the object along the path with the contacts rolling (:func:`~bhgrasp.grasp.path_check.path_contacts`).
The first that passes is run
(:func:`~bhgrasp.scenarios.object_grasp.run_object_grasp`).  When the move starts the supervisor checks the path again
at the contacts the fingers sense (the pads have sunk about half a millimetre under the squeeze, and land a little off
the plan); if it refuses, the next candidate that passes is run, at most :data:`TRIES` runs in all.  The result keeps
the chosen grasp and why each one before it was refused (:class:`~bhgrasp.scenarios.grasp_choice.GraspChoice`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace
from typing import Any

import numpy as np

from bhgrasp._validation import as_vector
from bhgrasp.errors import InputError, UnreachableError
from bhgrasp.grasp.candidates import GraspCandidate
from bhgrasp.grasp.path_check import path_contacts
from bhgrasp.grasp.synthesis import grasp_candidates
from bhgrasp.model.barrett_hand import BarrettHand
from bhgrasp.model.objects import RigidObject
from bhgrasp.scenarios.box_grasp import FRICTION
from bhgrasp.scenarios.demo_result import MU_ASSUMED, GraspDemoResult
from bhgrasp.scenarios.grasp_choice import GraspChoice, checked_pinch
from bhgrasp.scenarios.object_grasp import ObjectGrasp, object_grasp, run_object_grasp

TRIES = 3  # runs the supervisor may refuse when the move starts before the choice gives up (each costs a run)


def describe(candidate: GraspCandidate) -> str:
    """A grasp in a few words: its fingers, spread and force-closure quality."""
    return (
        f"{'+'.join(candidate.fingers)}, spread {np.degrees(candidate.spread):.0f} deg, "
        f"epsilon {candidate.quality.epsilon:.3f}"
    )


def checked_candidate(setup: ObjectGrasp, offset: Any) -> None:
    """Raise :class:`UnreachableError` unless ``setup``'s planned grasp makes ``offset`` (before simulating).

    Its manipulable space at the planned contacts, the pedestal's clearance and the path with the contacts rolling.
    """
    checked_pinch(setup, offset)  # the manipulable space and the pedestal, as for the demo's pinches
    c, hand = setup.candidate, setup.hand
    frames = [hand.fingertip_frames[f] for f in c.fingers]
    shape, pose = setup.item.geometry(), setup.item.pose
    path_contacts(hand, c.q_contact, c.points, frames, shape, pose, offset, labels=list(c.fingers)).check()


def grasp_for_motion(
    item: Any,
    offset: Any,
    duration: float = 3.0,
    candidates: Sequence[GraspCandidate] | None = None,
    tries: int = TRIES,
    mu: float = MU_ASSUMED,
) -> GraspDemoResult:
    """Grasp ``item`` with the first candidate that makes ``offset`` and run it (module docstring).

    Args:
        item: The object (a :class:`~bhgrasp.model.objects.RigidObject` placed in the BH8-280's world).
        offset: The motion (position [m], rotation vector [rad], world) after the squeeze.
        duration: Simulated time of each run [s].
        candidates: The grasps to choose from, best first (default: :func:`~bhgrasp.grasp.synthesis.grasp_candidates`
            of ``item`` at ``mu``).
        tries: Most runs, an integer >= 1 (each refused when its move starts passes to the next candidate).
        mu: The friction coefficient the synthesis assumes (unused when ``candidates`` are given).

    Returns:
        The chosen grasp's run; its ``grasp_choice`` names the grasp and why the ones before it were refused.

    Raises:
        InputError: ``item`` is not a rigid object, ``offset`` not 6 finite numbers, or ``tries`` not an integer >= 1.
        UnreachableError: No candidate makes the motion (or ``tries`` runs were refused); the message gives the
            count and the first candidate's reason, its ``result`` every (candidate, reason).
    """
    if not isinstance(item, RigidObject):
        raise InputError(f"`item` must be a bhgrasp rigid object (Box, Cylinder, Sphere, ...), got {item!r}")
    offset = as_vector(offset, "offset", 6)
    if isinstance(tries, bool) or not isinstance(tries, (int, np.integer)) or tries < 1:
        raise InputError(f"`tries` must be an integer >= 1, got {tries!r}")
    if candidates is None:
        candidates = grasp_candidates(BarrettHand(), replace(item, friction=FRICTION, density=None), mu)
    refused: list[tuple[str, str]] = []
    runs = 0
    for rank, candidate in enumerate(candidates, start=1):
        label = f"candidate {rank} of {len(candidates)} ({describe(candidate)})"
        if not (candidate.quality.force_closure and candidate.holds_weight):  # e.g. two opposed pads
            refused.append((label, "not a force-closure grasp that holds the weight in its cones"))
            continue
        setup = object_grasp(item, candidate=candidate, mu=mu)
        try:
            checked_candidate(setup, offset)
        except UnreachableError as error:
            refused.append((label, str(error)))
            continue
        runs += 1
        try:
            result = run_object_grasp(setup, offset=offset, duration=duration)
        except UnreachableError as error:
            refused.append((label, f"refused when the move started: {error}"))
            if runs >= tries:
                break
            continue
        return replace(result, grasp_choice=GraspChoice(label, None, tuple(refused)))
    motion = np.round(np.asarray(offset, dtype=float), 6).tolist()
    first = f" The first, {refused[0][0]}: {refused[0][1]}" if refused else ""
    if runs >= tries:
        raise UnreachableError(
            f"the supervisor refused the motion {motion} when the move started in all {runs} runs allowed "
            f"(`tries`), after {len(refused) - runs} grasps refused before simulating.{first}",
            tuple(refused),
        )
    raise UnreachableError(
        f"none of the {len(candidates)} synthesised BH8-280 grasps of this object makes the motion {motion} "
        f"({runs} refused when the move started).{first}",
        tuple(refused),
    )


__all__ = ["TRIES", "checked_candidate", "describe", "grasp_for_motion"]
