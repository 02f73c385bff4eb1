"""Scenes several test modules share: the hand parked far away, two boxes meeting off centre, a box on an incline, a
prism tipping onto the decomposed banana; the Barrett drive under its Python rules."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import trimesh

import bhgrasp as bh
from bhgrasp.model.household_objects import household
from bhgrasp.model.mesh_object import Mesh
from bhgrasp.model.objects import Box, Plane, table
from bhgrasp.sim import Simulator
from bhgrasp.sim.actuation import BarrettActuation
from bhgrasp.sim.contact_law import SpringDamper
from bhgrasp.sim.scene import Scene

G = 9.81  # [m/s^2]
FAR = pin.SE3(np.eye(3), np.array([5.0, 0.0, 0.3]))  # the hand's base, 5 m from the objects near the origin


def far_hand(gravity=(0.0, 0.0, 0.0)) -> bh.Hand:
    """The BH8-280 placed where no object reaches it."""
    return bh.BarrettHand(base_placement=FAR, gravity=gravity)


def off_centre_boxes() -> list[Box]:
    """A 0.3 kg and a 0.5 kg box flying at each other at 0.5 m/s, meeting off centre (they spin apart)."""
    first = Box(
        size=(0.05, 0.04, 0.03),
        mass=0.3,
        friction=0.8,
        pose=pin.SE3(np.eye(3), np.zeros(3)),
        velocity=[0.5, 0.0, 0.0, 0.0, 0.0, 0.0],
        name="first",
    )
    second = Box(
        size=(0.05, 0.04, 0.03),
        mass=0.5,
        friction=0.8,
        pose=pin.SE3(pin.rpy.rpyToMatrix(0.2, 0.1, 0.3), np.array([0.1, 0.02, 0.01])),
        velocity=[-0.5, 0.0, 0.0, 0.0, 0.0, 0.0],
        name="second",
    )
    return [first, second]


def incline(mu: float = 0.3, theta: float = np.radians(30.0)) -> tuple[Box, Plane, SpringDamper]:
    """A 0.2 kg box resting on a ``theta`` incline (friction ``mu``) at its static depth, and the contact law."""
    normal = np.array([np.sin(theta), 0.0, np.cos(theta)])
    rest = np.array([1.0, 0.0, 0.0]) + normal * (0.025 - 0.2 * G * np.cos(theta) / 1e4)
    box = Box(size=(0.06, 0.05, 0.05), mass=0.2, friction=mu, pose=pin.SE3(pin.rpy.rpyToMatrix(0, theta, 0), rest))
    plane = Plane(normal=normal, offset=float(normal[0]), friction=mu, name="incline")
    return box, plane, SpringDamper(stiffness=1e4, damping=20.0, friction=mu)


class PythonBarrettRules(BarrettActuation):
    """The BH8-280's drive stepped by its Python rules on any engine: a subclass of BarrettActuation runs its hooks.

    (The compiled Simulator runs ``BarrettActuation`` itself in C++, ``src/barrett.cpp``; this is its independent
    truth.)
    """


def prism_onto_banana() -> Simulator:
    """A heptagonal prism (one hull) tipping onto the banana (four convex pieces) on a table, the hand far away."""
    prism = Mesh(
        trimesh.creation.cylinder(radius=0.02, height=0.06, sections=7),
        mass=0.2,
        pose=pin.SE3(pin.rpy.rpyToMatrix(0.4, 0.0, 0.0), np.array([0.0, -0.03, 0.05])),
        velocity=[0.0, 0.3, 0.0, 0.0, 0.0, 0.0],
        name="prism",
    )
    banana = household("banana", position=(0.0, 0.02, 0.0))
    return Simulator(Scene(far_hand((0.0, 0.0, -G)), [prism, banana], [table()]))
