"""A collision query whose EPA stops short: both engines ask again at coal's default tolerance (bench's can grasp)."""

from __future__ import annotations

import coal
import numpy as np
import pinocchio as pin
import pytest

import bhgrasp as bh
from bhgrasp.data import ContactMemory
from bhgrasp.model.objects import Cylinder, FixedBox
from bhgrasp.sim import Simulator
from bhgrasp.sim.scene import Scene

# A finger's distal box edge in a can, from a grasp-benchmark run (coal 3.0.3), rotations orthonormalised
BOX_ROTATION = np.array(
    [
        [0.0728770715309165, 0.07379636417901929, -0.9946069721649026],
        [-0.690442286630716, -0.7159147786717495, -0.10370862313003859],
        [-0.7197071496638241, 0.6942766929066089, -0.0012216421065062025],
    ]
)
CAN_ROTATION = np.array(
    [
        [0.9923034086329043, -0.1212883538862502, -0.024961579018223153],
        [0.12083197109237012, 0.9924901646806847, -0.019050138425739802],
        [0.027084681601449407, 0.015887360500440425, 0.9995068843179006],
    ]
)
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


# A can standing on its stand, rim first, from a grasp-benchmark run (coal 3.0.3): the stand is a 66 x 66 x 200 mm box
# whose top is at z = 0, the can 33 mm x 100 mm, tilted 0.134 rad about x
STAND = (0.066, 0.066, 0.2)
STAND_AT = np.array([0.0, 0.0, -0.1])
RIM_ROTATION = np.array(
    [
        [0.9999999807178863, -0.00015371562908713995, -0.0001222118340072409],
        [0.00013606344818242302, 0.991085563025875, -0.13322683006220035],
        [0.00014160143030978776, 0.13322681086474195, 0.9910855648307291],
    ]
)
RIM_AT = np.array([-7.814041918834454e-06, -0.007025738824650085, 0.053912292354647236])


def test_a_depth_no_contact_has_is_asked_again_in_both_engines() -> None:
    """At 1e-10 coal's EPA reads the rim's overlap as 307 mm, ten times the can's size (the benchmark's can then
    spun up to 749 rad/s in one step); at coal's default tolerance it converges to what coal.distance gives."""
    stand_pose = coal.Transform3s(np.eye(3), STAND_AT)
    can_pose = coal.Transform3s(orthonormal(RIM_ROTATION), RIM_AT)
    stand, can = coal.Box(*STAND), coal.Cylinder(0.033, 0.1)
    tight = coal.CollisionRequest()
    tight.num_max_contacts, tight.gjk_tolerance, tight.epa_tolerance = 4, 1e-10, 1e-10  # the engines' first query
    result = coal.CollisionResult()
    assert coal.collide(stand, stand_pose, can, can_pose, tight, result)
    assert result.getContact(0).penetration_depth == pytest.approx(-0.307, abs=1e-3)  # the bug handled here
    depth = -coal.distance(stand, stand_pose, can, can_pose, coal.DistanceRequest(), coal.DistanceResult())
    lowest = max(
        -(orthonormal(RIM_ROTATION) @ [0.033 * np.cos(a), 0.033 * np.sin(a), -0.05] + RIM_AT)[2]
        for a in np.linspace(0.0, 2 * np.pi, 36000)
    )  # the rim's deepest point under the top [m]
    assert 0.0 < depth <= lowest < 4e-5  # along the normal at most the vertical overlap: tens of micrometres
    scene = Scene(
        bh.BarrettHand(base_placement=pin.SE3(np.eye(3), np.array([0.0, 0.0, 1.0]))),  # far away
        [Cylinder(radius=0.033, length=0.1, mass=0.35, pose=pin.SE3(orthonormal(RIM_ROTATION), RIM_AT))],
        environment=[FixedBox(size=STAND, pose=pin.SE3(np.eye(3), STAND_AT))],
    )
    for engine in ("python", "compiled"):
        simulator = Simulator(scene, engine=engine)
        contacts = simulator.engine.detect(simulator.initial_state().scene_q, ContactMemory.empty())
        assert len(contacts.depth) >= 1 and np.all(contacts.depth <= lowest + 1e-6), engine
