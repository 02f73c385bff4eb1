"""Learning the object online (thesis 5.6, (5.52) and (5.63)): identification runs of the grasped box.

The hand grasps the 0.6 kg box (the controller told 0.3 kg and the inertia of a 0.3 kg box) with the off-stop pinch,
lifts it 10 mm and shakes it along the directions the grasp can move it (:data:`EXCITATION`: y, z, and turns about x
and y; a shift along x or a turn about z would slide F3 and is refused by the grasp's manipulable space).  Runs
compare the thesis' law (5.52) with the composite law (:mod:`bhgrasp.controllers.object_identification`), with exact
and noisy sensing (:data:`NOISE`, the robustness table's levels), and report how well the mass and inertia are learnt
and how the Lyapunov function V_o of (5.63) evolves (:mod:`bhgrasp.controllers.grasp_lyapunov`).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import partial
from typing import Any

import numpy as np
import pinocchio as pin

from bhgrasp.controllers.adaptive_grasp import SMCAdaptiveGrasp
from bhgrasp.controllers.grasp_lyapunov import finger_lyapunov, force_integrals, object_lyapunov
from bhgrasp.controllers.grasp_options import GraspOptions
from bhgrasp.controllers.object_identification import ObjectIdentification
from bhgrasp.controllers.object_regressors import object_parameters
from bhgrasp.controllers.supervisor import GraspSupervisor
from bhgrasp.errors import InputError
from bhgrasp.grasp.metrics import slip_events_after
from bhgrasp.model.objects import Box
from bhgrasp.motion.excitation import PoseExcitation
from bhgrasp.scenarios.box_grasp import OFF_STOP_SPACING, box_grasp
from bhgrasp.scenarios.demo_result import MU_ASSUMED
from bhgrasp.scenarios.grasp_controllers import SQUEEZE
from bhgrasp.scenarios.uncertainty import sensor_model

MASS, ESTIMATE = 0.6, 0.3  # [kg] true box, and the box the controller is told (its inertia too)
RATES = (5.0, 1e-3)  # Gamma_o: mass [kg^2 / (N s)...], inertia; the composite law's P(0)
EXCITATION = {"amplitude": (0.0, 0.002, 0.002, 0.1, 0.1, 0.0), "frequency": (1.0, 1.1, 1.3, 2.0, 2.5, 1.0)}
"""Lift 10 mm, then +-2 mm along y and z and +-0.1 rad about x and y (frequencies [Hz]); none along x or about z."""
NOISE = {
    "pose_noise": (2e-4, 2e-3),
    "twist_noise": (2e-3, 2e-2),
    "force_noise": 0.1,
    "sensor_noise": (1e-4, 5e-3),
    "delay": 0.002,
}
"""The robustness table's combined sensing: a 0.2 mm / 2 mrad tracker, 2 mm/s / 20 mrad/s twist, 0.1 N force noise,
joint noise and a 2 ms delay."""
LAWS = ("thesis", "composite")
RISE = 1e-6  # a step of V_o counts as a rise above this fraction of V_o(0)


@dataclass
class IdentificationRun:
    """One identification run: the estimate over time and what it says.

    Samples from the grasp's start: ``estimate`` sigma_hat (N, 7), ``truth`` sigma (7,), ``lyapunov`` V_o [J],
    ``finger_lyapunov`` the finger part of V (5.63) [J] (without the hand parameters' constant term);
    ``slip_events`` the sliding contact samples.  Errors are in % of the true value.
    """

    law: str
    noisy: bool
    t: np.ndarray
    estimate: np.ndarray
    truth: np.ndarray
    lyapunov: np.ndarray
    slip_events: int
    finger_lyapunov: np.ndarray | None = None

    def mass_error(self, index: int = -1) -> float:
        """|m_hat - m| / m [%] at sample ``index``."""
        return float(100.0 * abs(self.estimate[index, 0] - self.truth[0]) / self.truth[0])

    def inertia_error(self, index: int = -1) -> float:
        """|I_hat - I|_F / |I|_F [%] at sample ``index``."""
        return float(
            100.0
            * np.linalg.norm(_tensor(self.estimate[index]) - _tensor(self.truth))
            / np.linalg.norm(_tensor(self.truth))
        )

    def axis_errors(self, index: int = -1) -> np.ndarray:
        """(I_hat_ii - I_ii) / I_ii [%] about the body x, y, z axes."""
        diagonal = [1, 4, 6]
        return 100.0 * (self.estimate[index, diagonal] - self.truth[diagonal]) / self.truth[diagonal]

    @property
    def rising(self) -> float:
        """Fraction of samples where V_o rises by more than :data:`RISE` V_o(0) (round-off aside)."""
        return float(np.mean(np.diff(self.lyapunov) > RISE * self.lyapunov[0]))

    @property
    def total_rising(self) -> float:
        """Fraction of samples where V = V_o + V_f rises by more than :data:`RISE` V(0)."""
        total = self.lyapunov + self.finger_lyapunov
        return float(np.mean(np.diff(total) > RISE * total[0]))


def _tensor(sigma: np.ndarray) -> np.ndarray:
    xx, xy, xz, yy, yz, zz = sigma[1:]
    return np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])


def identification_run(
    law: str = "composite",
    noisy: bool = False,
    duration: float = 8.0,
    seed: int = 0,
    hand_scale: float = 1.0,
    plant: dict[str, Any] | None = None,
    **controller: Any,
) -> IdentificationRun:
    """Grasp, lift and shake the box (module docstring) with ``law`` (one of :data:`LAWS`).

    Args:
        law: ``"thesis"`` ((5.52) alone) or ``"composite"`` (plus the measured wrench's prediction error).
        noisy: Sense with :data:`NOISE` (seeded by ``seed``) instead of exactly.
        duration: Simulated time [s] (the grasp closes at about 0.6 s, the shaking starts 0.5 s after the lift).
        seed: Seed of the sensor noise.
        hand_scale: The controller's hand model has every link's mass and inertia scaled by this
            (:meth:`~bhgrasp.model.hand.Hand.perturbed`; 1: the true hand).
        plant: Extra :func:`~bhgrasp.scenarios.box_grasp.box_grasp` arguments (e.g. ``joint_friction``).
        controller: Extra :class:`~bhgrasp.controllers.adaptive_grasp.SMCAdaptiveGrasp` arguments.
    """
    traj, setup, grasp = _simulate(law, noisy, duration, seed, hand_scale, plant or {}, controller)
    return summarise(traj, setup, grasp, law, noisy)


def hand_model_error(duration: float, hand_scale: float, rate: float) -> dict[str, float]:
    """How well hand adaptation (5.60) at gamma_f = ``rate`` learns a hand model scaled by ``hand_scale``.

    The composite law shakes the box (exact sensing); over the last second, the inverse-dynamics torques
    Y(q, v, a) sigma of the true hand along the run's motion (a by central differences) against those of the nominal
    and of the learnt model: rms [N m] of the true torques and of both errors.
    """
    traj, setup, grasp = _simulate("composite", False, duration, 0, hand_scale, {}, {"hand_adaptation": rate})
    hand, dt = setup.hand, float(traj.t[1] - traj.t[0])
    true, nominal, learnt = hand.inertial_parameters(), grasp.nominal.inertial_parameters(), grasp.hand_estimate
    torques = []
    for k in np.flatnonzero(traj.t >= traj.t[-1] - 1.0)[1:-1]:
        regressor = hand.regressor(traj.q[k], traj.v[k], (traj.v[k + 1] - traj.v[k - 1]) / (2.0 * dt))
        torques.append([regressor @ true, regressor @ (nominal - true), regressor @ (learnt - true)])
    rms = np.sqrt(np.mean(np.square(np.array(torques)), axis=(0, 2)))
    return {
        "torque_Nm": float(rms[0]),
        "nominal_torque_error_Nm": float(rms[1]),
        "learnt_torque_error_Nm": float(rms[2]),
        "error_ratio": float(rms[2] / rms[1]),
    }


def _simulate(law: str, noisy: bool, duration: float, seed: int, hand_scale: float, plant: dict, controller: dict):
    if law not in LAWS:
        raise InputError(f"`law` must be one of {LAWS}, got {law!r}")
    setup = box_grasp(mass=MASS, finger_spacing=OFF_STOP_SPACING, **plant)
    nominal = Box(size=setup.box.size, mass=ESTIMATE)
    identification = ObjectIdentification() if law == "composite" else None
    model = setup.hand if hand_scale == 1.0 else setup.hand.perturbed(hand_scale)
    grasp = SMCAdaptiveGrasp(
        model,
        nominal,
        object_adaptation=RATES,
        options=GraspOptions(mu=MU_ASSUMED, squeeze=SQUEEZE),
        identification=identification,
        **controller,
    )
    path = partial(PoseExcitation, **EXCITATION)
    space = setup.manipulable_space()
    for offset in path(pin.SE3.Identity()).extremes():  # refused before simulating if the grasp cannot make it
        space.check(offset)
    supervisor = GraspSupervisor(setup.hand, setup.q_contact, grasp, path=path)
    sensors = sensor_model(**NOISE) if noisy else None
    traj = setup.simulator.run(supervisor, duration, state=setup.state, sensors=sensors, seed=seed)
    return traj, setup, grasp


def summarise(traj, setup, grasp: SMCAdaptiveGrasp, law: str, noisy: bool) -> IdentificationRun:
    """The run's :class:`IdentificationRun` from the trajectory (true object state, the law's log)."""
    logged = [traj.log[key] for key in ("object_sliding", "parameter_information") if key in traj.log]
    finite = np.all([np.isfinite(value.reshape(len(value), -1)).all(axis=1) for value in logged], axis=0)
    held = np.flatnonzero((traj.log["phase"] >= 1) & finite)  # the grasp law's cycles
    t, log = traj.t[held], {key: value[held] for key, value in traj.log.items()}
    truth = object_parameters(setup.box.mass, setup.box.inertia)
    fixed = grasp.parameter_information()
    information = log.get("parameter_information", np.broadcast_to(fixed, (len(t), 7, 7)))
    lyapunov = np.zeros(len(t))
    for i, k in enumerate(held):
        x, y, z, w = traj.object_quaternion[k, 0]
        rotation = pin.Quaternion(w, x, y, z).toRotationMatrix()
        kinetic, parameter = object_lyapunov(
            setup.box.mass,
            setup.box.inertia,
            rotation,
            log["object_sliding"][i],
            log["object_parameters"][i],
            information[i],
        )
        lyapunov[i] = kinetic + parameter
    steps = np.diff(traj.t, prepend=traj.t[0])[held]  # each grasp cycle's length; the first has none (its clock
    steps[0] = 0.0  # starts there), nor the run's last sample (no control call: it repeats the last cycle's log)
    if held[-1] == len(traj.t) - 1:
        steps[-1] = 0.0
    integrals = force_integrals(log["desired_force"], log["force_error"], steps)
    fingers = np.array(
        [
            sum(
                finger_lyapunov(
                    setup.hand.mass_matrix(traj.q[k]), log["joint_sliding"][i], integrals[i], grasp.force_integral
                )
            )
            for i, k in enumerate(held)
        ]
    )
    return IdentificationRun(
        law=law,
        noisy=noisy,
        t=t,
        estimate=log["object_parameters"],
        truth=truth,
        lyapunov=lyapunov,
        slip_events=slip_events_after(setup.hand, traj, int(held[0])),
        finger_lyapunov=fingers,
    )


__all__ = [
    "ESTIMATE",
    "EXCITATION",
    "LAWS",
    "MASS",
    "NOISE",
    "RATES",
    "IdentificationRun",
    "hand_model_error",
    "identification_run",
    "summarise",
]
