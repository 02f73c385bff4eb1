"""The Simulator's boundary: whether a state belongs to its scene, and what a divergence it found says.

A state that the Simulator's own step made is trusted (its arrays are read-only); any other state, a copy, a
``dataclasses.replace``, a state of another simulator of the same scene or one a user built, is checked here in
full before a step, so that nothing malformed reaches an engine (Pinocchio's and coal's own errors name no field, and
coal's narrow phase crashes on coordinates near 1e155 m).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from bhgrasp.data import ContactMemory, State
from bhgrasp.errors import InputError, SimulationDiverged
from bhgrasp.sim.scene import Scene
from bhgrasp.sim.scene_layout import SceneLayout
from bhgrasp.sim.settings import SimulatorSettings

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


_KINDS = {
    1: ("joint/object position (coordinate {index})", "{value}", "reduce dt or the controller gains"),
    2: ("joint/object velocity (coordinate {index})", "{value}", "reduce dt or the controller gains"),
    3: ("speed of velocity coordinate {index}", "{value:.3g}", "reduce dt or gains"),
    4: ("contact depth", "{value:.4g} m", "stiffen the contact or reduce dt/forces"),
    5: ("coordinate {index}", "{value:.4g}", "beyond max_coordinate = {bound:g} [m or rad]"),
}


def describe_divergence(t: float, divergence: Any, settings: SimulatorSettings) -> SimulationDiverged:
    """The error for an engine's divergence record (``kind``, ``index``, ``value``): it names the value it saw."""
    quantity, value, hint = _KINDS[int(divergence.kind)]
    fields = {"index": int(divergence.index), "value": float(divergence.value), "bound": settings.max_coordinate}
    return SimulationDiverged(t, quantity.format(**fields), value.format(**fields), hint.format(**fields))


def divergence_text(divergence: Any) -> str:
    """A divergence record in words, e.g. ``"joint/object position (coordinate 12) = nan"`` ("" if none)."""
    if not divergence.kind:
        return ""
    quantity, value, _ = _KINDS[int(divergence.kind)]
    fields = {"index": int(divergence.index), "value": float(divergence.value)}
    return f"{quantity.format(**fields)} = {value.format(**fields)}"


__all__ = ["QUATERNION_TOLERANCE", "check_state", "describe_divergence", "divergence_text"]
