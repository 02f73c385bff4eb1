"""The options every object-space grasp controller shares: the force distribution, the closing torque, gravity.

Frozen and checked when made; a controller is built with one (:class:`GraspOptions`, default :data:`DEFAULT_GRASP`)
and keeps it: other options make another controller (``dataclasses.replace(DEFAULT_GRASP, mu=0.6)``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from bhgrasp._validation import as_positive, as_real, as_vector
from bhgrasp.errors import InputError

DISTRIBUTIONS = ("qp", "pinv")


@dataclass(frozen=True)
class GraspOptions:
    """How an object-space grasp controller distributes the object wrench over the contacts, and closes before them.

    Attributes:
        mu: Friction coefficient the distribution assumes (use a margin below the true one).
        squeeze: Desired normal force per contact [N] (the internal force the distribution stays closest to).
        min_normal_force: Lower bound of every normal force in the QP [N].
        approach_torque: Closing torque [N m] on each finger's proximal-most non-spread joint before contact.
        gravity: World gravity [m/s^2].
        distribution: ``"qp"`` (friction-cone QP) or ``"pinv"`` (thesis (5.45), the baseline).
        friction_margin: ``None`` (default): the QP's cones use ``mu``.  A fraction m in [0, 1): the fraction of
            ``mu`` kept in reserve for a true friction below the assumed one.  The QP's cones use (1 - m) mu, and
            the grip follows the load the fingers measure: each contact's desired normal force is raised to
            |f_t| / ((1 - m) mu) of its *measured* tangential force f_t, so that a load the model does not know
            (a wrong mass estimate, the object leaving its support) is met with more squeeze, not with sliding
            (the grip-load coupling of human grasping: Johansson and Westling, Exp. Brain Res. 56, 1984).  0 keeps
            the cones at mu and the grip reflex on.
        torque_limit: ``None`` (default): no limit.  The joints' torque limit [N m] the controller respects: one
            number for every joint, or one per joint (positive; ``inf`` for a joint without one).  When the
            distribution's forces would load a joint past it, the controller squeezes less: it scales the forces'
            internal part (the part the grasp map cancels) down until every joint is within its limit, so the
            fingers keep exerting the same wrench and press less together, relying on more friction than the cones
            allow (:mod:`bhgrasp.grasp.torque_limited`).  A drive that clips one joint instead leaves the object
            pushed by the fingers that are not clipped.
    """

    mu: float = 0.5
    squeeze: float = 3.0
    min_normal_force: float = 0.5
    approach_torque: float = 0.05
    gravity: Any = (0.0, 0.0, -9.81)
    distribution: str = "qp"
    friction_margin: float | None = None
    torque_limit: Any = None

    def __post_init__(self) -> None:
        if self.distribution not in DISTRIBUTIONS:
            raise InputError(f"`distribution` must be one of {DISTRIBUTIONS}, got {self.distribution!r}")
        object.__setattr__(self, "mu", as_positive(self.mu, "mu"))
        object.__setattr__(self, "squeeze", as_positive(self.squeeze, "squeeze"))
        object.__setattr__(self, "min_normal_force", as_real(self.min_normal_force, "min_normal_force"))
        object.__setattr__(self, "approach_torque", as_real(self.approach_torque, "approach_torque"))
        object.__setattr__(self, "gravity", tuple(float(g) for g in as_vector(self.gravity, "gravity", 3)))
        if self.friction_margin is not None:
            if isinstance(self.friction_margin, bool):
                raise InputError(f"`friction_margin` must be None or a number in [0, 1), got {self.friction_margin!r}")
            margin = as_real(self.friction_margin, "friction_margin")
            if not 0.0 <= margin < 1.0:
                raise InputError(f"`friction_margin` must be None or in [0, 1) (a fraction of mu), got {margin}")
            object.__setattr__(self, "friction_margin", margin)
        if self.torque_limit is not None:
            object.__setattr__(self, "torque_limit", torque_limits(self.torque_limit))

    @property
    def design_mu(self) -> float:
        """The friction coefficient the distribution enforces: ``mu`` less the margin, (1 - m) mu."""
        return self.mu if self.friction_margin is None else (1.0 - self.friction_margin) * self.mu


def torque_limits(value: Any) -> float | tuple[float, ...]:
    """A torque limit [N m] as a positive float, or a tuple of them (``inf`` allowed), else InputError."""
    if isinstance(value, (bool, np.bool_)):
        raise InputError(f"`torque_limit` must be None, a positive number or one per joint, got {value!r}")
    try:
        limits = np.asarray(value, dtype=float)
    except (TypeError, ValueError) as error:
        raise InputError(f"`torque_limit` must be None, a positive number or one per joint, got {value!r}") from error
    if limits.ndim > 1 or limits.size == 0 or np.any(np.isnan(limits)) or np.any(limits <= 0.0):
        raise InputError(f"`torque_limit` must be None, a positive number or one per joint [N m], got {value!r}")
    return float(limits) if limits.ndim == 0 else tuple(float(x) for x in limits)


DEFAULT_GRASP = GraspOptions()

__all__ = ["DEFAULT_GRASP", "DISTRIBUTIONS", "GraspOptions", "torque_limits"]
