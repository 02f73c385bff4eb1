"""The stand under a benchmark object and, for a trial among neighbours, the table around it, flush with its top.

The stand is the object's footprint, :data:`~bhgrasp.bench.height.STAND_HEIGHT` tall, its top the plane z = 0
(:func:`stand_of`).  :func:`table_around` frames it with four fixed boxes out to
:data:`~bhgrasp.bench.height.TABLE_REACH` from its axis, so that neighbours stand level with the object; the height
rule then keeps the fingers off the whole table (:mod:`~bhgrasp.bench.height`, ``table=True``), and
:func:`floor_below` catches what falls off it.  :class:`Clutter` is what a trial among neighbours starts from.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from bhgrasp._validation import as_real
from bhgrasp.bench.height import STAND_HEIGHT, TABLE_REACH
from bhgrasp.bench.objects import BenchObject
from bhgrasp.bench.protocol import APPROACH, FRICTION, STAND, Trial
from bhgrasp.model.objects import FixedBox, Plane, RigidObject
from bhgrasp.scenarios.clutter import DRAG

TABLE_THICKNESS = 0.02  # [m]
# [1/s] the neighbours' drag in a trial (Scene.object_drag; the object's is zero): a stand-in for the rolling
# resistance point contacts lack, without which a capsule or ball left resting against another rolls off on a force
# of millinewtons (measured: a capsule crept 10 mm in 18 s with no hand near it); it opposes a push of the hand with
# 0.1 N at 0.1 m/s for 0.2 kg
NEIGHBOUR_DRAG = DRAG
TABLE_PARTS = ("table -x", "table +x", "table -y", "table +y")  # the names of table_around's boxes


@dataclass(frozen=True)
class Clutter:
    """A trial's objects where they settled, the trial's object first; the table around its stand and the floor.

    ``approach`` [m]: how far above its grasp the open hand starts, clear of the neighbours (at least
    :data:`~bhgrasp.bench.protocol.APPROACH`); ``heading`` [rad]: the hand's turn about the object's vertical axis,
    away from the neighbours (:mod:`~bhgrasp.bench.heading`).

    Raises:
        InputError: A negative or non-finite ``approach``, a non-finite ``heading``.
    """

    objects: tuple[RigidObject, ...]
    table: tuple[FixedBox | Plane, ...]
    approach: float = APPROACH
    heading: float = 0.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "approach", as_real(self.approach, "approach"))
        object.__setattr__(self, "heading", as_real(self.heading, "heading", nonnegative=False))


def stand_of(item: BenchObject) -> FixedBox:
    """The stand: a fixed box of the object's footprint, its top at z = 0, named :data:`~.protocol.STAND`."""
    width = 2 * item.half_extents[:2]
    pose = pin.SE3(np.eye(3), np.array([0.0, 0.0, -0.5 * STAND_HEIGHT]))
    return FixedBox(size=(*width, STAND_HEIGHT), pose=pose, friction=FRICTION, name=STAND)


def table_around(item: BenchObject) -> tuple[FixedBox, ...]:
    """Four fixed boxes, top at z = 0, filling the square of half side :data:`TABLE_REACH` around the stand."""
    hx, hy = item.half_extents[:2]
    reach, z = TABLE_REACH, -0.5 * TABLE_THICKNESS

    def box(name: str, x: tuple[float, float], y: tuple[float, float]) -> FixedBox:
        centre = np.array([0.5 * (x[0] + x[1]), 0.5 * (y[0] + y[1]), z])
        size = (x[1] - x[0], y[1] - y[0], TABLE_THICKNESS)
        return FixedBox(size=size, pose=pin.SE3(np.eye(3), centre), friction=FRICTION, name=name)

    spans = [((-reach, -hx), (-reach, reach)), ((hx, reach), (-reach, reach)), ((-hx, hx), (-reach, -hy))]
    spans.append(((-hx, hx), (hy, reach)))
    return tuple(box(name, x, y) for name, (x, y) in zip(TABLE_PARTS, spans))


def supports(trial: Trial) -> frozenset[str]:
    """What the object stands on: the stand, and with ``trial.table`` the table around it.

    A finger pressing any of them counts as pressing the stand (:func:`~bhgrasp.bench.metrics.contact_summary`).
    """
    return frozenset({STAND, *(TABLE_PARTS if trial.table else ())})


def floor_below() -> Plane:
    """The floor under the stand's foot (z = -STAND_HEIGHT), where a neighbour pushed off the table lands."""
    return Plane(offset=-STAND_HEIGHT, friction=FRICTION, name="floor")


__all__ = [
    "NEIGHBOUR_DRAG",
    "TABLE_PARTS",
    "TABLE_THICKNESS",
    "Clutter",
    "floor_below",
    "stand_of",
    "supports",
    "table_around",
]
