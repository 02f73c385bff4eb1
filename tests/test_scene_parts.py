"""The scene's parts (bhgrasp.sim.scene_parts) against Pinocchio on the whole scene model, and their work space."""

from __future__ import annotations

import coal
import numpy as np
import pinocchio as pin
import pytest

import bhgrasp as bh
from bhgrasp.model.mount import mounted
from bhgrasp.model.objects import Box, Cylinder, Sphere
from bhgrasp.model.spring_mounted import SpringMounted
from bhgrasp.sim.scene import Scene
from bhgrasp.sim.scene_parts import SceneParts, object_parts

LOCAL_WORLD_ALIGNED = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED


def mixed_scene(hand: bh.Hand) -> Scene:
    """A hand with free objects of three shapes and a spring-mounted plate on a tilted axis."""
    plate = SpringMounted(body=Box(size=(0.04, 0.04, 0.01), mass=0.1), direction=[0.3, 0.0, 1.0], stiffness=200.0)
    objects = [
        Box(size=(0.04, 0.05, 0.06), mass=0.3, name="box"),
        Sphere(radius=0.03, mass=0.1, name="ball"),
        plate,
        Cylinder(radius=0.02, length=0.1, mass=0.2, name="can"),
    ]
    return Scene(hand, objects)


def random_state(scene: Scene, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    q = pin.neutral(scene.model)
    q[: scene.nq_hand] = rng.uniform(scene.hand.lower, scene.hand.upper)
    for i in range(len(scene.objects)):
        where = scene.object_q_slice(i)
        if where.stop - where.start == 7:
            q[where] = pin.SE3ToXYZQUAT(pin.SE3(pin.exp3(rng.normal(size=3)), rng.normal(size=3)))
        else:
            q[where] = rng.normal()
    return q, rng.normal(size=scene.nv)


@pytest.mark.parametrize("mount", [False, True])
def test_every_term_is_the_whole_models_to_the_bit(mount: bool) -> None:
    """M, h, each joint's placement, frame Jacobians and geometry placements equal Pinocchio's on the whole model."""
    hand = mounted(bh.BarrettHand()) if mount else bh.BarrettHand()
    scene = mixed_scene(hand)
    parts = SceneParts(scene.hand_model, scene.model)
    assert [part.model.nv for part in parts.parts] == [hand.nv, 6, 6, 1, 6]
    model, data = scene.model, scene.model.createData()
    lower = np.tril_indices(model.nv, -1)
    rng = np.random.default_rng(3)
    for _ in range(4):
        q, v = random_state(scene, rng)
        mass = pin.crba(model, data, q).copy()
        mass[lower] = mass.T[lower]
        np.testing.assert_array_equal(parts.mass_matrix(q), mass)
        np.testing.assert_array_equal(parts.nonlinear_effects(q, v), pin.nonLinearEffects(model, data, q, v))
        pin.computeJointJacobians(model, data, q)
        parts.compute_joint_jacobians(q)
        for joint in range(model.njoints):
            np.testing.assert_array_equal(parts.placement(joint).homogeneous, data.oMi[joint].homogeneous)
            if joint:
                placement = pin.SE3(np.eye(3), rng.normal(size=3))
                columns, jacobian = parts.point_jacobian(joint, placement)
                whole = np.zeros((6, model.nv))
                whole[:, columns] = jacobian
                np.testing.assert_array_equal(
                    whole, pin.getFrameJacobian(model, data, joint, placement, LOCAL_WORLD_ALIGNED)
                )
        truth, placed = pin.GeometryData(scene.geometry), pin.GeometryData(scene.geometry)
        pin.updateGeometryPlacements(model, data, scene.geometry, truth, q)
        parts.forward_kinematics(q)
        parts.update_geometry_placements(scene.geometry, placed)
        for g in range(scene.geometry.ngeoms):
            np.testing.assert_array_equal(placed.oMg[g].homogeneous, truth.oMg[g].homogeneous)


def test_the_energy_is_half_v_m_v_plus_the_potential() -> None:
    """Scene.energy from the parts equals Pinocchio's kinetic and potential energy of the whole model."""
    scene = mixed_scene(bh.BarrettHand())
    q, v = random_state(scene, np.random.default_rng(4))
    data = scene.model.createData()
    springs = 0.5 * 200.0 * float(q[scene.object_q_slice(2)][0]) ** 2
    whole = pin.computeKineticEnergy(scene.model, data, q, v) + pin.computePotentialEnergy(scene.model, data, q)
    assert scene.energy(q, v) == pytest.approx(whole + springs, rel=1e-13)


def test_a_scene_of_many_objects_simulates_without_a_data_of_the_whole_model() -> None:
    """64 boxes: the simulator's work space is the hand's and 64 six-velocity parts; no data of nv = 392 is made."""
    boxes = [
        Box(
            size=(0.03, 0.03, 0.03),
            mass=0.1,
            pose=pin.SE3(np.eye(3), np.array([0.5 + 0.05 * (i % 8), 0.05 * (i // 8), 0.1])),
        )
        for i in range(64)
    ]
    scene = Scene(bh.BarrettHand(), boxes)
    simulator = bh.Simulator(scene, engine="python", start_check="off")
    state = simulator.initial_state()
    state, _ = simulator.step(state, np.zeros(scene.hand.nv))
    assert scene._data is None and scene.nv == 8 + 64 * 6
    assert max(part.model.nv for part in simulator.engine.parts.parts) == 8
    velocity = state.scene_v[scene.object_v_slice(63)][:3]
    np.testing.assert_allclose(velocity, scene.hand.gravity * simulator.settings.dt, rtol=1e-12)  # free fall


def test_an_object_joint_on_the_hand_is_refused() -> None:
    hand_model = bh.BarrettHand().model
    model = pin.Model(hand_model)
    model.addJoint(1, pin.JointModelRX(), pin.SE3.Identity(), "on the hand")
    with pytest.raises(bh.ModelError, match="hangs from joint 1, not of its own object"):
        object_parts(model, hand_model.njoints)


def test_the_pairs_are_the_scenes_and_queried_as_pinocchio_would_with_the_scenes_settings() -> None:
    """No pair is Pinocchio's (a registered pair holds query state in every GeometryData); the one request every pair
    is queried with has the values Pinocchio's own per-pair request had once the scene set contacts on, 4 of them."""
    scene = mixed_scene(bh.BarrettHand())
    assert len(scene.pairs) > 0 and len(scene.geometry.collisionPairs) == 0
    assert len(scene.geometry_data.collisionRequests) == 0
    geometry = pin.GeometryModel()
    for name in ("a", "b"):
        geometry.addGeometryObject(pin.GeometryObject(name, 0, pin.SE3.Identity(), coal.Sphere(0.1)))
    geometry.addCollisionPair(pin.CollisionPair(0, 1))
    data = pin.GeometryData(geometry)
    pinocchios, patch = data.collisionRequests[0], data.contactPatchRequests[0]
    pinocchios.enable_contact, pinocchios.num_max_contacts = True, 4
    for field in ("enable_contact", "num_max_contacts", "security_margin", "break_distance"):
        assert getattr(scene.collision_request, field) == getattr(pinocchios, field), field
    assert scene.patch_request.max_num_patch == patch.max_num_patch
    assert scene.patch_request.getNumSamplesCurvedShapes() == patch.getNumSamplesCurvedShapes()
    assert scene.patch_request.getPatchTolerance() == patch.getPatchTolerance()
