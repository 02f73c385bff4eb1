"""State: one instant as a controller sees it (plain data, no physics), and the lazily built state a simulator makes.

Units SI, angles in radians, world frame.  Object poses are the world poses of the objects' centre-of-mass frames;
object twists are (linear [m/s], angular [rad/s]) of the centre of mass in world-aligned coordinates.  Contact
forces act on the contact's body b (an object); the opposite force acts on body a.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pinocchio as pin


@dataclass(frozen=True, slots=True)
class State:
    """One instant of a simulation (or of a real hand's sensors).

    A simulator's states are :class:`SimulatedState`: the same fields, those derived from the scene's
    configuration and the step's contacts built when first read.

    Attributes:
        t: Time [s].
        q: Hand joint positions [rad], shape (nv_hand,).
        v: Hand joint velocities [rad/s].
        object_poses: World pose of each object.
        object_twists: (n_objects, 6) object velocities, world-aligned.
        contact_points: (m, 3) contact points [m].
        contact_normals: (m, 3) unit normals from body a to body b.
        contact_forces: (m, 3) forces on body b [N].
        contact_bodies: (m, 2) names of (body a, body b).
        scene_q: Full scene configuration (hand + objects), for the simulator.
        scene_v: Full scene velocity.
        contact_memory: The simulator's memory of the last step's contacts (tangential spring displacements and
            stick/slip flags, a :class:`~bhgrasp.data.contacts.ContactMemory`); ``None`` = no contact remembered.
            A run from this state continues it exactly; ``dataclasses.replace(state, contact_memory=None)`` clears
            it.
        actuation_modes: The actuation's mode flags (e.g. TorqueSwitch per finger); ``None`` = re-armed.
        scene_signature: The signature of the scene whose ``scene_q`` and ``scene_v`` these are (a simulator
            refuses a state of another scene); ``None`` = not known (checked by sizes and values alone).
        object_time: When the object readings (``object_poses``, ``object_twists``) were taken [s]: a tracker's
            frame time, older than ``t`` by its latency and frame period; ``None`` = at ``t``.
    """

    t: float
    q: np.ndarray
    v: np.ndarray
    object_poses: tuple[pin.SE3, ...] = ()
    object_twists: np.ndarray = field(default_factory=lambda: np.zeros((0, 6)))
    contact_points: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    contact_normals: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    contact_forces: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    contact_bodies: tuple[tuple[str, str], ...] = ()
    scene_q: np.ndarray | None = None
    scene_v: np.ndarray | None = None
    contact_memory: Any = None
    actuation_modes: np.ndarray | None = None
    scene_signature: str | None = None
    object_time: float | None = None


DERIVED_FIELDS = frozenset(
    (
        "q",
        "v",
        "object_poses",
        "object_twists",
        "contact_points",
        "contact_normals",
        "contact_forces",
        "contact_bodies",
        "contact_memory",
    )
)


class SimulatedState(State):
    """A :class:`State` a simulator stepped to: the fields in :data:`DERIVED_FIELDS` are built when first read.

    A step keeps the scene's ``q``, ``v``, its contacts and contact memory as the engine returned them (the compiled
    engine's arrays stay in C++ objects); a simulator's step sets the hand's ``q`` and ``v`` as read-only views of
    the scene's (and the scene's arrays read-only: a state is a value); the object poses and twists, the contact
    arrays and body names and the
    :class:`~bhgrasp.data.contacts.ContactMemory` are made from them on first access and kept.
    Reading a field gives the same value as an eagerly built :class:`State` would hold; ``dataclasses.replace``
    and pickling build every field first.
    """

    __slots__ = ("_source",)

    def __getattr__(self, name: str) -> Any:
        """Build a derived field on first access (Python calls this only for a field not set yet)."""
        if name == "_source":  # a state dataclasses.replace made has none (asked per control cycle: no message)
            raise AttributeError(name)
        if name not in DERIVED_FIELDS:
            raise AttributeError(f"{type(self).__name__!r} object has no attribute {name!r}")
        try:
            source = object.__getattribute__(self, "_source")
        except AttributeError:  # made by dataclasses.replace or unpickled: every field was given
            raise AttributeError(f"{type(self).__name__!r} object has no attribute {name!r}") from None
        for field_name, value in source.derive(name, self).items():
            object.__setattr__(self, field_name, value)
        return object.__getattribute__(self, name)

    @classmethod
    def lazy(
        cls,
        t: float,
        scene_q: np.ndarray,
        scene_v: np.ndarray,
        modes: np.ndarray,
        source: Any,
        hand_sizes: tuple[int, int] | None = None,
        scene_signature: str | None = None,
    ) -> SimulatedState:
        """A state with its time, scene ``q``, ``v`` and actuation modes, the rest built by ``source.derive``.

        With ``hand_sizes`` = (nq_hand, nv_hand) the hand's ``q`` and ``v`` are set at once as read-only views of
        the scene's arrays (which no one changes after the step that made them); otherwise they are derived too.

        ``source.derive(name, state)`` returns a dict of derived fields that includes ``name`` (it may add others
        it computed on the way, e.g. twists with poses).
        """
        state = object.__new__(cls)
        set_t, set_scene_q, set_scene_v, set_modes, set_source, set_q, set_v, set_signature, set_object_time = _SETTERS
        if scene_q.flags.writeable:  # (the compiled engine's are read-only views already)
            scene_q.flags.writeable = False
        if scene_v.flags.writeable:
            scene_v.flags.writeable = False
        set_t(state, t)
        set_scene_q(state, scene_q)
        set_scene_v(state, scene_v)
        set_modes(state, modes)
        set_source(state, source)
        set_signature(state, scene_signature)
        set_object_time(state, None)
        if hand_sizes is not None:  # the hand's q and v: views of the scene's, read-only as they are
            set_q(state, scene_q[: hand_sizes[0]])
            set_v(state, scene_v[: hand_sizes[1]])
        return state


# the slots' own setters (a frozen dataclass refuses attribute assignment; these bypass it, as its __init__ does)
_SETTERS = tuple(
    owner.__dict__[name].__set__
    for owner, name in (
        (State, "t"),
        (State, "scene_q"),
        (State, "scene_v"),
        (State, "actuation_modes"),
        (SimulatedState, "_source"),
        (State, "q"),
        (State, "v"),
        (State, "scene_signature"),
        (State, "object_time"),
    )
)


__all__ = ["DERIVED_FIELDS", "SimulatedState", "State"]
