"""Grasp analysis against independent truths: wrenches summed by hand, finite differences of points carried by
links, rigid-body velocities from Pinocchio, classic force-closure grasps, LP membership in the wrench space."""

from __future__ import annotations

import copy
import itertools
import math
import re
import subprocess
import sys
from collections.abc import Callable
from typing import Any

import numpy as np
import pinocchio as pin
import pytest
from scipy.optimize import linprog
from scipy.spatial.transform import Rotation

import bhgrasp as bh
from bhgrasp.errors import InputError
from bhgrasp.grasp import (
    GraspQuality,
    contact_frames,
    default_torque_scale,
    ferrari_canny,
    force_closure_margin,
    friction_cone_edges,
    friction_pyramid,
    grasp_constraint_residual,
    grasp_map,
    grasp_quality,
    grasp_wrench_space_volume,
    hand_jacobian,
    in_friction_cone,
    is_force_closure,
    primitive_wrenches,
)

SEEDS = range(4)
LINKS = ("F1_proximal_link", "F1_distal_link", "F2_distal_link", "F3_proximal_link", "F3_distal_link", "F3_tip")


def random_contacts(rng: np.random.Generator, count: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    points = rng.normal(scale=0.05, size=(count, 3))
    normals = rng.normal(size=(count, 3)) * rng.uniform(0.5, 2.0, size=(count, 1))  # not unit on purpose
    return points, normals, rng.normal(scale=0.05, size=3)


# --- classic grasps (object centre at the origin, normals into the object) ------------------------------------


def sphere_equator(count: int, radius: float = 0.05) -> tuple[np.ndarray, np.ndarray]:
    angles = 2.0 * np.pi * np.arange(count) / count
    outward = np.column_stack([np.cos(angles), np.sin(angles), np.zeros(count)])
    return radius * outward, -outward


def tetrahedron_faces(size: float = 0.04) -> tuple[np.ndarray, np.ndarray]:
    vertices = np.array([[1.0, 1.0, 1.0], [1.0, -1.0, -1.0], [-1.0, 1.0, -1.0], [-1.0, -1.0, 1.0]])
    # the face opposite vertex k has its centre at -v_k / 3 and its inward normal along +v_k
    return -size * vertices / 3.0, vertices / math.sqrt(3.0)


def cube_faces_offset(half: float = 0.03) -> tuple[np.ndarray, np.ndarray]:
    """Two contacts per face of a cube, offset along another axis so that normal forces alone make torques."""
    points, normals = [], []
    for axis in range(3):
        other = (axis + 1) % 3
        for sign in (1.0, -1.0):
            for offset in (0.5 * half, -0.5 * half):
                point = np.zeros(3)
                point[axis], point[other] = sign * half, offset
                normal = np.zeros(3)
                normal[axis] = -sign
                points.append(point)
                normals.append(normal)
    return np.array(points), np.array(normals)


def antipodal() -> tuple[np.ndarray, np.ndarray]:
    return np.array([[0.03, 0.0, 0.0], [-0.03, 0.0, 0.0]]), np.array([[-1.0, 0.0, 0.0], [1.0, 0.0, 0.0]])


def one_side() -> tuple[np.ndarray, np.ndarray]:
    points = np.array([[0.02, 0.0, 0.0], [-0.01, 0.02, 0.0], [-0.01, -0.02, 0.0], [0.0, 0.0, 0.0]])
    return points, np.tile([0.0, 0.0, 1.0], (4, 1))


CLASSICS = [
    ("3 on a sphere, mu 0.3", *sphere_equator(3), 0.3, True),
    ("3 on a sphere, mu 1.0", *sphere_equator(3), 1.0, True),
    ("3 on a sphere, frictionless", *sphere_equator(3), 0.0, False),
    ("2 antipodal, frictionless", *antipodal(), 0.0, False),
    ("2 antipodal, mu 0.5", *antipodal(), 0.5, False),
    ("2 antipodal, mu 3.0", *antipodal(), 3.0, False),
    ("4 on tetrahedron faces, mu 0.5", *tetrahedron_faces(), 0.5, True),
    ("4 on tetrahedron faces, frictionless", *tetrahedron_faces(), 0.0, False),
    ("12 offset on cube faces, frictionless", *cube_faces_offset(), 0.0, True),
    ("4 on one side, mu 0.8", *one_side(), 0.8, False),
]
CLOSURE = [case for case in CLASSICS if case[4]]


def ids(cases: list[tuple[Any, ...]]) -> list[str]:
    return [case[0] for case in cases]


# --- contact frames and the grasp map ---------------------------------------------------------------------------


def test_contact_frames_are_right_handed_orthonormal_with_the_normal_last() -> None:
    rng = np.random.default_rng(0)
    normals = np.vstack([rng.normal(size=(50, 3)), np.eye(3), -np.eye(3), [[0.9, 0.43, 0.0], [0.91, 0.41, 0.0]]])
    normals *= rng.uniform(0.1, 10.0, size=(len(normals), 1))
    frames = contact_frames(normals)
    assert frames.shape == (len(normals), 3, 3)
    np.testing.assert_allclose(frames.transpose(0, 2, 1) @ frames, np.broadcast_to(np.eye(3), frames.shape), atol=1e-14)
    np.testing.assert_allclose(np.linalg.det(frames), 1.0, atol=1e-14)
    np.testing.assert_allclose(frames[:, :, 2], normals / np.linalg.norm(normals, axis=1, keepdims=True), atol=1e-15)
    np.testing.assert_array_equal(contact_frames([[0.0, 0.0, 2.0]])[0], np.eye(3))  # +z normal: world frame
    np.testing.assert_array_equal(contact_frames(normals), frames)  # deterministic
    # continuous away from the switch |n_x| = 0.9: a small tilt of the normal moves the frame by as little
    for normal in rng.normal(size=(20, 3)):
        normal /= np.linalg.norm(normal)
        if abs(abs(normal[0]) - 0.9) < 0.05:
            continue
        tilted = normal + 1e-7 * rng.normal(size=3)
        change = np.abs(contact_frames([tilted])[0] - contact_frames([normal])[0]).max()
        assert change < 1e-5


@pytest.mark.parametrize("seed", SEEDS)
def test_grasp_map_gives_the_wrench_summed_contact_by_contact(seed: int) -> None:
    rng = np.random.default_rng(seed)
    points, normals, reference = random_contacts(rng, 5)
    forces = rng.normal(size=(5, 3))
    frames = contact_frames(normals)
    total_force, total_torque = np.zeros(3), np.zeros(3)
    for point, frame, force in zip(points, frames, forces):
        world = frame[:, 0] * force[0] + frame[:, 1] * force[1] + frame[:, 2] * force[2]
        total_force += world
        total_torque += np.cross(point - reference, world)
    grasp = grasp_map(points, normals, reference)
    assert grasp.shape == (6, 15)
    np.testing.assert_allclose(grasp @ forces.ravel(), np.r_[total_force, total_torque], atol=1e-14)


@pytest.mark.parametrize("seed", SEEDS)
def test_the_wrench_of_the_same_physical_forces_moves_with_a_rigid_transform(seed: int) -> None:
    """Contact frames need not rotate with the normals (t1 is built from a world axis); the physical statement is:
    the same world forces, moved by (R, t) and re-expressed in the new contact frames, give (R force, R torque)."""
    rng = np.random.default_rng(seed)
    points, normals, reference = random_contacts(rng, 4)
    rotation, shift = Rotation.random(random_state=seed).as_matrix(), rng.normal(size=3)
    forces = rng.normal(size=(4, 3))
    world_forces = np.einsum("nij,nj->ni", contact_frames(normals), forces)
    new_normals = normals @ rotation.T
    new_forces = np.einsum("nji,nj->ni", contact_frames(new_normals), world_forces @ rotation.T)
    moved = grasp_map(points @ rotation.T + shift, new_normals, rotation @ reference + shift) @ new_forces.ravel()
    original = grasp_map(points, normals, reference) @ forces.ravel()
    np.testing.assert_allclose(moved, np.r_[rotation @ original[:3], rotation @ original[3:]], atol=1e-13)


def test_primitive_wrenches_are_unit_edge_forces_with_scaled_torques() -> None:
    points, normals = tetrahedron_faces()
    reference, mu, facets, scale = np.array([0.001, -0.002, 0.003]), 0.4, 5, 0.02
    wrenches = primitive_wrenches(grasp_map(points, normals, reference), mu, facets, scale)
    frames = contact_frames(normals)
    for i in range(4):
        for j in range(facets):
            angle = 2.0 * np.pi * j / facets
            local = np.array([mu * np.cos(angle), mu * np.sin(angle), 1.0]) / math.hypot(1.0, mu)
            world = frames[i] @ local
            expected = np.r_[world, np.cross(points[i] - reference, world) / scale]
            np.testing.assert_allclose(wrenches[:, i * facets + j], expected, atol=1e-15)


def test_default_torque_scale_is_the_largest_reference_to_contact_distance() -> None:
    rng = np.random.default_rng(5)
    points, normals, reference = random_contacts(rng, 6)
    expected = np.linalg.norm(points - reference, axis=1).max()
    assert default_torque_scale(grasp_map(points, normals, reference)) == pytest.approx(expected, rel=1e-14)
    assert grasp_quality(points, normals, reference, 0.5).torque_scale == pytest.approx(expected, rel=1e-14)
    assert default_torque_scale(grasp_map(points[:1], normals[:1], points[0])) == 1.0  # no lever at all


# --- hand Jacobian and the grasp constraint ---------------------------------------------------------------------


@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize("placed", [False, True], ids=["base at origin", "base placed"])
def test_hand_jacobian_equals_finite_differences_of_points_carried_by_links(
    barrett: bh.Hand, seed: int, placed: bool
) -> None:
    rng = np.random.default_rng(seed)
    hand = copy.deepcopy(barrett)
    if placed:
        hand.base_placement = pin.SE3(Rotation.random(random_state=seed).as_matrix(), rng.normal(size=3))
    q, v = hand.random_configuration(rng), rng.normal(size=hand.nv)
    links = list(rng.choice(LINKS, size=5))
    links[0] = "palm"  # a contact on the fixed palm: zero rows
    local = rng.normal(scale=0.02, size=(5, 3))  # each point in its link frame, carried by the link
    points = np.array([hand.frame_placement(q, link).act(p) for link, p in zip(links, local)])
    normals = rng.normal(size=(5, 3))
    frames = contact_frames(normals)  # held fixed while the configuration moves

    def contact_coordinates(configuration: np.ndarray) -> np.ndarray:
        world = [hand.frame_placement(configuration, link).act(p) for link, p in zip(links, local)]
        return np.concatenate([frame.T @ point for frame, point in zip(frames, world)])

    h = 1e-6
    numeric = (contact_coordinates(q + h * v) - contact_coordinates(q - h * v)) / (2.0 * h)
    jacobian = hand_jacobian(hand, q, points, links, normals)
    assert jacobian.shape == (15, hand.nv)
    np.testing.assert_allclose(jacobian @ v, numeric, atol=1e-8)
    np.testing.assert_array_equal(jacobian[:3], 0.0)
    assert np.abs(numeric[3:]).max() > 1e-2  # not vacuous


def test_hand_jacobian_at_a_fingertip_is_the_fingertip_jacobian_in_contact_coordinates(barrett: bh.Hand) -> None:
    q = barrett.random_configuration(7)
    normals = np.random.default_rng(7).normal(size=(3, 3))
    frames = contact_frames(normals)
    tips = [barrett.fingertip_frames[finger] for finger in barrett.fingers]
    jacobian = hand_jacobian(barrett, q, barrett.fingertip_positions(q), tips, normals)
    for i, finger in enumerate(barrett.fingers):
        np.testing.assert_allclose(
            frames[i] @ jacobian[3 * i : 3 * i + 3], barrett.fingertip_jacobian(q, finger), atol=1e-14
        )


@pytest.mark.parametrize("seed", SEEDS)
def test_grasp_constraint_holds_for_an_object_carried_by_a_link(barrett: bh.Hand, seed: int) -> None:
    """An object welded to F2's distal link: its twist is the link's spatial velocity (Pinocchio's forward
    kinematics with velocities, not Jacobians), moved to the reference point; fixed contacts satisfy (5.19)."""
    rng = np.random.default_rng(seed)
    q, v = barrett.random_configuration(rng), rng.normal(size=barrett.nv)
    link = "F2_distal_link"
    model, data = barrett.model, barrett.model.createData()
    pin.forwardKinematics(model, data, q, v)
    pin.updateFramePlacements(model, data)
    frame = model.getFrameId(link)
    velocity = pin.getFrameVelocity(model, data, frame, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)
    origin = data.oMf[frame].translation
    reference = origin + rng.normal(scale=0.03, size=3)
    twist = np.r_[velocity.linear + np.cross(velocity.angular, reference - origin), velocity.angular]

    points = origin + rng.normal(scale=0.02, size=(3, 3))
    normals = rng.normal(size=(3, 3))
    grasp = grasp_map(points, normals, reference)
    residual = grasp_constraint_residual(grasp, hand_jacobian(barrett, q, points, link, normals), twist, v)
    assert residual.shape == (9,)
    np.testing.assert_allclose(residual, 0.0, atol=1e-10)
    # the same contacts on another finger's link slip: the check is not vacuous
    slipping = hand_jacobian(barrett, q, points, "F1_distal_link", normals)
    assert np.abs(grasp_constraint_residual(grasp, slipping, twist, v)).max() > 1e-3


# --- friction cones ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize(("mu", "facets"), [(0.0, 3), (0.3, 3), (0.5, 4), (1.0, 8), (2.5, 7), (0.2, 16)])
def test_friction_pyramid_and_cone_edges_describe_the_same_pyramid(mu: float, facets: int) -> None:
    edges = friction_cone_edges(mu, facets)
    rows, offsets = friction_pyramid(mu, facets)
    assert edges.shape == (facets, 3) and rows.shape == (facets, 3) and offsets.shape == (facets,)
    np.testing.assert_array_equal(offsets, 0.0)
    np.testing.assert_allclose(np.linalg.norm(edges, axis=1), 1.0, atol=1e-15)
    np.testing.assert_allclose(np.linalg.norm(rows, axis=1), 1.0, atol=1e-15)
    distances = edges @ rows.T  # (edge, facet)
    assert distances.max() <= 1e-12
    if mu > 0.0:
        # edge j is the intersection of facets j - 1 and j: equality on exactly those two
        for j in range(facets):
            assert sorted(np.flatnonzero(np.abs(distances[j]) <= 1e-12)) == sorted({(j - 1) % facets, j})
        # every point of the half-space description is a non-negative combination of the edges (and back)
        rng = np.random.default_rng(facets)
        inside = rng.uniform(size=(100, facets)) @ edges
        assert (inside @ rows.T).max() <= 1e-12
        sample = rng.normal(size=(2000, 3))
        in_pyramid = sample[(sample @ rows.T).max(axis=1) <= 0.0]
        for f in in_pyramid[:50]:
            result = linprog(np.zeros(facets), A_eq=edges.T, b_eq=f, bounds=[(0.0, None)] * facets, method="highs")
            assert result.status == 0


@pytest.mark.parametrize(("mu", "facets"), [(0.3, 3), (0.5, 4), (1.0, 8), (2.5, 7)])
def test_inscribed_pyramid_lies_inside_the_exact_cone(mu: float, facets: int) -> None:
    edges = friction_cone_edges(mu, facets)
    assert all(in_friction_cone(edge, mu, margin=-1e-15) for edge in edges)  # on the cone (to rounding)
    assert not any(in_friction_cone(edge, mu, margin=1e-9) for edge in edges)  # ... not inside it
    midpoints = (edges + np.roll(edges, -1, axis=0)) / 2.0
    assert all(in_friction_cone(point, mu, margin=1e-6) for point in midpoints)  # facet centres strictly inside
    # the exact cone at the facet mid-angles lies outside the pyramid: inscribed, not circumscribed
    rows, _ = friction_pyramid(mu, facets)
    angles = 2.0 * np.pi * (np.arange(facets) + 0.5) / facets
    on_cone = np.column_stack([mu * np.cos(angles), mu * np.sin(angles), np.ones(facets)])
    assert np.all(np.diag(on_cone @ rows.T) > 0.0)


def test_in_friction_cone_on_the_boundary_inside_and_outside() -> None:
    assert in_friction_cone([3.0, 4.0, 10.0], 0.5)  # |f_t| = 5 = mu f_n exactly: the boundary is in
    assert not in_friction_cone([3.0, 4.0, 10.0], 0.5, margin=1e-9)
    assert in_friction_cone([3.0, 4.0, 10.0], 0.5 - 1e-9, margin=-1e-6)  # a negative margin is a tolerance
    assert in_friction_cone([0.1, -0.2, 10.0], 0.5, margin=4.0)
    assert not in_friction_cone([3.0, 4.0001, 10.0], 0.5)
    assert not in_friction_cone([0.0, 0.0, -1.0], 0.5)  # pulling
    assert in_friction_cone([0.0, 0.0, 1.0], 0.0)  # frictionless: pure push only
    assert not in_friction_cone([1e-9, 0.0, 1.0], 0.0)


# --- force closure and quality ----------------------------------------------------------------------------------


@pytest.mark.parametrize(("name", "points", "normals", "mu", "closure"), CLASSICS, ids=ids(CLASSICS))
def test_classic_grasps_force_closure_and_epsilon_agree(
    name: str, points: np.ndarray, normals: np.ndarray, mu: float, closure: bool
) -> None:
    grasp = grasp_map(points, normals, np.zeros(3))
    assert is_force_closure(grasp, mu) is closure
    epsilon = ferrari_canny(grasp, mu)
    assert (epsilon > 0.0) is closure
    assert (grasp_wrench_space_volume(grasp, mu) > 0.0) is closure
    assert (force_closure_margin(grasp, mu) > 1e-9) is closure
    quality = grasp_quality(points, normals, np.zeros(3), mu)
    assert isinstance(quality, GraspQuality)
    assert quality.force_closure is closure
    assert quality.epsilon == pytest.approx(epsilon, rel=1e-12)
    assert (quality.rank == 6) or not closure


def test_antipodal_frictional_contacts_cannot_resist_torque_about_their_axis() -> None:
    points, normals = antipodal()
    grasp = grasp_map(points, normals, np.zeros(3))
    torque_about_axis = np.r_[0.0, 0.0, 0.0, 1.0, 0.0, 0.0]
    np.testing.assert_allclose(grasp.T @ torque_about_axis, 0.0, atol=1e-15)  # no contact force makes it
    quality = grasp_quality(points, normals, np.zeros(3), 10.0)
    assert quality.rank == 5 and not quality.force_closure and quality.epsilon == 0.0
    assert force_closure_margin(grasp, 10.0) == 0.0  # balanced (squeezing) but not spanning


@pytest.mark.parametrize(("name", "points", "normals", "mu", "closure"), CLOSURE, ids=ids(CLOSURE))
def test_epsilon_is_the_radius_of_a_ball_inside_the_wrench_space(
    name: str, points: np.ndarray, normals: np.ndarray, mu: float, closure: bool
) -> None:
    """Independent of qhull: radial distances to the boundary of conv(W) by LP, in random directions, are all
    >= epsilon (the ball is inside) and the smallest is close to it (the ball is the largest)."""
    grasp = grasp_map(points, normals, np.zeros(3))
    wrenches = primitive_wrenches(grasp, mu)
    epsilon = ferrari_canny(grasp, mu)
    count = wrenches.shape[1]
    directions = np.random.default_rng(1).normal(size=(150, 6))
    radii = []
    for u in directions / np.linalg.norm(directions, axis=1, keepdims=True):
        equality = np.zeros((7, count + 1))
        equality[:6, :count], equality[:6, -1], equality[6, :count] = wrenches, -u, 1.0
        cost = np.r_[np.zeros(count), -1.0]  # maximise t with t u in conv(W)
        bounds = [(0.0, None)] * count + [(None, None)]
        result = linprog(cost, A_eq=equality, b_eq=np.r_[np.zeros(6), 1.0], bounds=bounds, method="highs")
        radii.append(result.x[-1])
    assert min(radii) >= epsilon * (1.0 - 1e-7)
    assert min(radii) <= 1.3 * epsilon


@pytest.mark.parametrize(("name", "points", "normals", "mu", "closure"), CLOSURE, ids=ids(CLOSURE))
def test_doubling_the_facets_never_lowers_epsilon(
    name: str, points: np.ndarray, normals: np.ndarray, mu: float, closure: bool
) -> None:
    """The 16 edges at angles 2 pi j / 16 include the 8 at 2 pi j / 8, so the 16-facet wrench space contains the
    8-facet one (same torque scale, which depends only on the geometry): the inscribed-pyramid discretisation
    error can only shrink, and the tolerance is rounding alone (stricter than a cos(pi/8) vs cos(pi/16) bound)."""
    grasp = grasp_map(points, normals, np.zeros(3))
    assert ferrari_canny(grasp, mu, 16) >= ferrari_canny(grasp, mu, 8) - 1e-12
    assert grasp_wrench_space_volume(grasp, mu, 16) >= grasp_wrench_space_volume(grasp, mu, 8) * (1.0 - 1e-12)


@pytest.mark.parametrize(("coarse", "fine"), [(8, 12), (12, 8), (6, 16), (16, 5)])
@pytest.mark.parametrize("grasp_points", [sphere_equator(3), tetrahedron_faces()], ids=["sphere", "tetrahedron"])
def test_other_facet_counts_obey_the_inscribed_pyramid_bound(
    coarse: int, fine: int, grasp_points: tuple[np.ndarray, np.ndarray]
) -> None:
    """Non-nested pyramids.  The k'-pyramid of mu contains the exact cone of mu' = mu cos(pi/k') (its inscribed
    circle), hence the k-pyramid of mu'.  A unit edge u of the latter has normal part h' = 1/sqrt(1 + mu'^2) and
    u (h/h') lies on the cap of conv(unit edges of the k'-pyramid) (normal part h = 1/sqrt(1 + mu^2)), so
    W_k'(mu) contains (h/h') W_k(mu') and epsilon_k'(mu) >= (h/h') epsilon_k(mu')."""
    mu = 0.6
    grasp = grasp_map(*grasp_points, np.zeros(3))
    reduced = mu * math.cos(math.pi / fine)
    factor = math.sqrt((1.0 + reduced**2) / (1.0 + mu**2))
    assert ferrari_canny(grasp, mu, fine) >= factor * ferrari_canny(grasp, reduced, coarse) - 1e-12


@pytest.mark.parametrize("grasp_points", [sphere_equator(3), tetrahedron_faces()], ids=["sphere", "tetrahedron"])
def test_epsilon_grows_with_friction(grasp_points: tuple[np.ndarray, np.ndarray]) -> None:
    grasp = grasp_map(*grasp_points, np.zeros(3))
    epsilons = [ferrari_canny(grasp, mu) for mu in (0.05, 0.1, 0.2, 0.4, 0.8, 1.6)]
    assert epsilons[0] > 0.0
    assert all(b > a for a, b in itertools.pairwise(epsilons))
    # guaranteed part: the unit edges of mu1 scaled by h2/h1 lie in conv(unit edges of mu2) for mu1 <= mu2
    for mu1, mu2 in [(0.05, 0.1), (0.4, 1.6)]:
        factor = math.sqrt((1.0 + mu1**2) / (1.0 + mu2**2))
        assert ferrari_canny(grasp, mu2) >= factor * ferrari_canny(grasp, mu1) - 1e-12


def test_quality_does_not_depend_on_the_unit_of_length() -> None:
    points, normals = tetrahedron_faces()
    reference = np.array([0.002, -0.001, 0.003])
    metres = grasp_quality(points, normals, reference, 0.5)
    millimetres = grasp_quality(1000.0 * points, normals, 1000.0 * reference, 0.5)
    assert millimetres.epsilon == pytest.approx(metres.epsilon, rel=1e-9)
    assert millimetres.volume == pytest.approx(metres.volume, rel=1e-9)
    assert millimetres.margin == pytest.approx(metres.margin, abs=1e-9)
    assert millimetres.torque_scale == pytest.approx(1000.0 * metres.torque_scale, rel=1e-12)
    # an explicit torque scale changes epsilon (Ferrari-Canny depends on it) but not force closure
    other = grasp_quality(points, normals, reference, 0.5, torque_scale=10.0 * metres.torque_scale)
    assert other.force_closure and other.epsilon != pytest.approx(metres.epsilon, rel=1e-3)


# --- input validation -------------------------------------------------------------------------------------------

POINTS, NORMALS = sphere_equator(3)
GRASP = grasp_map(POINTS, NORMALS, np.zeros(3))

BAD_CALLS: list[tuple[str, Callable[[], Any], str]] = [
    ("shape mismatch", lambda: grasp_map(POINTS, NORMALS[:2], np.zeros(3)), "same shape"),
    ("points not (n, 3)", lambda: grasp_map(POINTS[:, :2], NORMALS[:, :2], np.zeros(3)), "points"),
    ("no contacts", lambda: grasp_map(np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(3)), "n >= 1"),
    ("NaN point", lambda: grasp_map([[0.0, np.nan, 0.0]], [[0.0, 0.0, 1.0]], np.zeros(3)), "points"),
    ("inf normal", lambda: contact_frames([[0.0, 0.0, 1.0], [np.inf, 0.0, 0.0]]), "index [1]"),
    ("zero normal", lambda: contact_frames([[0.0, 0.0, 1.0], [0.0, 0.0, 1.0], [0.0, 0.0, 0.0]]), "index [2]"),
    ("bad reference", lambda: grasp_map(POINTS, NORMALS, np.zeros(2)), "reference"),
    ("negative mu", lambda: friction_cone_edges(-0.1, 8), "mu"),
    ("NaN mu", lambda: ferrari_canny(GRASP, float("nan")), "mu"),
    ("facets 2", lambda: friction_pyramid(0.5, 2), "facets"),
    ("facets float", lambda: is_force_closure(GRASP, 0.5, 8.0), "facets"),
    ("torque scale 0", lambda: primitive_wrenches(GRASP, 0.5, 8, 0.0), "torque_scale"),
    ("grasp matrix shape", lambda: force_closure_margin(GRASP[:, :4], 0.5), "grasp_matrix"),
    ("cone force shape", lambda: in_friction_cone([0.0, 1.0], 0.5), "`f`"),
    ("twist shape", lambda: grasp_constraint_residual(GRASP, np.zeros((9, 8)), np.zeros(5), np.zeros(8)), "twist"),
    ("jacobian rows", lambda: grasp_constraint_residual(GRASP, np.zeros((6, 8)), np.zeros(6), np.zeros(8)), "jacobian"),
]


@pytest.mark.parametrize(("name", "call", "mentions"), BAD_CALLS, ids=[case[0] for case in BAD_CALLS])
def test_bad_inputs_raise_input_error(name: str, call: Callable[[], Any], mentions: str) -> None:
    with pytest.raises(InputError, match=re.escape(mentions)):
        call()


def test_hand_jacobian_rejects_unknown_links_and_wrong_link_counts(barrett: bh.Hand) -> None:
    q = barrett.neutral()
    with pytest.raises(InputError, match="no_such_link"):
        hand_jacobian(barrett, q, POINTS, ["F1_tip", "no_such_link", "F3_tip"], NORMALS)
    with pytest.raises(InputError, match="links"):
        hand_jacobian(barrett, q, POINTS, ["F1_tip", "F2_tip"], NORMALS)
    with pytest.raises(InputError, match="q"):
        hand_jacobian(barrett, np.zeros(3), POINTS, "F1_tip", NORMALS)


def test_importing_grasp_does_not_import_scipy() -> None:
    code = "import sys, bhgrasp.grasp; assert not any(m.startswith('scipy') for m in sys.modules)"
    subprocess.run([sys.executable, "-c", code], check=True)
