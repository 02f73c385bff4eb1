"""The generic-hand grasp scene: the Allegro hand (example-robot-data, 16 DOF) grasps a box on a pedestal.

The demonstration that the grasp pipeline takes any :class:`~bhgrasp.model.hand.Hand`: the scene is a call of
:func:`~bhgrasp.scenarios.object_grasp.object_grasp` (pedestal, contact law, drive) whose grasp the opposition search
plans (:mod:`bhgrasp.grasp.opposition`: pads placed by IK from sampled reach, the same checks as the BH8-280's
synthesis); what is chosen here is only the mounting, where the box sits and which fingers grasp.  The hand is
mounted with its fingers pointing along world x and its palm facing world y (base frame: fingers along z, palm
normal x; the world gets base y as "up").  The thumb opposes the index and middle fingers across the box; the ring
finger stays straight (at rest, zero) and out of the way.

The box (0.05 x 0.07 x 0.05 m in the hand's base axes, its 70 mm side vertical) rests on a 20 mm pedestal; its centre
sits at (0.09, 0.02, 0.02) m in the base frame, in front of the palm where the thumb and the two fingers meet.  The
search grasps across the box's faces (its horizontal axes, ``directions=0``: 1.6 s instead of 7 s over 8 more axes,
which find the same best grasp).
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from bhgrasp._validation import as_positive
from bhgrasp.model.hand import Hand
from bhgrasp.model.objects import Box
from bhgrasp.model.resources import example_robot_data_urdf
from bhgrasp.scenarios.box_grasp import JOINT_DAMPING, STIFFNESS, BoxGrasp
from bhgrasp.scenarios.demo_result import MU_ASSUMED
from bhgrasp.scenarios.object_grasp import object_grasp

ALLEGRO_URDF = "allegro_hand_description/urdf/allegro_right_hand.urdf"
FINGERTIPS = {"index": "link_3.0_tip", "middle": "link_7.0_tip", "ring": "link_11.0_tip", "thumb": "link_15.0_tip"}
GRASPING = ("index", "middle", "thumb")
MOUNT = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])  # world <- base: base z -> x, base y -> z
BOX_SIZE = (0.05, 0.07, 0.05)  # [m] along the base frame's x (palm normal), y, z (finger direction)
BOX_CENTRE = (0.09, 0.02, 0.02)  # [m] base frame


def allegro_hand() -> Hand:
    """The Allegro right hand of example-robot-data, fingers named, mounted as described in the module."""
    return Hand.from_urdf(example_robot_data_urdf(ALLEGRO_URDF), FINGERTIPS, base_placement=pin.SE3(MOUNT, np.zeros(3)))


def allegro_box_grasp(
    mass: float = 0.2,
    opening: float = 0.02,
    closing: float = 0.008,
    dt: float = 1e-3,
    stiffness: float = STIFFNESS,
    damping: float = JOINT_DAMPING,
) -> BoxGrasp:
    """Build the scene and plan the grasp of thumb, index and middle finger (about 2 s).

    Fully actuated, 0.05 N m s/rad joint damping, contacts of ``stiffness`` and mu 0.8; the grasp from
    :func:`~bhgrasp.grasp.opposition.opposed_grasps`.

    Args:
        mass: Box mass [kg].
        opening: Distance [m] the start configuration's pads stand off their faces.
        closing: Depth [m] into the box of the approach's target pad positions (so that the fingers press).
        dt: Simulator step [s].
        stiffness: Contact stiffness [N/m] (damping 2e-3 s times it).
        damping: Viscous joint damping [N m s/rad].

    Returns:
        The :class:`~bhgrasp.scenarios.box_grasp.BoxGrasp` of the best candidate; its ``q_close`` is the
        approach's target, and it asks for the joint damping to be cancelled (0.05 N m s/rad against distal-link
        inertias of ~5e-6 kg m^2: a computed-torque law that ignores it lags by tenths of a radian).
    """
    hand = allegro_hand()
    centre = hand.base_placement.act(np.array(BOX_CENTRE))
    box = Box(size=BOX_SIZE, mass=as_positive(mass, "mass"), pose=pin.SE3(MOUNT, centre))
    setup = object_grasp(
        box,
        mu=MU_ASSUMED,
        dt=dt,
        hand=hand,
        stiffness=stiffness,
        damping=damping,
        fingers=GRASPING,
        directions=0,
        standoff=as_positive(opening, "opening"),
        closing=as_positive(closing, "closing"),
    )
    c = setup.candidate
    return BoxGrasp(
        setup.simulator,
        setup.state,
        hand,
        setup.item,
        c.q_contact,
        c.q_pregrasp,
        c.q_close,
        c.fingers,
        cancel_damping=True,
    )


__all__ = ["ALLEGRO_URDF", "BOX_CENTRE", "BOX_SIZE", "FINGERTIPS", "GRASPING", "allegro_box_grasp", "allegro_hand"]
