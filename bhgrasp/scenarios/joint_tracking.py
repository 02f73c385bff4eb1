"""Joint tracking on a fully actuated hand in free space: the thesis' joint controllers by name, with our gains.

:func:`controller` builds one of the thesis' chapter-3 controllers (computed torque, SMC, ASMC, HOSM and HOSMA A, B,
C) for a nominal hand whose masses and inertias are :data:`MASS_ERROR` too light; :func:`simulate` runs it on the plant
from rest (dt = control period = :data:`DT`, sensor noise :data:`NOISE` when asked, seed :data:`SEED`);
:func:`f3_case` is the thesis' F3 case (Table 3.3, Fig 3.34).  A :class:`Run` keeps the trajectory and the measured
joints, and reads their tracking error and chattering.  The robust gains are sized from the mass error bound along the
reference (:func:`~bhgrasp.controllers.sliding_gains`), K_s = :data:`SURFACE_RATE` x diag M and gamma =
:data:`ADAPTATION_GAIN`; :mod:`bhgrasp.thesis.chapter3` says why.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from bhgrasp import metrics
from bhgrasp.controllers import (
    AdaptiveSlidingMode,
    ComputedTorque,
    SlidingMode,
    hosm,
    inertia_gain,
    sliding_gains,
)
from bhgrasp.controllers.base import Controller
from bhgrasp.data import Trajectory
from bhgrasp.model.barrett_hand import BarrettHand
from bhgrasp.model.hand import Hand
from bhgrasp.motion.trajectories import Quintic, Reference
from bhgrasp.sim import Simulator
from bhgrasp.sim.scene import Scene

DT = 1e-3  # [s] physics and control period
MASS_ERROR = 0.3  # nominal = plant scaled by 1 - MASS_ERROR
NOISE = (1e-4, 5e-3)  # (sigma_q [rad], sigma_v [rad/s])
SEED = 3
ADAPTATION_GAIN = 3000.0
SURFACE_RATE = 40.0  # K_s = SURFACE_RATE x diag M  [1/s]
SLIDING = ("SMC", "ASMC", "HOSM-A", "HOSMA-A", "HOSM-B", "HOSMA-B", "HOSM-C", "HOSMA-C")


@dataclass
class Run:
    """One simulated case: the controller's name, its trajectory and the joints that the case measures."""

    name: str
    noise: bool
    trajectory: Trajectory
    joints: tuple[int, ...]
    labels: tuple[str, ...]

    def tracking(self, scale: np.ndarray | None = None) -> metrics.TrackingError:
        """Joint tracking error of the measured joints against the logged reference."""
        traj, j = self.trajectory, list(self.joints)
        return metrics.tracking_error(traj.t, traj.q[:, j], traj.log["q_d"][:, j], scale=scale)

    def chattering(self) -> np.ndarray:
        """Chattering index [N m/s] of the measured joints' torques."""
        return metrics.chattering_index(self.trajectory.t, self.trajectory.u[:, list(self.joints)])


def controller(name: str, nominal: Hand, reference: Reference, duration: float, lam: float = 17.0) -> Controller:
    """One of the chapter's controllers by name ("CTC", "SMC", "ASMC", "HOSM-A" ... "HOSMA-C") with our gains."""
    if name == "CTC":
        return ComputedTorque(nominal, reference, kp=400.0, kv=160.0)
    gains = sliding_gains(nominal, reference, duration, MASS_ERROR)
    k_s = inertia_gain(nominal, SURFACE_RATE)
    if name == "SMC":
        return SlidingMode(nominal, reference, lam=lam, k_s=k_s, k=gains.k)
    if name == "ASMC":
        return AdaptiveSlidingMode(nominal, reference, lam=lam, k_s=k_s, adaptation_gain=ADAPTATION_GAIN)
    family, law = name.split("-")
    adaptive = family == "HOSMA"
    extra = {"adaptation_gain": ADAPTATION_GAIN} if adaptive else {}
    if law == "C":
        extra.update(w=gains.w, u_max=gains.u_max, lambda_s=gains.lambda_s)
    else:
        extra.update(alpha=gains.alpha)
    return hosm(law, nominal, reference, adaptive=adaptive, lam=lam, k_s=k_s, **extra)


def simulate(
    hand: Hand, make: Callable[[], Controller], q0: np.ndarray, duration: float, noise: bool, record_every: int = 1
) -> Trajectory:
    """Run one controller on the fully actuated ``hand`` from rest at ``q0``."""
    sim = Simulator(Scene(hand), dt=DT)
    return sim.run(
        make(),
        duration,
        state=sim.initial_state(q0),
        sensor_noise=NOISE if noise else None,
        seed=SEED,
        progress=False,
        record_every=record_every,
    )


def f3_case(name: str, noise: bool, duration: float = 3.0, hand: Hand | None = None) -> Run:
    """Table 3.3 / Fig 3.34 case: finger F3 to q2 = 45 deg, q3 = 15 deg (quintic, 1.5 s), 30 % mass error."""
    plant = hand if hand is not None else BarrettHand()
    nominal = plant.perturbed(1.0 - MASS_ERROR)
    q0 = plant.configuration(F1_proximal=0.3, F2_proximal=0.3, F3_proximal=0.05, F3_distal=0.05)
    qf = q0.copy()
    joints = (plant.joint_index("F3_proximal"), plant.joint_index("F3_distal"))
    qf[list(joints)] = np.radians([45.0, 15.0])
    reference = Quintic(q0, qf, 1.5)
    traj = simulate(plant, lambda: controller(name, nominal, reference, duration, lam=8.0), q0, duration, noise)
    return Run(name, noise, traj, joints, ("F3 q2", "F3 q3"))


__all__ = [
    "ADAPTATION_GAIN",
    "DT",
    "MASS_ERROR",
    "NOISE",
    "SEED",
    "SLIDING",
    "SURFACE_RATE",
    "Run",
    "controller",
    "f3_case",
    "simulate",
]
