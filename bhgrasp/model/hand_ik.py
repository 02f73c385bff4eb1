"""Inverse kinematics of several fingertips of any hand at once: damped least squares within the joint limits."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from bhgrasp._validation import as_generator, as_positive, as_vector, require_name
from bhgrasp.errors import InputError, UnreachableError
from bhgrasp.model.hand import Hand


@dataclass(frozen=True)
class IKResult:
    """Outcome of :func:`ik`: configuration, convergence and per-finger position errors [m]."""

    q: np.ndarray
    converged: bool
    iterations: int
    errors: dict[str, float] = field(default_factory=dict)

    @property
    def max_error(self) -> float:
        """Largest fingertip position error [m]."""
        return max(self.errors.values(), default=0.0)


def ik(
    hand: Hand,
    targets: Mapping[str, Any],
    q0: Any = None,
    *,
    tolerance: float = 1e-6,
    max_iterations: int = 200,
    damping: float = 1e-4,
    restarts: int = 0,
    rng: np.random.Generator | int | None = None,
) -> IKResult:
    """Fingertip-position IK for any hand by damped least squares, inside the joint limits.

    Each step solves ``dq = J^T (J J^T + damping^2 I)^-1 e`` for the stacked fingertip errors ``e`` [m], limits
    the step to 0.2 rad, and clamps ``q`` to the joint limits.  It is a local method: joint limits create local
    minima (a Barrett spread stuck at the wrong end of [0, pi]; an Allegro thumb near its limits), which the
    seeded ``restarts`` escape (tests: 30 random reachable 4-finger Allegro targets all solved with 30 restarts).

    Args:
        targets: Finger name -> target fingertip position in the world [m].
        q0: Start configuration (default: middle of the joint limits).
        tolerance: Convergence threshold on every fingertip error [m].
        restarts: Extra attempts if the first does not converge (needs ``rng``): the joints of the fingers that
            missed their target are re-drawn uniformly within their limits, the others kept.

    Raises:
        UnreachableError: No attempt converged; ``error.result`` holds the best :class:`IKResult`.
    """
    if not targets:
        raise InputError("`targets` must name at least one finger")
    goals = {require_name(f, hand.fingers, "finger"): as_vector(p, f"targets[{f!r}]", 3) for f, p in targets.items()}
    tolerance = as_positive(tolerance, "tolerance")
    damping = as_positive(damping, "damping")
    if restarts and rng is None:
        raise InputError("`restarts` needs a seeded `rng` (an integer or numpy Generator)")
    start = 0.5 * (hand.lower + hand.upper) if q0 is None else as_vector(q0, "q0", hand.nq)
    generator = as_generator(rng) if rng is not None else None
    best: IKResult | None = None
    q = start
    for attempt in range(restarts + 1):
        if attempt > 0:  # keep the fingers that converged, re-draw the joints of those that did not
            q = best.q.copy()
            for finger, error in best.errors.items():
                if error >= tolerance:
                    indices = hand.finger_indices(finger)
                    q[indices] = generator.uniform(hand.lower[indices], hand.upper[indices])
        result = _dls(hand, goals, q, tolerance, max_iterations, damping)
        if best is None or result.max_error < best.max_error:
            best = result
        if result.converged:
            return result
    raise UnreachableError(
        f"IK did not reach {', '.join(goals)} within {tolerance} m after {restarts + 1} attempt(s); "
        f"best errors {', '.join(f'{f}: {e:.3g} m' for f, e in best.errors.items())}",
        result=best,
    )


def _dls(
    hand: Hand, goals: dict[str, np.ndarray], q: np.ndarray, tolerance: float, iterations: int, damping: float
) -> IKResult:
    lower, upper = hand.lower, hand.upper
    q = np.clip(q, lower, upper)
    order = [hand.fingers.index(f) for f in goals]
    goal = np.concatenate(list(goals.values()))
    for iteration in range(iterations + 1):
        error = goal - hand.fingertip_positions(q)[order].ravel()
        norms = np.linalg.norm(error.reshape(-1, 3), axis=1)
        if np.all(norms < tolerance) or iteration == iterations:
            break
        jacobian = np.vstack([hand.fingertip_jacobian(q, f) for f in goals])
        gram = jacobian @ jacobian.T + damping**2 * np.eye(len(goal))
        step = jacobian.T @ np.linalg.solve(gram, error)
        step *= min(1.0, 0.2 / max(np.abs(step).max(), 1e-300))
        q = np.clip(q + step, lower, upper)
    errors = dict(zip(goals, map(float, norms)))
    return IKResult(q, bool(np.all(norms < tolerance)), iteration, errors)


__all__ = ["IKResult", "ik"]
