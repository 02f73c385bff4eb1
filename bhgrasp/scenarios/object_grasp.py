"""Grasp any object with any hand, as the synthesis plans it: the chapter-5 scene around a box, cylinder or sphere.

:func:`object_grasp` places the object (its ``pose`` in the hand's world) on a small pedestal, synthesises its
grasp unless one is given, and builds the simulator as the thesis' scene does (:mod:`~bhgrasp.scenarios.box_grasp`:
contacts 10 kN/m, friction 0.8, joint damping 0.05 N m s/rad, the hand fully actuated).  The synthesis is the
approach-line search of :mod:`bhgrasp.grasp.synthesis` for the BH8-280 (the default hand) and the opposition search
of :mod:`bhgrasp.grasp.opposition` for any other hand, which also plans the approach's target (pads pressed
``closing`` into the object); the controller then cancels the drive's joint damping, which it knows (a light hand's
links, ~5e-6 kg m^2 on the Allegro's, would lag behind a law that ignores it).  :func:`run_object_grasp` runs it as
the demo does
(:func:`~bhgrasp.scenarios.grasp_demo.run_grasp_demo`): approach from the pre-grasp configuration, squeeze, move
by ``offset`` with the SMC-adaptive law from a wrong mass, after refusing a motion the grasp cannot make or whose
path drives the object into its pedestal.  The pedestal is a 20 mm high column under the object's centre, 40 % of
its footprint (the thesis' box stands on a 20 mm cube, 40 % of its 50 mm faces).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
import pinocchio as pin

from bhgrasp._validation import as_positive
from bhgrasp.controllers.motor_commands import MotorCommands
from bhgrasp.controllers.supervisor import GraspSupervisor
from bhgrasp.controllers.supervisor_options import Approach, Planning
from bhgrasp.data import State
from bhgrasp.grasp.candidates import GraspCandidate
from bhgrasp.grasp.clearance import check_clearance
from bhgrasp.grasp.manipulability import ManipulableSpace, manipulable_space
from bhgrasp.grasp.opposition import opposed_grasp
from bhgrasp.grasp.synthesis import synthesize
from bhgrasp.model.barrett_hand import BarrettHand
from bhgrasp.model.hand import Hand
from bhgrasp.model.objects import Box, Cylinder, FixedBox, Sphere
from bhgrasp.scenarios.box_grasp import CONTACT_HEIGHT, FRICTION, JOINT_DAMPING, STIFFNESS
from bhgrasp.scenarios.demo_result import MU_ASSUMED, GraspDemoResult, evaluate_demo
from bhgrasp.scenarios.grasp_controllers import grasp_controller
from bhgrasp.sim import Simulator
from bhgrasp.sim.actuation import FullyActuated
from bhgrasp.sim.contact_law import SpringDamper
from bhgrasp.sim.scene import Scene

PEDESTAL_HEIGHT, PEDESTAL_SHARE = 0.02, 0.4  # [m], share of the object's footprint
# Example objects of household sizes the BH8-280 spans, each centred where the thesis' box is: key -> (label, object)
CENTRE = pin.SE3(np.eye(3), np.array([0.0, 0.0, CONTACT_HEIGHT]))
OBJECTS = {
    "box": ("thesis box 0.06 x 0.05 x 0.05 m, 0.6 kg", Box(size=(0.06, 0.05, 0.05), mass=0.6, pose=CENTRE)),
    "cube": ("cube 0.05 m, 0.3 kg", Box(size=(0.05, 0.05, 0.05), mass=0.3, pose=CENTRE)),
    "can": ("can r 33 mm x 100 mm, 0.35 kg", Cylinder(radius=0.033, length=0.10, mass=0.35, pose=CENTRE)),
    "ball": ("ball r 35 mm, 0.2 kg", Sphere(radius=0.035, mass=0.2, pose=CENTRE)),
}


@dataclass
class ObjectGrasp:
    """A ready-to-run grasp of ``item``: simulator, start state (pre-grasp), hand and the synthesised candidate.

    ``cancel_damping``: the controller should cancel the drive's known viscous joint damping
    (:class:`~bhgrasp.controllers.motor_commands.MotorCommands`).
    """

    simulator: Simulator
    state: State
    hand: Hand
    item: Any
    candidate: GraspCandidate
    cancel_damping: bool = False

    def manipulable_space(self) -> ManipulableSpace:
        """The object motions the planned contacts allow (:mod:`bhgrasp.grasp.manipulability`)."""
        c = self.candidate
        frames = [self.hand.fingertip_frames[f] for f in c.fingers]
        return manipulable_space(
            self.hand, c.q_contact, c.points, c.normals, frames, self.item.pose.translation, c.fingers
        )

    def check_clearance(self, offset: Any) -> None:
        """Refuse a motion that drives the object into its pedestal (:mod:`bhgrasp.grasp.clearance`)."""
        check_clearance(self.item.geometry(), self.item.pose, offset, self.simulator.scene.environment)


def object_grasp(
    item: Any,
    candidate: GraspCandidate | None = None,
    mu: float = MU_ASSUMED,
    dt: float = 1e-3,
    hand: Hand | None = None,
    stiffness: float = STIFFNESS,
    damping: float = JOINT_DAMPING,
    **synthesis: Any,
) -> ObjectGrasp:
    """Build the scene around ``item`` (a :class:`~bhgrasp.model.objects.RigidObject` placed in ``hand``'s world).

    Args:
        item: The object (its friction is set to the scene's 0.8).
        candidate: The grasp (default: synthesised with ``mu`` and ``synthesis``'s options, module docstring).
        mu: Friction coefficient the synthesis assumes.
        dt: Simulator step [s].
        hand: Any :class:`~bhgrasp.model.hand.Hand` (default: the BH8-280, :class:`~bhgrasp.model.hand.BarrettHand`).
        stiffness: Contact stiffness [N/m] (damping 2e-3 s times it).
        damping: Viscous joint damping [N m s/rad] of the drive.

    Raises:
        UnreachableError: The synthesis finds no grasp (the message says what was searched).
    """
    barrett = hand is None or isinstance(hand, BarrettHand)
    hand = BarrettHand() if hand is None else hand
    item = replace(item, friction=FRICTION, mass=item.mass, density=None)
    if candidate is None:
        candidate = synthesize(hand, item, mu, **synthesis) if barrett else opposed_grasp(hand, item, mu, **synthesis)
    shape = item.geometry()
    shape.computeLocalAABB()
    corners = np.array(np.meshgrid(*zip(shape.aabb_local.min_, shape.aabb_local.max_))).reshape(3, -1).T
    world = corners @ item.pose.rotation.T
    footprint = PEDESTAL_SHARE * (world.max(axis=0) - world.min(axis=0))[:2]
    top = item.pose.translation[2] + world[:, 2].min()
    centre = np.array([*item.pose.translation[:2], top - 0.5 * PEDESTAL_HEIGHT])
    pedestal = FixedBox(size=(*footprint, PEDESTAL_HEIGHT), pose=pin.SE3(np.eye(3), centre), friction=FRICTION)
    stiffness = as_positive(stiffness, "stiffness")
    law = SpringDamper(stiffness=stiffness, damping=2e-3 * stiffness, friction=FRICTION)
    drive = FullyActuated(hand, damping=as_positive(damping, "damping"))
    simulator = Simulator(Scene(hand, [item], environment=[pedestal]), dt=dt, contact=law, actuation=drive)
    state = simulator.initial_state(candidate.q_pregrasp)
    return ObjectGrasp(simulator, state, hand, item, candidate, cancel_damping=not barrett)


def run_object_grasp(
    setup: ObjectGrasp,
    offset: Any = (0.0, 0.0, 0.01, 0.0, 0.0, 0.0),
    estimate: float | None = None,
    duration: float = 3.0,
    controller: str = "smc-adaptive",
) -> GraspDemoResult:
    """Grasp, squeeze and move the object by ``offset`` (the demo's sequence).

    ``estimate`` [kg]: the controller's
    initial mass (default: half the true one).

    Raises:
        UnreachableError: ``offset`` is outside the grasp's manipulable space, or its path hits the pedestal.
    """
    setup.manipulable_space().check(offset)
    setup.check_clearance(offset)
    mass = setup.item.mass
    estimate = 0.5 * mass if estimate is None else float(estimate)
    nominal = replace(setup.item, mass=estimate, density=None)
    grasp = grasp_controller(controller, setup.hand, nominal)
    damping = float(np.max(setup.simulator.actuation.damping))  # the drive's (one value for every joint)
    supervisor = GraspSupervisor(
        setup.hand,
        setup.candidate.q_contact,
        grasp,
        offset=offset,
        fingers=setup.candidate.fingers,
        q_close=setup.candidate.q_close,
        approach=Approach(damping=0.0 if setup.cancel_damping else damping),
        planning=Planning(object_shape=setup.item.geometry()),
    )
    law = MotorCommands(supervisor, setup.simulator.actuation.drive) if setup.cancel_damping else supervisor
    start = time.perf_counter()
    traj = setup.simulator.run(law, duration, state=setup.state, progress=False)
    wall = time.perf_counter() - start
    return evaluate_demo(traj, setup.hand, controller, mass, estimate, supervisor, wall, setup.simulator.scene)


__all__ = ["OBJECTS", "PEDESTAL_HEIGHT", "PEDESTAL_SHARE", "ObjectGrasp", "object_grasp", "run_object_grasp"]
