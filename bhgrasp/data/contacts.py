"""Contacts as data: one instant's contact points, their records, and the memory a run carries between steps.

A :class:`ContactSet` holds the arrays the engines compute on (:func:`empty_contact_set` when there are none);
:meth:`ContactSet.records` turns them into :class:`Contact` records for users; :class:`ContactMemory` is what a
:class:`~bhgrasp.data.state.State` carries from one step to the next (each contact's tangential spring and slide
flag).  World frame, SI units.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from bhgrasp.errors import InputError


@dataclass(frozen=True)
class Contact:
    """One contact point, as a user inspects it (world frame, SI units).

    Attributes:
        body_a: Name of the body the normal points away from (hand link, environment, first object).
        body_b: Name of the body the force ``force`` acts on (an object); ``-force`` acts on ``body_a``.
        point: Contact point [m] (midway between the two surfaces).
        normal: Unit normal from a to b.
        depth: Penetration [m] (>= 0).
        normal_force: f_n [N] (>= 0).
        tangential_force: f_t [N], perpendicular to ``normal``.
        sticking: Whether the tangential force is inside the friction cone (no sliding).
    """

    body_a: str
    body_b: str
    point: np.ndarray
    normal: np.ndarray
    depth: float
    normal_force: float
    tangential_force: np.ndarray
    sticking: bool

    @property
    def force(self) -> np.ndarray:
        """Total force on ``body_b`` [N]."""
        return self.normal_force * self.normal + self.tangential_force

    @property
    def point_a(self) -> np.ndarray:
        """Deepest point of body a's surface inside body b [m]."""
        return self.point + 0.5 * self.depth * self.normal

    @property
    def point_b(self) -> np.ndarray:
        """Deepest point of body b's surface inside body a [m]."""
        return self.point - 0.5 * self.depth * self.normal


@dataclass(frozen=True, eq=False)
class ContactMemory:
    """What a run carries from one step to the next about its contacts (part of :class:`~bhgrasp.data.state.State`).

    An immutable value: its arrays are read-only copies, and ``dataclasses.replace(memory, displacement=...)`` makes
    a new memory that every engine reads as given.  The compiled engine's copy of the same arrays (kept so that a
    compiled run hands its memory on without converting it back and forth) is private to the instance it was made
    with: it is neither copied by ``replace`` nor pickled, so it cannot go stale.

    Attributes:
        pair: (m,) collision-pair index of each remembered contact.
        local_b: (m, 3) the contact point in its body b's joint frame [m] (contacts are matched by position on b).
        displacement: (m, 3) end-of-step tangential spring displacement u [m].
        sliding: (m,) whether the contact ended the step sliding (the next step starts it sliding).
    """

    pair: np.ndarray
    local_b: np.ndarray
    displacement: np.ndarray
    sliding: np.ndarray

    def __post_init__(self) -> None:
        """Keep read-only copies of the arrays, checked for matching lengths."""
        m = len(self.pair)
        for name, dtype, shape in (
            ("pair", np.int64, (m,)),
            ("local_b", np.float64, (m, 3)),
            ("displacement", np.float64, (m, 3)),
            ("sliding", np.bool_, (m,)),
        ):
            array = np.array(getattr(self, name), dtype=dtype)  # a copy: the caller's array stays its own
            if array.shape != shape:
                raise InputError(f"`ContactMemory.{name}` must have shape {shape} for {m} contacts, got {array.shape}")
            array.flags.writeable = False
            object.__setattr__(self, name, array)
        object.__setattr__(self, "_native", None)

    @classmethod
    def empty(cls) -> ContactMemory:
        """No contact remembered (the start of a run, or contacts cleared)."""
        return cls(np.zeros(0, int), np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0, bool))

    @classmethod
    def with_native(cls, native: Any) -> ContactMemory:
        """The compiled engine's ``Memory`` as a ContactMemory that keeps it (for the engine that made it)."""
        memory = cls(native.pair, native.local_b, native.displacement, native.sliding)
        object.__setattr__(memory, "_native", native)
        return memory

    @property
    def native(self) -> Any:
        """The compiled engine's copy this memory was made from (``None``: made in Python)."""
        return self._native

    def __len__(self) -> int:
        return len(self.pair)

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, ContactMemory):
            return NotImplemented
        return all(
            np.array_equal(getattr(self, name), getattr(other, name))
            for name in ("pair", "local_b", "displacement", "sliding")
        )

    __hash__ = None  # type: ignore[assignment]  (a value of arrays)

    def __reduce__(self) -> tuple:
        """Copies and pickles keep the arrays; the compiled engine rebuilds its native copy from them."""
        return type(self), (self.pair, self.local_b, self.displacement, self.sliding)


@dataclass
class ContactSet:
    """The contact points of one instant as arrays (m contacts); ``contacts`` gives :class:`Contact` records."""

    pair: np.ndarray  # (m,) collision-pair index
    point: np.ndarray  # (m, 3) [m]
    normal: np.ndarray  # (m, 3) unit, a -> b
    depth: np.ndarray  # (m,) [m]
    friction: np.ndarray  # (m,) mu
    displacement: np.ndarray  # (m, 3) tangential elastic displacement u at the start of the step [m]
    weight: np.ndarray  # (m,) share of its patch's stiffness and damping: 1 / (points in the patch)
    local_b: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))  # (m, 3) points in b's joint frame [m]
    force: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))  # (m, 3) on b [N]
    sticking: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=bool))
    was_sliding: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=bool))  # (m,) slid the last step

    def __post_init__(self) -> None:
        m = len(self.pair)
        if len(self.force) != m:  # detected, forces not computed yet
            self.force = np.zeros((m, 3))
            self.sticking = np.zeros(m, dtype=bool)
        if len(self.was_sliding) != m:
            self.was_sliding = np.zeros(m, dtype=bool)

    def __len__(self) -> int:
        return len(self.pair)

    def normal_forces(self) -> np.ndarray:
        """f_n per contact [N]."""
        return np.einsum("ij,ij->i", self.force, self.normal) if len(self) else np.zeros(0)

    def records(self, scene: Any) -> list[Contact]:
        """The contacts as :class:`Contact` records, named by ``scene`` (the :class:`~bhgrasp.sim.scene.Scene`)."""
        records = []
        for i, k in enumerate(self.pair):
            pair = scene.pairs[k]
            f_n = float(self.force[i] @ self.normal[i])
            records.append(
                Contact(
                    pair.body_a,
                    pair.body_b,
                    self.point[i].copy(),
                    self.normal[i].copy(),
                    float(self.depth[i]),
                    f_n,
                    self.force[i] - f_n * self.normal[i],
                    bool(self.sticking[i]),
                )
            )
        return records


def empty_contact_set() -> ContactSet:
    """A set with no contacts."""
    return ContactSet(
        np.zeros(0, int), np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0), np.zeros(0), np.zeros((0, 3)), np.zeros(0)
    )


__all__ = ["Contact", "ContactMemory", "ContactSet", "empty_contact_set"]
