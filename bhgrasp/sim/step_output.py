"""What a step makes beside its new state: the :class:`StepInfo` it returns and the source of its state's fields.

Either engine's contacts and contact memory stay as the engine made them (a ``ContactSet``/``ContactMemory`` of the
Python engine, or the compiled engine's ``Contacts``/``Memory``) and are converted only when first read.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, NamedTuple, Protocol

import numpy as np

from bhgrasp.data import ContactMemory, ContactSet, State, empty_contact_set
from bhgrasp.sim.scene_layout import SceneLayout, object_states

if TYPE_CHECKING:
    from bhgrasp.sim.engine import Engine
    from bhgrasp.sim.scene import Scene


class StepSource(Protocol):
    """What a state's derived fields are read from: the stepping simulator's scene, layout and engine."""

    scene: Scene
    layout: SceneLayout
    engine: Engine


class StepInfo:
    """What one step computed, beyond the new state: contacts with their forces and the drive torques.

    Attributes:
        contacts: The step's contacts and forces, a :class:`~bhgrasp.data.contacts.ContactSet` (built when first
            read).
        drive_torques: Hand joint torques the drive delivered over the step [N m], (nv_hand,).
        contact_arrays: The contacts as the engine returned them: a ``ContactSet``, or the compiled engine's
            ``Contacts``; both carry the arrays ``pair``, ``point``, ``normal``, ``depth``, ``force``, ``sticking``.
    """

    __slots__ = ("_contacts", "_engine", "_result")

    def __init__(self, result: Any, engine: Engine | None = None) -> None:
        """``result``: the engine's step (``contacts`` and ``drive`` read from it when asked for)."""
        self._result, self._engine, self._contacts = result, engine, None

    @classmethod
    def empty(cls, nv_hand: int) -> StepInfo:
        """The information before any step: no contacts, no drive torque."""
        return cls(_Empty(empty_contact_set(), np.zeros(nv_hand)))

    @property
    def contact_arrays(self) -> Any:
        """The step's contacts as the engine returned them."""
        return self._result.contacts

    @property
    def drive_torques(self) -> np.ndarray:
        """Hand joint torques the drive delivered over the step [N m], (nv_hand,)."""
        return self._result.drive

    @property
    def contacts(self) -> ContactSet:
        """The step's contacts as a :class:`~bhgrasp.data.contacts.ContactSet` (built on first read, then kept)."""
        if self._contacts is None:
            arrays = self._result.contacts
            self._contacts = arrays if isinstance(arrays, ContactSet) else self._engine.contact_set(arrays)
        return self._contacts


class _Empty(NamedTuple):
    """A step's result as :class:`StepInfo` reads it, before any step."""

    contacts: ContactSet
    drive: np.ndarray


class StepOutput:
    """What a step hands to its :class:`~bhgrasp.data.state.SimulatedState` to build derived fields from.

    ``simulator``: the Simulator whose step made the state; ``contacts``: the step's ``ContactSet`` or compiled
    ``Contacts``; ``memory``: its ``ContactMemory`` or compiled ``Memory``; ``start``: the problems of the initial
    state the run began from (:mod:`~bhgrasp.sim.start_check`), handed on from step to step.
    """

    __slots__ = ("contacts", "memory", "simulator", "start")

    def __init__(self, simulator: StepSource, contacts: Any, memory: Any, start: tuple = ()) -> None:
        self.simulator, self.contacts, self.memory, self.start = simulator, contacts, memory, start

    def derive(self, name: str, state: State) -> dict[str, Any]:
        """The derived field ``name`` of ``state`` (and its companions computed on the way)."""
        scene = self.simulator.scene
        if name in ("q", "v"):
            return {"q": state.scene_q[: scene.nq_hand].copy(), "v": state.scene_v[: scene.nv_hand].copy()}
        if name in ("object_poses", "object_twists"):
            poses, twists = object_states(scene, state.scene_q, state.scene_v)
            return {"object_poses": poses, "object_twists": twists}
        if name == "contact_memory":
            memory = self.memory
            if not isinstance(memory, ContactMemory):
                memory = self.simulator.engine.contact_memory(memory)
            return {"contact_memory": memory}
        contacts = self.contacts  # a ContactSet or the compiled Contacts: both carry the arrays read here
        if not len(contacts):
            contacts = empty_contact_set()
        return {
            "contact_points": contacts.point,
            "contact_normals": contacts.normal,
            "contact_forces": contacts.force,
            "contact_bodies": self.simulator.layout.body_names(contacts.pair),
        }


__all__ = ["StepInfo", "StepOutput", "StepSource"]
