"""Sweep rollouts of the built-in scenes, for :func:`bhgrasp.sweep.run_sweep`.

:func:`grasp_rollout` is the grasp demo (:func:`~bhgrasp.scenarios.grasp_demo.run_grasp_demo`) with any of its
parameters varied (:func:`check_grasp_case` checks a case without running it); :data:`hold_rollout` is the reference
hold (:func:`~bhgrasp.scenarios.hold.reference_hold`) batched in one :class:`~bhgrasp.sim.batch.BatchSimulator`.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from bhgrasp.controllers.grasp_options import DEFAULT_GRASP
from bhgrasp.errors import InputError
from bhgrasp.grasp.hold_torque import static_hold_torque
from bhgrasp.scenarios.box_grasp import FRICTION
from bhgrasp.scenarios.demo_result import MU_ASSUMED, GraspDemoResult
from bhgrasp.scenarios.estimation import state_at
from bhgrasp.scenarios.grasp_demo import check_demo_arguments, run_grasp_demo
from bhgrasp.scenarios.hold import POSTURE_GAIN, SQUEEZE, reference_hold
from bhgrasp.sim.batch import BatchSimulator
from bhgrasp.sweep import BatchedRollout


def check_grasp_case(parameters: dict[str, Any]) -> None:
    """The checks :func:`grasp_rollout` makes of a case, without running it (a ``check`` for ``run_sweep``).

    Raises:
        InputError: ``seed`` given, or a name that is not a parameter of the grasp demo, or a bad value.
    """
    if "seed" in parameters:
        raise InputError("the case seed comes from the sweep; do not give `seed` as a parameter")
    check_demo_arguments(**parameters)


def grasp_rollout(parameters: dict[str, Any], seed: int) -> dict[str, float]:
    """The grasp demo as a sweep scenario; ``parameters`` are keyword arguments of ``run_grasp_demo``.

    For example ``mass``, ``estimate``, ``controller``, ``distribution``, ``stiffness``, ``duration`` and
    ``sensor_noise`` and the uncertainties of :mod:`bhgrasp.scenarios.uncertainty` (whose draws use the case's
    ``seed``).  Returns the demo's figures of merit: pose errors [m, rad] (the controller's, and the true ones
    against its reference), force error (fraction), slip events, the farthest a link slid [m], the final mass
    estimate [kg] (NaN for non-adaptive controllers), the grasp time [s], when the motion ends [s], the minimum
    cone margin [N], and the least peak joint torque [N m] with which the final grasp can hold the box at rest
    (:func:`final_hold_torque`) inside the cones the controller commands (``hold_torque``) and inside the true
    friction's (``hold_torque_true_mu``).
    """
    check_grasp_case(parameters)
    result = run_grasp_demo(**parameters, seed=seed)
    margin = parameters.get("friction_margin")
    assumed = float(parameters.get("mu", MU_ASSUMED)) * (1.0 if margin is None else 1.0 - float(margin))
    return {
        "position_error": result.position_error,
        "rotation_error": result.rotation_error,
        "true_position_error": result.true_position_error,
        "true_rotation_error": result.true_rotation_error,
        "force_error": result.force_error,
        "slip_events": float(result.slip_events),
        "slide": result.slide,
        "mass_estimate": float("nan") if result.mass_estimate is None else result.mass_estimate,
        "grasp_time": result.grasp_time,
        "motion_end": result.motion_end,
        "cone_margin": result.cone_margin,
        "hold_torque": final_hold_torque(result, assumed),
        "hold_torque_true_mu": final_hold_torque(result, float(parameters.get("friction", FRICTION))),
    }


def final_hold_torque(result: GraspDemoResult, mu: float) -> float:
    """The least peak joint torque [N m] that holds the box at rest in the run's final grasp, with cones of ``mu``.

    :func:`~bhgrasp.grasp.hold_torque.static_hold_torque` of the last sample as the controller models the grasp (one
    contact per finger, the pyramids inscribed in the cones of ``mu``, its least normal force, the true mass): no
    forces of that model hold the box's weight with every finger joint torque below it.  ``inf`` when the fingers no
    longer touch the box, or no such forces hold it.
    """
    state = state_at(result.trajectory, len(result.trajectory.t) - 1)
    scene = result.scene
    body, least = result.trajectory.object_names[0], DEFAULT_GRASP.min_normal_force
    return static_hold_torque(scene.hand, state, body, result.true_mass, mu, min_normal_force=least).fraction


def _hold_batch(parameters: list[dict[str, Any]], seeds: list[int]) -> list[dict[str, float]]:
    """The reference hold (:func:`~bhgrasp.scenarios.hold.reference_hold`) for many gains at once."""
    known = {"squeeze", "posture_gain", "duration"}
    for case in parameters:
        unknown = sorted(set(case) - known)
        if unknown:
            raise InputError(f"hold_rollout has no parameters {unknown}; it takes {sorted(known)}")
    durations = {float(case.get("duration", 1.0)) for case in parameters}
    if len(durations) > 1:
        raise InputError(f"the cases of one batch must share `duration`, got {sorted(durations)}")
    hold = reference_hold()
    q0, fingers, forces = hold.state.q, list(SQUEEZE), np.array(list(SQUEEZE.values()))
    squeeze = np.array([float(case.get("squeeze", 1.0)) for case in parameters])
    gain = np.array([float(case.get("posture_gain", POSTURE_GAIN)) for case in parameters])

    def controller(t: float, batch: BatchSimulator) -> np.ndarray:
        tips = np.einsum("nkij,ki->nj", batch.fingertip_jacobians(fingers), forces)
        return batch.gravity_torques() + gain[:, None] * (q0 - batch.q) + squeeze[:, None] * tips

    batch = BatchSimulator(hold.simulator, [hold.state] * len(parameters)).run(controller, durations.pop())
    drop = hold.box_height - batch.object_positions()[:, 2]
    return [
        {"drop": float(d), "diverged": float(x), "contacts": float(len(batch.contacts(i)))}
        for i, (d, x) in enumerate(zip(drop, batch.diverged))
    ]


hold_rollout = BatchedRollout(_hold_batch, size=64)
"""The reference hold as a batched sweep scenario: parameters ``squeeze`` (scale of the squeeze forces, default 1),
``posture_gain`` [N m/rad] (default 2) and ``duration`` [s] (default 1, shared by a batch); metrics ``drop`` (the
box's fall [m]), ``diverged`` (0 or 1) and ``contacts`` (contact points at the end)."""


__all__ = ["check_grasp_case", "final_hold_torque", "grasp_rollout", "hold_rollout"]
