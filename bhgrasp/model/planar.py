"""The thesis' planar fingers (chapters 3-4) as Pinocchio models with the :class:`~bhgrasp.model.hand.Hand` interface.

An n-link serial chain in the x-y plane: every joint turns about z, angles are measured from +x (joint i
relative to link i-1), gravity points along -y.  As in the thesis' Lagrangian ((2.11)-(2.13): kinetic energy
0.5 m v^2 of each link's end), each link is a point mass at its far end unless ``rods=True`` (uniform slender
rods, inertia m l^2 / 12 about the centre).  The fingertip frame ``tip`` sits at the end of the last link.
"""

from __future__ import annotations

from collections.abc import Sequence

import coal
import numpy as np
import pinocchio as pin

from bhgrasp._validation import as_positive, as_vector
from bhgrasp.errors import InputError
from bhgrasp.model.hand import Hand

PLANAR_GRAVITY = (0.0, -9.81, 0.0)  # [m/s^2]: the thesis' potential energy is m g y


def planar_finger(
    lengths: Sequence[float],
    masses: Sequence[float],
    *,
    rods: bool = False,
    gravity: Sequence[float] = PLANAR_GRAVITY,
    joint_range: float = np.pi,
    tip_radius: float | None = None,
    name: str = "planar finger",
) -> Hand:
    """An n-link planar finger as a :class:`Hand` with one finger, ``"tip"``.

    Args:
        lengths: Link lengths [m], base outward.
        masses: Link masses [kg], same length.
        rods: Uniform rods instead of point masses at the link ends.
        gravity: Gravity in the base frame [m/s^2].
        joint_range: Joint limits are [-joint_range, joint_range] [rad]; speed and torque limits are infinite
            (the thesis' planar fingers are idealised).
        tip_radius: Radius [m] of a collision sphere centred on the fingertip (on the last link's frame), so that
            the finger can touch objects in a :class:`~bhgrasp.sim.scene.Scene`; ``None``: no collision geometry.
        name: Display name.
    """
    lengths = as_vector(lengths, "lengths")
    masses = as_vector(masses, "masses", lengths.size)
    for i, (length, mass) in enumerate(zip(lengths, masses)):
        as_positive(length, f"lengths[{i}]")
        as_positive(mass, f"masses[{i}]")
    joint_range = as_positive(joint_range, "joint_range")
    if lengths.size == 0:
        raise InputError("`lengths` must hold at least one link length")

    model = pin.Model()
    model.name = name
    parent, offset = 0, 0.0
    for i, (length, mass) in enumerate(zip(lengths, masses), start=1):
        placement = pin.SE3(np.eye(3), np.array([offset, 0.0, 0.0]))
        parent = model.addJoint(
            parent,
            pin.JointModelRZ(),
            placement,
            f"joint{i}",
            max_effort=np.array([np.inf]),
            max_velocity=np.array([np.inf]),
            min_config=np.array([-joint_range]),
            max_config=np.array([joint_range]),
        )
        if rods:
            inertia = pin.Inertia(
                mass, np.array([length / 2, 0.0, 0.0]), np.diag([0.0, 1.0, 1.0]) * mass * length**2 / 12
            )
        else:
            inertia = pin.Inertia(mass, np.array([length, 0.0, 0.0]), np.zeros((3, 3)))
        model.appendBodyToJoint(parent, inertia, pin.SE3.Identity())
        model.addFrame(pin.Frame(f"link{i}", parent, pin.SE3.Identity(), pin.FrameType.BODY))
        offset = float(length)
    tip = pin.SE3(np.eye(3), np.array([offset, 0.0, 0.0]))
    model.addFrame(pin.Frame("tip", parent, tip, pin.FrameType.OP_FRAME))
    geometry = None
    if tip_radius is not None:
        geometry = pin.GeometryModel()
        link = model.getFrameId(f"link{lengths.size}")
        sphere = coal.Sphere(as_positive(tip_radius, "tip_radius"))
        geometry.addGeometryObject(pin.GeometryObject("tip_sphere", parent, link, tip, sphere))
    return Hand(model, {"tip": "tip"}, name=name, gravity=gravity, collision_geometry=geometry)


def thesis_two_link_finger() -> Hand:
    """Chapter 3's planar finger: "the same mass and link dimensions of the Barrett finger" (thesis 3.5.2).

    That is the two moving links of chapter 2: l = (0.05, 0.05) m, m = (0.0579, 0.0342) kg, point masses.
    """
    return planar_finger((0.05, 0.05), (0.0579, 0.0342), name="thesis ch.3 planar finger")


def thesis_impedance_finger(tip_radius: float = 0.02) -> Hand:
    """Chapter 4's planar two-link finger for impedance control (4.5.4): m = (1, 1) kg, l = (0.5, 0.5) m.

    Its fingertip carries a collision sphere of ``tip_radius`` [m] (our choice; the thesis' contact is a point).
    """
    return planar_finger((0.5, 0.5), (1.0, 1.0), tip_radius=tip_radius, name="thesis ch.4 planar finger")


def thesis_one_link_finger(mass: float = 1.0, tip_radius: float = 0.01) -> Hand:
    """Chapter 4's one-link finger (4.4): l = 0.2 m.  The thesis gives no link mass: 1 kg by default (our choice).

    Its fingertip carries a collision sphere of ``tip_radius`` [m] (our choice).
    """
    return planar_finger((0.2,), (mass,), tip_radius=tip_radius, name="thesis ch.4 one-link finger")
