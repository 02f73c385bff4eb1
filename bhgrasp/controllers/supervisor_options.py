"""The options of a :class:`~bhgrasp.controllers.supervisor.GraspSupervisor`: how it approaches, how it plans.

Frozen and checked when made: ``dataclasses.replace(Approach(), kp=900.0)`` is a new, checked option set.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import coal
import numpy as np

from bhgrasp._validation import as_positive, as_real, as_vector
from bhgrasp.errors import InputError
from bhgrasp.grasp.path_result import TOLERANCE as PATH_TOLERANCE

PLAN_TOLERANCE = (5e-4, 5e-3)  # [m], [rad] the most the plan may differ from the request: the final-pose
# tolerance, as chapter 5's motion table judges success (a request the sensed contacts make only worse than that is
# refused, not approximated)


@dataclass(frozen=True)
class Approach:
    """How the fingers close on the object: joint computed torque along a smooth step (thesis (5.36)).

    Attributes:
        time: Time constant [s] of the smooth step.
        closing: Extra closing [rad] beyond the contact configuration on the non-spread joints (unless the supervisor
            is given ``q_close``), so that the fingers press once they touch.
        contact_force: Sensed normal force [N] at which a finger counts as arrived.
        timeout: Longest approach [s] before the grasp controller takes over anyway.
        kp, kv: Joint computed-torque gains [1/s^2, 1/s].
        damping: The joints' known viscous damping [N m s/rad] the approach cancels (its computed torque models the
            links alone, whose inertia is small next to it: at 0.05 N m s/rad a BH8-280 distal joint closes with a
            ~3 s time constant under the default gains); the grasp controller does not add it.
    """

    time: float = 0.15
    closing: float = 0.1
    contact_force: float = 0.05
    timeout: float = 2.0
    kp: float = 400.0
    kv: float = 40.0
    damping: float = 0.0

    def __post_init__(self) -> None:
        for name in ("time", "contact_force", "timeout", "kp", "kv"):
            object.__setattr__(self, name, as_positive(getattr(self, name), f"Approach.{name}"))
        object.__setattr__(self, "closing", as_real(self.closing, "Approach.closing"))
        damping = as_real(self.damping, "Approach.damping")
        if damping < 0.0:
            raise InputError(f"`Approach.damping` must be >= 0 [N m s/rad], got {self.damping}")
        object.__setattr__(self, "damping", damping)


@dataclass(frozen=True)
class Planning:
    """How the object motion after the squeeze is planned and checked.

    Attributes:
        plan: Track the part of the requested offset the grasp can make at the contacts sensed when the motion
            starts (the supervisor's ``planned_offset``), instead of the offset as given.
        tolerance: The largest position [m] and rotation [rad] differences between the plan and the offset: a
            request the sensed contacts make only worse than that is refused with
            :class:`~bhgrasp.errors.UnreachableError`, naming the part the fingers cannot make; ``None`` tracks any
            plan.
        object_shape: The object's coal shape (placed by its pose): the planned motion is also followed to its end
            with the sensed contacts rolling without slip (:func:`~bhgrasp.grasp.path_check.path_contacts`) and
            refused with :class:`~bhgrasp.errors.UnreachableError` (naming the link, the face and the angle) if another
            part of a finger would meet the object or a joint leave its limits; ``None``: first order only.
        path_tolerance: With ``object_shape``: how near [m] another part of a finger may come to the object along the
            planned motion (:data:`~bhgrasp.grasp.path_result.TOLERANCE`).
    """

    plan: bool = True
    tolerance: Any = PLAN_TOLERANCE
    object_shape: coal.CollisionGeometry | None = None
    path_tolerance: float = PATH_TOLERANCE

    def __post_init__(self) -> None:
        object.__setattr__(self, "plan", bool(self.plan))
        tolerance = None if self.tolerance is None else as_vector(self.tolerance, "Planning.tolerance", 2)
        if tolerance is not None and not np.all(tolerance > 0.0):
            raise InputError(f"`Planning.tolerance` must be two positive numbers [m], [rad], got {tolerance.tolist()}")
        object.__setattr__(self, "tolerance", None if tolerance is None else tuple(float(x) for x in tolerance))
        object.__setattr__(self, "path_tolerance", as_real(self.path_tolerance, "Planning.path_tolerance"))


DEFAULT_APPROACH = Approach()
DEFAULT_PLANNING = Planning()

__all__ = ["DEFAULT_APPROACH", "DEFAULT_PLANNING", "PLAN_TOLERANCE", "Approach", "Planning"]
