"""A step's inputs checked at the Simulator's boundary: control inputs, joint disturbances, forces on objects."""

from __future__ import annotations

from typing import Any

import numpy as np

from bhgrasp._validation import as_array, finite_vector
from bhgrasp.errors import InputError, SimulationDiverged
from bhgrasp.sim.scene import Scene


def control_input(u: Any, n_inputs: int, t: float) -> np.ndarray:
    """The control input as a finite float array of shape (n_inputs,).

    Raises:
        InputError: Not numbers, or the wrong shape.
        SimulationDiverged: NaN/inf (a controller that diverged).
    """
    try:
        u = np.asarray(u, dtype=float)
    except (TypeError, ValueError) as error:
        raise InputError(f"`u` must be {n_inputs} numbers (the inputs), got {u!r}") from error
    if u.shape != (n_inputs,):
        raise InputError(f"`u` must have shape ({n_inputs},), got shape {u.shape}")
    if not finite_vector(u):
        raise SimulationDiverged(t, "control input u", u.tolist(), "the controller returned NaN/inf")
    return u


def joint_torques(torque: Any, nv_hand: int, name: str) -> np.ndarray | None:
    """A disturbance as finite joint torques of shape (nv_hand,) [N m] (``None``: none)."""
    if torque is None:
        return None
    try:
        array = np.asarray(torque, dtype=float)
    except (TypeError, ValueError) as error:
        raise InputError(f"`{name}` must be joint torques [N m], got {torque!r}") from error
    if array.shape != (nv_hand,):
        raise InputError(
            f"`{name}` must be {nv_hand} joint torques [N m] (one per hand joint), got shape {array.shape}"
        )
    if not np.isfinite(array).all():
        raise InputError(f"`{name}` must be finite, got {array.tolist()}")
    return array


def generalized_forces(scene: Scene, disturbance: np.ndarray | None, forces: Any) -> np.ndarray:
    """Generalized forces on the whole scene: hand joint torques, then world forces at the objects' COMs.

    A free object's first three velocity coordinates translate its COM along the world axes
    (:meth:`~bhgrasp.sim.scene.Scene.object_twist`), so a world force F enters as it is; a spring-mounted object's
    slide takes F . direction.
    """
    forces = as_array(forces, "object_forces", (len(scene.objects), 3))
    total = np.zeros(scene.nv)
    if disturbance is not None:
        total[: scene.nv_hand] = disturbance
    for index, force in enumerate(forces):
        rows = scene.object_v_slice(index)
        if rows.stop - rows.start == 6:
            total[rows.start : rows.start + 3] = force
        else:
            total[rows] = force @ scene.objects[index].direction
    return total


__all__ = ["control_input", "generalized_forces", "joint_torques"]
