"""The generic-hand grasp scene: the Allegro hand (example-robot-data, 16 DOF) grasps a box on a pedestal.

The demonstration that the grasp pipeline takes any :class:`~bhgrasp.hand.Hand`: nothing here is specific
to the Allegro beyond the choice of fingers, the box placement and the mounting.  The hand is mounted with its
fingers pointing along world x and its palm facing world y (base frame: fingers along z, palm normal x; the world
gets base y as "up"), so the thumb and the index + middle fingertips squeeze the box along world x while gravity
pulls along the faces, as in the Barrett scene (:mod:`bhgrasp.experiments.box_grasp`).  The ring finger stays
straight and out of the way.

The box (0.05 x 0.07 x 0.05 m in the hand's base axes, its 70 mm side between the index and middle fingers) rests
on a 20 mm fixed pedestal; its centre sits at (0.09, 0.02, 0.02) m in the base frame, a placement chosen for
joint-limit margin (>= 0.38 rad on every grasping joint) and clearance (every link but the fingertip spheres
>= 2.4 mm from the box at contact).  The contact configuration comes from the damped-least-squares IK with each
12 mm fingertip sphere touching its face; the start configuration from the same IK with the targets drawn
``opening`` [m] back along the face normals, and the approach's target with them pushed ``closing`` [m] into the
box.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from bhgrasp._validation import as_positive
from bhgrasp.experiments.box_grasp import FRICTION, JOINT_DAMPING, PEDESTAL, STIFFNESS, BoxGrasp
from bhgrasp.hand import Hand
from bhgrasp.ik import ik
from bhgrasp.objects import Box, FixedBox
from bhgrasp.resources import example_robot_data_urdf
from bhgrasp.sim import Simulator
from bhgrasp.sim.actuation import FullyActuated
from bhgrasp.sim.contact_law import SpringDamper
from bhgrasp.sim.scene import Scene

ALLEGRO_URDF = "allegro_hand_description/urdf/allegro_right_hand.urdf"
FINGERTIPS = {"index": "link_3.0_tip", "middle": "link_7.0_tip", "ring": "link_11.0_tip", "thumb": "link_15.0_tip"}
GRASPING = ("index", "middle", "thumb")
MOUNT = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])  # world <- base: base z -> x, base y -> z
BOX_SIZE = (0.05, 0.07, 0.05)  # [m] along the base frame's x (palm normal), y, z (finger direction)
BOX_CENTRE = (0.09, 0.02, 0.02)  # [m] base frame
TIP_RADIUS = 0.012  # [m] fingertip sphere of the URDF
TIP_SPACING = 0.05  # [m] index to middle fingertip along the box's 70 mm side


def allegro_hand() -> Hand:
    """The Allegro right hand of example-robot-data, fingers named, mounted as described in the module."""
    return Hand.from_urdf(example_robot_data_urdf(ALLEGRO_URDF), FINGERTIPS, base_placement=pin.SE3(MOUNT, np.zeros(3)))


def fingertip_targets(hand: Hand, offset: float = 0.0) -> dict[str, np.ndarray]:
    """World fingertip-centre targets [m] touching the box, moved ``offset`` [m] out along the face normals."""
    centre, half = np.array(BOX_CENTRE), 0.5 * np.array(BOX_SIZE)
    reach = half[2] + TIP_RADIUS + offset
    base = {
        "index": centre + np.array([0.0, 0.5 * TIP_SPACING, reach]),
        "middle": centre + np.array([0.0, -0.5 * TIP_SPACING, reach]),
        "thumb": centre + np.array([0.0, 0.0, -reach]),
    }
    return {finger: hand.base_placement.act(point) for finger, point in base.items()}


def allegro_box_grasp(
    mass: float = 0.2,
    opening: float = 0.02,
    closing: float = 0.008,
    dt: float = 1e-3,
    stiffness: float = STIFFNESS,
    damping: float = JOINT_DAMPING,
) -> BoxGrasp:
    """Build the scene (fully actuated, 0.05 N m s/rad joint damping, contacts of ``stiffness`` and mu 0.8).

    Args:
        mass: Box mass [kg].
        opening: Distance [m] the start configuration's fingertips stand off their faces.
        closing: Depth [m] into the box of the approach's target fingertip positions (so that fingers press).
        dt: Simulator step [s].
        stiffness: Contact stiffness [N/m] (damping 2e-3 s times it).
        damping: Viscous joint damping [N m s/rad].

    Returns:
        The :class:`~bhgrasp.experiments.box_grasp.BoxGrasp`; its ``q_close`` is the approach's target, and it asks
        for the joint damping to be cancelled (0.05 N m s/rad against distal-link inertias of ~5e-6 kg m^2: a
        computed-torque law that ignores it lags by tenths of a radian).
    """
    mass = as_positive(mass, "mass")
    opening, closing = as_positive(opening, "opening"), as_positive(closing, "closing")
    hand = allegro_hand()
    straight_ring = hand.finger_indices("ring")

    def solve(offset: float, guess: np.ndarray | None) -> np.ndarray:
        q = ik(hand, fingertip_targets(hand, offset), guess, tolerance=1e-7, restarts=10, rng=0).q
        q[straight_ring] = 0.0
        return q

    q_contact = solve(0.0, None)
    q_start, q_close = solve(opening, q_contact), solve(-closing, q_contact)
    centre = hand.base_placement.act(np.array(BOX_CENTRE))
    box = Box(size=BOX_SIZE, mass=mass, friction=FRICTION, pose=pin.SE3(MOUNT, centre))
    below = centre - [0.0, 0.0, 0.5 * BOX_SIZE[1] + 0.5 * PEDESTAL]  # the box's 70 mm side is vertical
    pedestal = FixedBox(size=(PEDESTAL,) * 3, pose=pin.SE3(np.eye(3), below), friction=FRICTION)
    law = SpringDamper(stiffness=stiffness, damping=2e-3 * stiffness, friction=FRICTION)
    drive = FullyActuated(hand, damping=as_positive(damping, "damping"))
    simulator = Simulator(Scene(hand, [box], environment=[pedestal]), dt=dt, contact=law, actuation=drive)
    state = simulator.initial_state(q_start)
    return BoxGrasp(simulator, state, hand, box, q_contact, q_start, q_close, GRASPING, cancel_damping=True)


__all__ = ["ALLEGRO_URDF", "BOX_CENTRE", "BOX_SIZE", "FINGERTIPS", "allegro_box_grasp", "allegro_hand"]
