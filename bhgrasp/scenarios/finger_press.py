"""A finger pressing a spring-mounted box (thesis chapter 4's benches), the simulator that runs it, and its metrics.

The thesis' compliant objects (4.3)-(4.7): a box of mass :data:`OBJECT_MASS` on a spring K_s (plus a light damper,
0.3 of critical) that can only move along the pushing direction, touched through the spring-damper contact
:data:`CONTACT`, so that the fingertip sees k_e = (1/K_s + 1/k_c)^-1 (:func:`effective_stiffness`).
:func:`planar_setup` builds the thesis' planar finger (or its one-link finger) in front of one, :func:`f3_setup`
Barrett finger F3, whose first touch :func:`probe_surface` measures; :func:`run` simulates a controller from the
setup's start and :func:`normal_force` reads the force the finger exerts along the normal [N] from the contacts;
:func:`force_metrics` reads contact time, impact, peak, final force, overshoot, 2 % settling and steady-state error
from it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from bhgrasp import metrics
from bhgrasp.controllers import WorkspaceComputedTorque
from bhgrasp.controllers.base import Controller
from bhgrasp.data import Trajectory
from bhgrasp.errors import InputError
from bhgrasp.model.barrett_hand import BarrettHand
from bhgrasp.model.hand import Hand
from bhgrasp.model.objects import Box
from bhgrasp.model.planar import thesis_impedance_finger, thesis_one_link_finger
from bhgrasp.model.spring_mounted import SpringMounted
from bhgrasp.motion.trajectories import Reference
from bhgrasp.sim import Simulator
from bhgrasp.sim.contact_law import SpringDamper
from bhgrasp.sim.scene import Scene

DT = 1e-3
OBJECT_MASS = 0.25  # [kg] thesis 4.5.3
CONTACT = SpringDamper(stiffness=1e6, damping=200.0, friction=0.5)
STIFFNESSES = (1e3, 1e4, 2e4, 3e4, 5e4)  # K_s [N/m], thesis 10-50 kN/m (and 1e3)
F3_GAINS = (430.0, 175.0)  # inner loop Kp [1/s^2], Kv [1/s]: thesis F3
PLANAR_GAINS = (80.0, 37.0)  # thesis planar finger
F3_IMPEDANCE = {"mass": 0.05, "stiffness": 100.0}  # ours: M_I [kg], K_I [N/m] for the BH8-280 fingertip
F3_START = {"F3_proximal": 0.3, "F3_distal": 0.5, "F1_proximal": 0.3, "F2_proximal": 0.3}


def effective_stiffness(spring: float, contact: float = CONTACT.stiffness) -> float:
    """k_e [N/m] the fingertip sees: the object spring in series with the contact spring."""
    return 1.0 / (1.0 / spring + 1.0 / contact)


@dataclass
class Setup:
    """A finger, a compliant object in front of it, and a simulator."""

    hand: Hand
    finger: str
    simulator: Simulator
    q0: np.ndarray
    tip0: np.ndarray
    normal: np.ndarray  # pushing direction (unit, world)
    surface: float  # normal coordinate [m] of the fingertip frame at first touch (measured by a probe)
    k_e: float

    def surface_point(self) -> np.ndarray:
        """A point whose normal coordinate is the surface's (the tip's start moved along the normal)."""
        return self.tip0 + (self.surface - self.normal @ self.tip0) * self.normal


def _spring_box(
    centre: np.ndarray, size: tuple[float, float, float], direction: np.ndarray, spring: float, friction: float = 0.5
):
    box = Box(size=size, mass=OBJECT_MASS, friction=friction, pose=pin.SE3(np.eye(3), centre), name="object")
    return SpringMounted(box, direction=direction, stiffness=spring, damping=0.6 * np.sqrt(spring * OBJECT_MASS))


def planar_setup(spring: float, one_link: bool = False, friction: float = 0.5) -> Setup:
    """The thesis' planar finger (2 links, 1 kg each, 0.5 m) or one-link finger pushing a box along +x.

    ``friction`` is the box's Coulomb coefficient (0: a frictionless face, used to check
    :func:`~bhgrasp.thesis.chapter4_closed_form.steady_force`).
    """
    hand = thesis_one_link_finger() if one_link else thesis_impedance_finger()
    q0 = np.array([0.0]) if one_link else np.array([-0.4, 1.4])
    tip0 = hand.fingertip_positions(q0)[0]
    normal = np.array([0.0, 1.0, 0.0]) if one_link else np.array([1.0, 0.0, 0.0])
    gap = 0.06 if one_link else 0.05  # [m] between the tip sphere and the object at start
    radius = 0.01 if one_link else 0.02
    face = tip0 + (gap + radius) * normal
    centre = face + 0.05 * normal
    scene = Scene(hand, objects=[_spring_box(centre, (0.1, 0.1, 0.1), normal, spring, friction)])
    sim = Simulator(scene, dt=DT, contact=CONTACT)
    return Setup(hand, "tip", sim, q0, tip0, normal, float(normal @ face) - radius, effective_stiffness(spring))


def f3_setup(spring: float, friction: float = 0.5) -> Setup:
    """Barrett finger F3 closing onto a tilted box that moves along the fingertip's closing direction.

    The normal is the direction the F3 tip moves when the proximal joint turns at the start pose (in the finger's
    y-z plane, 43 deg from the palm): a 3-D direction, not a coordinate axis.  ``friction`` is the box's Coulomb
    coefficient (0: a frictionless face, used to check :func:`~bhgrasp.thesis.chapter4_closed_form.steady_force`).
    """
    hand = BarrettHand()
    q0 = hand.configuration(**F3_START)
    tip0 = hand.fingertip_positions(q0)[2]
    closing = hand.fingertip_jacobian(q0, "F3")[:, hand.joint_index("F3_proximal")]
    normal = closing / np.linalg.norm(closing)
    side = np.array([1.0, 0.0, 0.0])
    rotation = np.column_stack((side, np.cross(normal, side), normal))  # box z axis along the normal
    half = 0.03
    centre = tip0 + (0.02 + 0.01 + half) * normal  # 2 cm gap ahead of the 1 cm tip sphere
    box = Box(
        size=(0.06, 0.06, 2 * half), mass=OBJECT_MASS, friction=friction, pose=pin.SE3(rotation, centre), name="object"
    )
    mounted = SpringMounted(box, direction=normal, stiffness=spring, damping=0.6 * np.sqrt(spring * OBJECT_MASS))
    sim = Simulator(Scene(hand, objects=[mounted]), dt=DT, contact=CONTACT)
    setup = Setup(hand, "F3", sim, q0, tip0, normal, 0.0, effective_stiffness(spring))
    setup.surface = probe_surface(setup)
    return setup


def probe_surface(setup: Setup, speed: float = 0.01, limit: float = 3.0) -> float:
    """Normal coordinate [m] of the fingertip frame at first contact, by a slow probing approach (calibration)."""
    sim, hand = setup.simulator, setup.hand
    start = setup.tip0
    path = _Ramp(start, setup.normal, speed)
    controller = WorkspaceComputedTorque(hand, {setup.finger: path}, kp=F3_GAINS[0], kv=F3_GAINS[1])
    state = sim.initial_state(setup.q0)
    controller.reset(state)
    index = hand.fingers.index(setup.finger)
    for _ in range(round(limit / sim.dt)):
        state, info = sim.step(state, controller(state.t, state))
        if len(info.contacts):
            return float(setup.normal @ hand.fingertip_positions(state.q)[index])
    raise InputError(f"probing along {setup.normal} for {limit} s found no contact: place the object within reach")


class _Ramp(Reference):
    """start + speed t normal: a constant-speed probing path [m]."""

    def __init__(self, start: np.ndarray, normal: np.ndarray, speed: float) -> None:
        self.start, self.normal, self.speed = start, normal, speed

    @property
    def size(self) -> int:
        return 3

    def __call__(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        return self.start + self.speed * t * self.normal, self.speed * self.normal, np.zeros(3)


def run(setup: Setup, controller: Controller, duration: float) -> Trajectory:
    """Simulate ``controller`` from the setup's start."""
    sim = setup.simulator
    return sim.run(controller, duration, state=sim.initial_state(setup.q0), progress=False)


def normal_force(setup: Setup, traj: Trajectory) -> np.ndarray:
    """Force the finger exerts on the object along the normal [N], per sample (from the recorded contacts)."""
    forces = np.zeros(len(traj))
    for k in range(len(traj)):
        rows = slice(traj.contact_offsets[k], traj.contact_offsets[k + 1])
        forces[k] = float(np.sum(traj.contact_force[rows] @ setup.normal))
    return forces


IMPACT_WINDOW = 0.02  # [s] after first contact: the impact transient, reported apart from the pushing peak


@dataclass(frozen=True)
class ForceMetrics:
    """Force response after first contact.

    Attributes: contact_time [s], impact (largest force in the first IMPACT_WINDOW after contact, before any
    controller can react) [N], peak (largest force after it) [N], final [N], overshoot [%], settling (2 %, after
    contact) [s], error (steady state, % of f_d).
    """

    contact_time: float
    impact: float
    peak: float
    final: float
    overshoot: float
    settling: float
    error: float


def force_metrics(t: np.ndarray, force: np.ndarray, desired: float | None = None) -> ForceMetrics:
    """Metrics of a force response; ``desired`` None uses the final force as the target (PIM, uncontrolled)."""
    touching = np.flatnonzero(force > 1e-6)
    if len(touching) == 0:
        return ForceMetrics(np.nan, 0.0, 0.0, 0.0, np.nan, np.nan, np.nan)
    k0 = touching[0]
    window = t < t[k0] + IMPACT_WINDOW
    impact = float(force[window].max())
    peak = float(force[~window].max()) if np.any(~window) else 0.0
    final = float(np.mean(force[-max(2, len(force) // 20) :]))
    target = final if desired is None else desired
    response = metrics.step_response(t[k0:], force[k0:], target, start=0.0)
    error = np.nan if desired is None else 100.0 * abs(final - desired) / desired
    overshoot = np.nan if desired is None else 100.0 * max(0.0, peak - desired) / desired  # after the impact
    return ForceMetrics(float(t[k0]), impact, peak, final, overshoot, float(response.settling_time[0]), error)


__all__ = [
    "CONTACT",
    "DT",
    "F3_GAINS",
    "F3_IMPEDANCE",
    "F3_START",
    "IMPACT_WINDOW",
    "OBJECT_MASS",
    "PLANAR_GAINS",
    "STIFFNESSES",
    "ForceMetrics",
    "Setup",
    "effective_stiffness",
    "f3_setup",
    "force_metrics",
    "normal_force",
    "planar_setup",
    "probe_surface",
    "run",
]
