"""The chapter-5 grasp scene: the Barrett hand, a 0.06 x 0.05 x 0.05 m box (thesis 5.7) on a small pedestal.

The box stands on a 20 mm fixed pedestal between the fingers, its 50 mm faces normal to y.  The contact points are
the centres of those faces, F1 and F2 on the -y face at x = -/+ 25 mm and F3 on the +y face; the contact
configuration comes from the fingertip IK (thesis 5.4.2) with each fingertip pad (radius 10 mm) touching its face.
There the spread joints sit on their stop (0): ``finger_spacing`` above 50 mm puts F1 and F2 further apart, the spread
off its stop (:data:`OFF_STOP_SPACING`), which the object's rotations about y need.
The hand starts opened by ``opening`` [rad] on every proximal joint.  Contacts are spring-dampers of 10 kN/m
(the thesis' K_s) with friction 0.8; the joints have 0.05 N m s/rad of damping.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import pinocchio as pin

from bhgrasp._validation import as_positive
from bhgrasp.data import State
from bhgrasp.errors import InputError
from bhgrasp.grasp.clearance import check_clearance
from bhgrasp.grasp.manipulability import ManipulableSpace, manipulable_space
from bhgrasp.model.barrett_hand import BarrettHand
from bhgrasp.model.hand import Hand
from bhgrasp.model.hand_ik import ik
from bhgrasp.model.objects import Box, FixedBox
from bhgrasp.sim import Simulator
from bhgrasp.sim.actuation import Actuation, BarrettActuation, FullyActuated
from bhgrasp.sim.contact_law import SpringDamper
from bhgrasp.sim.scene import Scene

BOX_SIZE = (0.06, 0.05, 0.05)  # [m] thesis 5.7 (x along the palm, y between the fingers, z up)
PAD_RADIUS = 0.010  # [m] fingertip pad of the packaged URDF
CONTACT_HEIGHT = 0.172  # [m] box centre above the palm: F3's distal joint near mid-range at contact
PEDESTAL = 0.02  # [m] edge of the pedestal cube
FRICTION = 0.8
STIFFNESS = 1e4  # [N/m]
JOINT_DAMPING = 0.05  # [N m s/rad]
KNUCKLE_SPACING = 0.05  # [m] between F1's and F2's knuckles (spread axes): contacts this far apart put the spread at 0
OFF_STOP_SPACING = 0.055  # [m] F1 and F2 contacts 2.5 mm outside their knuckles: spread 0.07 rad, off its stop


@dataclass
class BoxGrasp:
    """A ready-to-run grasp: simulator, start state, hand, the box, the contact and start configurations.

    ``q_close`` is the configuration the approach should drive to (``None``: the supervisor's default, the
    contact configuration closed on the non-spread joints); ``fingers`` the grasping fingers (``None``: all);
    ``cancel_damping``: the controller should cancel the drive's known viscous damping (wrap it in
    :class:`~bhgrasp.controllers.motor_commands.MotorCommands`), for hands whose links are too light for a model-based
    law to ignore it.
    """

    simulator: Simulator
    state: State
    hand: Hand
    box: Box
    q_contact: np.ndarray
    q_start: np.ndarray
    q_close: np.ndarray | None = None
    fingers: tuple[str, ...] | None = None
    cancel_damping: bool = False

    def manipulable_space(self) -> ManipulableSpace:
        """The object motions the planned grasp allows (:mod:`bhgrasp.grasp.manipulability`), before simulating.

        Each grasping fingertip at ``q_contact`` touches the nearest point of the box's surface.
        """
        fingers = self.fingers or self.hand.fingers
        tips = self.hand.fingertip_positions(self.q_contact)[[self.hand.fingers.index(f) for f in fingers]]
        pose, half = self.box.pose, 0.5 * np.asarray(self.box.size)
        local = (tips - pose.translation) @ pose.rotation  # box frame
        points = np.clip(local, -half, half) @ pose.rotation.T + pose.translation  # the nearest surface points
        normals = points - tips  # from the fingertip into the box
        normals /= np.linalg.norm(normals, axis=1, keepdims=True)
        frames = [self.hand.fingertip_frames[f] for f in fingers]
        return manipulable_space(self.hand, self.q_contact, points, normals, frames, pose.translation, fingers)

    def check_clearance(self, offset: Any) -> None:
        """Refuse an object motion that drives the box into its pedestal (:mod:`bhgrasp.grasp.clearance`)."""
        check_clearance(self.box.geometry(), self.box.pose, offset, self.simulator.scene.environment)


def box_grasp(
    mass: float = 1.0,
    actuation: str = "full",
    opening: float = 0.3,
    dt: float = 1e-3,
    stiffness: float = STIFFNESS,
    friction: float = FRICTION,
    joint_friction: float = 0.0,
    joint_damping: float = JOINT_DAMPING,
    torque_limit: float | None = None,
    finger_spacing: float = KNUCKLE_SPACING,
) -> BoxGrasp:
    """Build the scene.

    Args:
        mass: Box mass [kg] (the thesis' m_o = 1 kg).
        actuation: ``"full"`` (one torque per joint) or ``"barrett"`` (the BH8-280's four motors).
        opening: Proximal opening [rad] of the start configuration relative to the contact configuration.
        dt: Simulator step [s].
        stiffness: Contact stiffness [N/m] (damping 2e-3 s times it).
        friction: The true friction coefficient of the box, its pedestal and the finger pads.
        joint_friction: Coulomb friction [N m] on every joint.
        joint_damping: Viscous joint damping [N m s/rad].
        torque_limit: Each joint torque [N m] is clipped to this (``"full"`` actuation; default: no limit).
        finger_spacing: Distance [m] between F1's and F2's contact points along x (the thesis' 50 mm, the spread on
            its stop; up to the box's 60 mm edge).
    """
    mass = as_positive(mass, "mass")
    friction = as_positive(friction, "friction")
    spacing = as_positive(finger_spacing, "finger_spacing")
    if not KNUCKLE_SPACING <= spacing <= BOX_SIZE[0]:
        raise InputError(
            f"`finger_spacing` must be within [{KNUCKLE_SPACING}, {BOX_SIZE[0]}] m (the knuckles' spacing, where the "
            f"spread is 0, to the box's edge), got {finger_spacing}"
        )
    if torque_limit is not None and actuation != "full":
        raise InputError(f"`torque_limit` applies to the 'full' actuation, got actuation {actuation!r}")
    hand = BarrettHand()
    centre = np.array([0.0, 0.0, CONTACT_HEIGHT])
    half = 0.5 * BOX_SIZE[1] + PAD_RADIUS
    targets = {
        "F1": centre + np.array([-0.5 * spacing, -half, 0.0]),
        "F2": centre + np.array([0.5 * spacing, -half, 0.0]),
        "F3": centre + np.array([0.0, half, 0.0]),
    }
    guess = hand.configuration(
        F1_proximal=1.2, F1_distal=0.5, F2_proximal=1.2, F2_distal=0.5, F3_proximal=1.2, F3_distal=0.5
    )
    q_contact = ik(hand, targets, guess, tolerance=1e-7).q
    q_start = q_contact.copy()
    for finger in hand.fingers:
        index = hand.joint_index(f"{finger}_proximal")
        q_start[index] = max(q_contact[index] - opening, hand.lower[index])
    box = Box(size=BOX_SIZE, mass=mass, friction=friction, pose=pin.SE3(np.eye(3), centre))
    pedestal_centre = centre - [0.0, 0.0, 0.5 * BOX_SIZE[2] + 0.5 * PEDESTAL]
    pedestal = FixedBox(size=(PEDESTAL,) * 3, pose=pin.SE3(np.eye(3), pedestal_centre), friction=friction)
    joints = {"damping": joint_damping, "friction": joint_friction}
    if actuation == "full":
        drive: Actuation = FullyActuated(hand, limit=torque_limit, **joints)
    elif actuation == "barrett":
        drive = BarrettActuation(hand, **joints)
    else:
        raise InputError(f"`actuation` must be 'full' or 'barrett', got {actuation!r}")
    law = SpringDamper(stiffness=stiffness, damping=2e-3 * stiffness, friction=friction)
    simulator = Simulator(Scene(hand, [box], environment=[pedestal]), dt=dt, contact=law, actuation=drive)
    return BoxGrasp(simulator, simulator.initial_state(q_start), hand, box, q_contact, q_start)


__all__ = ["BOX_SIZE", "BoxGrasp", "box_grasp"]
