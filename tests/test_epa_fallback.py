"""A collision query whose EPA stops short: both engines ask again at coal's default tolerance (bench's can grasp)."""

from __future__ import annotations

import coal
import numpy as np
import pinocchio as pin
import pytest

import bhgrasp as bh
from bhgrasp.data import ContactMemory
from bhgrasp.objects import Cylinder, FixedBox
from bhgrasp.sim import Simulator
from bhgrasp.sim.scene import Scene

# A finger's distal box edge in a can, from a grasp-benchmark run (coal 3.0.3), rotations orthonormalised
BOX_ROTATION = np.array([[0.0728770715309165, 0.07379636417901929, -0.9946069721649026],
                         [-0.690442286630716, -0.7159147786717495, -0.10370862313003859],
                         [-0.7197071496638241, 0.6942766929066089, -0.0012216421065062025]])  # fmt: skip
CAN_ROTATION = np.array([[0.9923034086329043, -0.1212883538862502, -0.024961579018223153],
                         [0.12083197109237012, 0.9924901646806847, -0.019050138425739802],
                         [0.027084681601449407, 0.015887360500440425, 0.9995068843179006]])  # fmt: skip
BOX_AT = np.array([-0.030661690579647398, 0.05676708132314192, 0.0337137587596117])
CAN_AT = np.array([-0.00481793657285365, -0.0011478277925822285, 0.049674489198309135])


def orthonormal(rotation: np.ndarray) -> np.ndarray:
    u, _, vt = np.linalg.svd(rotation)
    return u @ vt


def test_an_unconverged_epa_is_asked_again_and_both_engines_find_the_distance_depth() -> None:
    box_pose = coal.Transform3s(orthonormal(BOX_ROTATION), BOX_AT)
    can_pose = coal.Transform3s(orthonormal(CAN_ROTATION), CAN_AT)
    box, can = coal.Box(0.0605, 0.0208, 0.0237), coal.Cylinder(0.033, 0.1)
    tight = coal.CollisionRequest()
    tight.num_max_contacts, tight.gjk_tolerance, tight.epa_tolerance = 4, 1e-10, 1e-10  # the engines' first query
    result = coal.CollisionResult()
    assert coal.collide(box, box_pose, can, can_pose, tight, result)
    assert result.getContact(0).penetration_depth < -1e300  # coal's EPA stopped short: -DBL_MAX, the bug handled here
    depth = -coal.distance(box, box_pose, can, can_pose, coal.DistanceRequest(), coal.DistanceResult())  # 2nd method
    assert depth == pytest.approx(5.31e-4, rel=1e-3)
    scene = Scene(
        bh.BarrettHand(base_placement=pin.SE3(np.eye(3), np.array([0.0, 0.0, 1.0]))),  # far away
        [Cylinder(radius=0.033, length=0.1, mass=0.35, pose=pin.SE3(orthonormal(CAN_ROTATION), CAN_AT))],
        environment=[FixedBox(size=(0.0605, 0.0208, 0.0237), pose=pin.SE3(orthonormal(BOX_ROTATION), BOX_AT))],
    )
    for engine in ("python", "compiled"):
        simulator = Simulator(scene, engine=engine)
        q = simulator.initial_state().scene_q
        contacts = simulator.engine.detect(q, ContactMemory.empty())
        assert len(contacts.depth) == 1, engine
        assert contacts.depth[0] == pytest.approx(depth, rel=2e-3), engine  # EPA at 1e-6 m on 0.53 mm
