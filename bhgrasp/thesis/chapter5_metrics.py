"""Chapter 5's figures of merit of a grasp run: the motion's tracking, its contact forces, its mass estimate.

And the chapter's run constants (durations, masses, the moved channels, the force band).
"""

from __future__ import annotations

import numpy as np

from bhgrasp import metrics
from bhgrasp.grasp.metrics import finger_normal_forces
from bhgrasp.model.barrett_hand import BarrettHand
from bhgrasp.scenarios.demo_result import GraspDemoResult
from bhgrasp.scenarios.grasp_demo import OFFSET

DURATION = 3.0  # [s] each run
THESIS_MASS = 1.0  # [kg] m_o of thesis 5.7
LAW_MASS = 0.3  # [kg] the object of the CTC / natural / stiffness cases (known to the controller)
MASSES = (0.2, 0.4, 0.6, 0.8, 1.0)  # [kg] unknown-mass sweep, the controller starts at 0.5 kg
MOVED = (2, 3)  # object_error channels that move: z and the rotation about x
FORCE_BAND = 0.05  # contact-force settling band, fraction of the commanded force


def motion_metrics(result: GraspDemoResult) -> dict[str, np.ndarray]:
    """Motion figures of the moved channels (z [m], rotation about x [rad]).

    Overshoot [% of the move], settling after the reference ends [s] (2 % band), the largest tracking error during
    and after the move, and the final error.
    """
    traj = result.trajectory
    moving = traj.t >= result.motion_start
    if np.count_nonzero(moving) < 2:  # a shortened run that ends before the move
        return dict.fromkeys(("overshoot", "settling", "max_error", "final_error"), np.full(len(MOVED), np.nan))
    error = traj.log["object_error"][moving][:, MOVED]
    offset = np.asarray(OFFSET)[list(MOVED)]
    # the pose relative to the start of the motion, from the logged error and the (known) minimum-jerk reference
    duration = result.motion_end - result.motion_start
    progress = error + offset * _min_jerk((traj.t[moving] - result.motion_start) / duration)
    step = metrics.step_response(traj.t[moving], progress, target=offset, start=np.zeros(2))
    settling = np.maximum(step.settling_time - duration, 0.0)
    return {
        "overshoot": step.overshoot_percent,
        "settling": settling,
        "max_error": np.max(np.abs(error), axis=0),
        "final_error": np.abs(error[-1]),
    }


def _min_jerk(s: np.ndarray) -> np.ndarray:
    s = np.clip(s, 0.0, 1.0)[:, None]
    return s**3 * (10.0 + s * (-15.0 + 6.0 * s))


def force_metrics(result: GraspDemoResult) -> dict[str, float]:
    """Contact-force error after settling, [N] and [%] of the commanded normal force, and its settling time.

    The settling time [s] counts from the grasp until every finger stays within 5 % of its commanded force.
    """
    traj = result.trajectory
    measured = finger_normal_forces(BarrettHand(), traj)
    commanded = traj.log["commanded_normal"]
    grasping = traj.t >= result.grasp_time
    relative = np.max(np.abs(measured - commanded)[grasping] / np.maximum(commanded[grasping], 1e-9), axis=1)
    outside = np.flatnonzero(relative > FORCE_BAND)
    settle = 0.0 if outside.size == 0 else float(traj.t[grasping][min(outside[-1] + 1, relative.size - 1)])
    settled = traj.t >= min(result.settle_time, float(traj.t[-1]))
    absolute = float(np.max(np.abs(measured - commanded)[settled]))
    return {"error_n": absolute, "error_percent": 100.0 * result.force_error, "settling": settle - result.grasp_time}


def estimate_convergence(result: GraspDemoResult, band: float = 0.02) -> float:
    """Time [s] after the grasp from which the mass estimate stays within ``band`` of the true mass (inf: never)."""
    traj = result.trajectory
    estimate = np.ravel(traj.log["mass_estimate"][:, 0])
    off = np.flatnonzero(~(np.abs(estimate - result.true_mass) <= band * result.true_mass))
    if off.size and off[-1] == len(traj) - 1:
        return float("inf")
    return float(traj.t[off[-1] + 1] - result.grasp_time) if off.size else 0.0


def motion_values(prefix: str, m: dict[str, np.ndarray]) -> dict[str, float]:
    """The motion metrics of :func:`motion_metrics` as numbers named ``prefix + name`` (z [mm], rot x [mrad])."""
    values = {}
    for name, scale, units in (
        ("overshoot", 1.0, ("pct", "pct")),
        ("max_error", 1e3, ("mm", "mrad")),
        ("settling", 1.0, ("s", "s")),
        ("final_error", 1e3, ("mm", "mrad")),
    ):
        for channel, value, unit in zip(("z", "rotx"), m[name], units):
            values[f"{prefix}{name}_{channel}_{unit}"] = scale * float(value)
    return values


def pair_text(values: np.ndarray, spec: str) -> str:
    """``values`` formatted with ``spec``, joined by " / " (a z / rot x pair in the tables)."""
    return " / ".join(format(float(v), spec) for v in values)


__all__ = [
    "DURATION",
    "FORCE_BAND",
    "LAW_MASS",
    "MASSES",
    "MOVED",
    "THESIS_MASS",
    "estimate_convergence",
    "force_metrics",
    "motion_metrics",
    "motion_values",
    "pair_text",
]
