"""The reference grasp scene: the Barrett hand squeezes a 0.2 kg box between F1 + F2 and F3 and holds it.

Used by the demo, the simulator tests and ``benchmarks/bench_sim.py``.  The fingers sit at proximal 1.2 rad,
distal 0.3 rad (spread 0, so F1 and F2 face F3); the box (0.08 m long, 0.05 m tall) is as wide as the gap between
the fingertip pads minus a 0.2 mm preload per side.  The controller is gravity compensation + a posture spring
(2 N m/rad) + Jacobian-transpose squeeze forces (F1, F2: 2 N; F3: 4 N, along y), with 0.05 N m s/rad of implicit
joint damping: the friction margin is mu * sum(f_n) / (m g) = 0.8 * 8 N / 1.96 N = 3.3.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from bhgrasp.data import State
from bhgrasp.model.barrett_hand import BarrettHand
from bhgrasp.model.hand import Hand
from bhgrasp.model.objects import Box
from bhgrasp.sim import Simulator
from bhgrasp.sim.actuation import FullyActuated
from bhgrasp.sim.contact_law import SpringDamper
from bhgrasp.sim.scene import Scene

SQUEEZE = {"F1": np.array([0.0, 2.0, 0.0]), "F2": np.array([0.0, 2.0, 0.0]), "F3": np.array([0.0, -4.0, 0.0])}  # [N]
POSTURE_GAIN = 2.0  # [N m/rad]
JOINT_DAMPING = 0.05  # [N m s/rad]
BOX_MASS = 0.2  # [kg]


@dataclass
class HoldScenario:
    """A ready-to-run hold: simulator, start state, controller, and the box's initial height [m]."""

    simulator: Simulator
    state: State
    controller: Callable[[float, State], np.ndarray]
    box_height: float
    hand: Hand


def reference_hold(
    dt: float = 1e-3, stiffness: float = 1e4, damping: float | None = None, box_mass: float = BOX_MASS
) -> HoldScenario:
    """Build the reference hold: contact stiffness [N/m] (damping default 2e-3 s * stiffness), step [s], box mass [kg].

    The built-in squeeze controller is sized for the default 0.2 kg box.
    """
    hand = BarrettHand()
    q0 = hand.configuration(
        F1_proximal=1.2, F1_distal=0.3, F2_proximal=1.2, F2_distal=0.3, F3_proximal=1.2, F3_distal=0.3
    )
    tips = hand.fingertip_positions(q0)
    size = (0.08, 2 * (tips[2, 1] - 0.010) + 0.0004, 0.05)  # between the 10 mm pads, 0.2 mm preload each side
    height = float(tips[2, 2])
    box = Box(size=size, mass=box_mass, friction=0.8, pose=pin.SE3(np.eye(3), np.array([0.0, 0.0, height])))
    law = SpringDamper(stiffness=stiffness, damping=2e-3 * stiffness if damping is None else damping, friction=0.8)
    simulator = Simulator(Scene(hand, [box]), dt=dt, contact=law, actuation=FullyActuated(hand, damping=JOINT_DAMPING))

    def controller(t: float, state: State) -> np.ndarray:
        tau = hand.gravity_torques(state.q) + POSTURE_GAIN * (q0 - state.q)
        for finger, force in SQUEEZE.items():
            tau += hand.fingertip_jacobian(state.q, finger).T @ force
        return tau

    return HoldScenario(simulator, simulator.initial_state(q0), controller, height, hand)
