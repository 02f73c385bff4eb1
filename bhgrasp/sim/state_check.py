"""The Simulator's boundary: whether a state belongs to its scene, and what a divergence it found says.

A state that the Simulator's own step made is trusted (its arrays are read-only); any other state, a copy, a
``dataclasses.replace``, a state of another simulator of the same scene or one a user built, is checked here in
full before a step, so that nothing malformed reaches an engine (Pinocchio's and coal's own errors name no field, and
coal's narrow phase crashes on coordinates near 1e155 m).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from bhgrasp.data import ContactMemory, ContactSet, State
from bhgrasp.errors import InputError, SimulationDiverged
from bhgrasp.sim.scene import Scene
from bhgrasp.sim.scene_layout import SceneLayout
from bhgrasp.sim.settings import SimulatorSettings
from bhgrasp.sim.start_check import summary

QUATERNION_TOLERANCE = 1e-6  # on | |quaternion| - 1 |: integration keeps it to ~1e-15, a hand-written one to its digits


def check_state(state: Any, scene: Scene, layout: SceneLayout, settings: SimulatorSettings) -> ContactMemory:
    """Check that ``state`` is a state of ``scene`` a step can start from; return its contact memory.

    Raises:
        InputError: Not a State; of another scene (its signature differs); ``scene_q`` or ``scene_v`` missing, of
            the wrong size or not finite; an object's quaternion not of unit length; a coordinate beyond
            ``settings.max_coordinate``; a time that is not finite; a contact memory that is not a ContactMemory.
    """
    if not isinstance(state, State):
        raise InputError(f"`state` must be a bhgrasp State, got {type(state).__name__}")
    signature = state.scene_signature
    if signature is not None and signature != layout.signature:
        raise InputError(
            f"`state` is a state of another scene (signature {signature[:12]}...), not of this simulator's "
            f"{scene!r} (signature {layout.signature[:12]}...); start from this simulator's initial_state()"
        )
    if not (isinstance(state.t, int | float | np.floating) and math.isfinite(state.t)):
        raise InputError(f"`state.t` must be a finite time [s], got {state.t!r}")
    q = _coordinates(state.scene_q, "scene_q", scene.nq)
    _coordinates(state.scene_v, "scene_v", scene.nv)
    for index, rows in enumerate(layout.quaternions):
        norm = float(np.linalg.norm(q[rows]))
        if not abs(norm - 1.0) <= QUATERNION_TOLERANCE:
            raise InputError(
                f"`state.scene_q[{rows.start}:{rows.stop}]` must be the unit quaternion (x, y, z, w) of object "
                f"{scene.object_names[_free_index(scene, index)]!r}, got {q[rows].tolist()} (norm {norm:.6g})"
            )
    largest = int(np.argmax(np.abs(q))) if len(q) else 0
    if len(q) and not abs(q[largest]) <= settings.max_coordinate:
        raise InputError(
            f"`state.scene_q[{largest}]` = {q[largest]:.4g} is beyond max_coordinate = {settings.max_coordinate:g} "
            "[m or rad] (a scene that far out has lost its precision; move it, or raise max_coordinate)"
        )
    memory = state.contact_memory
    if memory is None:
        return ContactMemory.empty()
    if not isinstance(memory, ContactMemory):
        raise InputError(f"`state.contact_memory` must be a ContactMemory or None, got {type(memory).__name__}")
    return memory


def _coordinates(values: Any, name: str, size: int) -> np.ndarray:
    """A state's ``scene_q`` or ``scene_v`` as a finite float array of ``size`` entries."""
    if values is None:
        raise InputError(
            f"`state.{name}` is missing: a State a controller reads carries no scene coordinates; step a state of "
            "this simulator (its initial_state() or one a step or run returned)"
        )
    try:
        array = np.asarray(values, dtype=float)
    except (TypeError, ValueError) as error:
        raise InputError(f"`state.{name}` must be {size} numbers, got {values!r}") from error
    if array.shape != (size,):
        raise InputError(f"`state.{name}` must have shape ({size},) for this simulator's scene, got {array.shape}")
    if not np.isfinite(array).all():
        bad = np.flatnonzero(~np.isfinite(array))
        raise InputError(f"`state.{name}` must be finite, got {array[bad[0]]} at index {int(bad[0])}")
    return array


def _free_index(scene: Scene, quaternion: int) -> int:
    """The object index of the ``quaternion``-th free object."""
    free = [i for i, item in enumerate(scene.objects) if not hasattr(item, "stiffness")]
    return free[quaternion]


_KINDS = {  # {where}: the coordinate and, with the scene, its joint or object ("coordinate 2, joint F1_distal")
    1: ("joint/object position ({where})", "{value}", "reduce dt or the controller gains"),
    2: ("joint/object velocity ({where})", "{value}", "reduce dt or the controller gains"),
    3: ("speed of velocity ({where})", "{value:.3g}", "reduce dt or gains"),
    4: ("contact depth", "{value:.4g} m", "stiffen the contact or reduce dt/forces"),
    5: ("{where}", "{value:.4g}", "beyond max_coordinate = {bound:g} [m or rad]"),
}


def describe_divergence(
    t: float,
    divergence: Any,
    settings: SimulatorSettings,
    scene: Scene | None = None,
    start: Sequence = (),
    contacts: ContactSet | None = None,
) -> SimulationDiverged:
    """The error for an engine's divergence record (``kind``, ``index``, ``value``): it names the value it saw.

    With the ``scene``, it names the joint or object the coordinate belongs to (and, given the step's ``contacts``,
    the bodies of the deepest contact); with the problems the run's start had
    (:func:`~bhgrasp.sim.start_check.start_problems`), it gives them as the likely cause instead of the generic hint.
    """
    kind = int(divergence.kind)
    quantity, value, hint = _KINDS[kind]
    fields = {"index": int(divergence.index), "value": float(divergence.value), "bound": settings.max_coordinate}
    fields["where"] = f"coordinate {fields['index']}"
    if scene is not None and kind in (1, 2, 3, 5) and fields["index"] >= 0:
        fields["where"] += f", {coordinate_owner(scene, fields['index'], velocity=kind in (2, 3))}"
    quantity = quantity.format(**fields)
    if scene is not None and kind == 4 and contacts is not None and len(contacts):
        pair = scene.pairs[int(contacts.pair[int(np.argmax(contacts.depth))])]
        quantity += f" ({pair.body_b} in {pair.body_a})"
    hint = hint.format(**fields)  # before any name is added: a name may hold braces
    if start:  # the likely cause instead of the generic cure (a bound passed stays named)
        cause = f"likely because {summary(list(start))}"
        hint = f"{hint}; {cause}" if kind == 5 else cause
    return SimulationDiverged(t, quantity, value.format(**fields), hint)


def coordinate_owner(scene: Scene, index: int, velocity: bool) -> str:
    """What a coordinate of the scene's ``q`` (or ``v``, ``velocity``) moves: ``"joint NAME"`` or ``"object NAME"``."""
    for i, name in enumerate(scene.object_names):
        span = scene.object_v_slice(i) if velocity else scene.object_q_slice(i)
        if span.start <= index < span.stop:
            return f"object {name}"
    model = scene.model
    for joint in range(1, model.njoints):
        start, size = (model.idx_vs[joint], model.nvs[joint]) if velocity else (model.idx_qs[joint], model.nqs[joint])
        if start <= index < start + size:
            return f"joint {model.names[joint]}"
    return f"coordinate {index}"


def divergence_text(divergence: Any) -> str:
    """A divergence record in words, e.g. ``"joint/object position (coordinate 12) = nan"`` ("" if none)."""
    if not divergence.kind:
        return ""
    quantity, value, _ = _KINDS[int(divergence.kind)]
    fields = {"index": int(divergence.index), "value": float(divergence.value)}
    fields["where"] = f"coordinate {fields['index']}"
    return f"{quantity.format(**fields)} = {value.format(**fields)}"


__all__ = ["QUATERNION_TOLERANCE", "check_state", "coordinate_owner", "describe_divergence", "divergence_text"]
