"""The contact detection's shortcuts against what they replace, bit for bit.

Two shortcuts, each with a switch back to its reference:

- **the kept coal solver** (src/narrowphase.cpp): coal::collide makes a new solver for every query; the compiled
  engine keeps one and sets it back before each query to the state a new one starts in.  The truth is coal::collide:
  the same engine with ``kept_solver`` off calls it.
- **the boxes' separating axes** (src/detect.cpp, ``box_separation``): a pair of boxes apart along one of the 15
  axes of the separating-axis test is not asked of coal.  The truth is coal asked for every pair (``box_axes`` off).

Two simulators of one scene, one with the shortcut and one without, stepped side by side must give the same bits at
every step: a box pinched by three fingertips, the BH8-280 closing on a box (patches on links and the palm), convex
mesh pieces rolling on a table, and a settled pile of mixed primitives in a bin, pushed about (object-object pairs
and walls).  ``box_separation`` itself is held to coal's distance: a lower bound of it, equal to it for boxes apart
along a face normal.
"""

from __future__ import annotations

from collections.abc import Callable

import coal
import numpy as np
import pinocchio as pin
import pytest
from scenes import prism_onto_banana

from bhgrasp.scenarios.box_grasp import box_grasp
from bhgrasp.scenarios.clutter import bin_walls, drop_pile, mixed_objects
from bhgrasp.scenarios.hold import reference_hold
from bhgrasp.sim import Simulator
from bhgrasp.sim.actuation import BarrettActuation
from bhgrasp.sim.coal_queries import FALLBACK_TOLERANCE, NARROW_TOLERANCE
from bhgrasp.sim.compiled import core_module

SLACK = 1e-9 + 10 * max(NARROW_TOLERANCE, FALLBACK_TOLERANCE)  # [m] detect()'s: apart beyond the margin by this
CHECKED = "3.0.3"  # the coal whose collide() src/narrowphase.cpp mirrors (another one runs coal::collide itself)


def coal_collide(simulator: Simulator) -> Simulator:
    """``simulator``'s engine set to let coal::collide make a solver per query (the reference)."""
    native = simulator.engine._engine
    assert native.kept_solver == (coal.__version__ == CHECKED), f"coal {coal.__version__}: re-check the kept solver"
    native.kept_solver = False
    return simulator


def every_box_pair(simulator: Simulator) -> Simulator:
    """``simulator``'s engine set to ask coal about every pair of boxes (the reference of the separating axes)."""
    native = simulator.engine._engine
    assert native.box_axes
    native.box_axes = False
    return simulator


REFERENCES = {"kept solver": coal_collide, "box axes": every_box_pair}
reference_of = pytest.mark.parametrize("reference_of", REFERENCES.values(), ids=REFERENCES.keys())


def assert_same_bits(kept: Simulator, reference: Simulator, inputs: Callable, steps: int, state) -> int:
    """Step both from ``state`` with ``inputs(k, state) -> (u, object_forces)``; every step's bits equal.

    Returns the most contact points seen at a step (the scene must have exercised the detection).
    """
    a = b = state
    most = 0
    for k in range(steps):
        u, forces = inputs(k, a)
        a, info_a = kept.step(a, u, object_forces=forces)
        b, info_b = reference.step(b, u, object_forces=forces)
        np.testing.assert_array_equal(a.scene_q, b.scene_q)
        np.testing.assert_array_equal(a.scene_v, b.scene_v)
        for field in ("pair", "point", "normal", "depth", "force"):
            np.testing.assert_array_equal(getattr(info_a.contacts, field), getattr(info_b.contacts, field))
        most = max(most, len(info_a.contacts))
    return most


@reference_of
def test_a_pinched_box_sees_the_same_contacts(reference_of) -> None:
    kept, reference = reference_hold(), reference_hold()
    reference_of(reference.simulator)

    def inputs(k, state):
        return kept.controller(state.t, state) * (1.0 + 0.5 * np.sin(k / 40.0)), None

    engines = (kept.simulator.engine._engine, reference.simulator.engine._engine)
    before = [engine.box_axes_skipped for engine in engines]
    assert assert_same_bits(kept.simulator, reference.simulator, inputs, 600, kept.state) >= 3
    skipped = [engine.box_axes_skipped - count for engine, count in zip(engines, before)]
    assert skipped[0] > 600  # the links' boxes near the box, apart from it: about one in two pairs a step
    assert skipped[1] == (0 if reference_of is every_box_pair else skipped[0])


@reference_of
def test_the_barrett_hand_closing_on_a_box_sees_the_same_contacts(reference_of) -> None:
    setup = box_grasp(mass=0.3, actuation="barrett")

    def simulator() -> Simulator:
        actuation = BarrettActuation(setup.hand, saturate=True)
        return Simulator(setup.simulator.scene, dt=setup.simulator.dt, contact=setup.simulator.law, actuation=actuation)

    kept, reference = simulator(), reference_of(simulator())
    close = np.array([0.01, 0.02, 0.02, 0.02])  # [N m]
    state = kept.initial_state(setup.q_start)
    assert assert_same_bits(kept, reference, lambda k, s: (close, None), 900, state) >= 6


def test_convex_mesh_pieces_rolling_on_a_table_see_the_same_contacts() -> None:  # no boxes: the kept solver only
    kept, reference = prism_onto_banana(), coal_collide(prism_onto_banana())
    state = kept.initial_state()
    assert assert_same_bits(kept, reference, lambda k, s: (np.zeros(8), None), 400, state) >= 4


@reference_of
def test_a_pushed_pile_in_a_bin_sees_the_same_contacts(reference_of) -> None:
    pile = drop_pile(mixed_objects(6, seed=3), bin_walls(inner=(0.2, 0.16), height=0.1), (-0.08, -0.06, 0.08, 0.06))
    kept = pile.simulator
    reference = reference_of(Simulator.from_settings(kept.scene, kept.settings, kept.law, kept.actuation))
    pushes = np.random.default_rng(3).normal(scale=2.0, size=(len(pile.objects), 3))  # [N]

    def inputs(k, state):
        return np.zeros(kept.actuation.n_inputs), pushes * np.cos(k / 25.0)

    assert assert_same_bits(kept, reference, inputs, 300, pile.state) >= 10
    assert kept.engine._engine.box_axes_skipped > 0  # boxes and walls near each other, apart


def random_pose(rng: np.random.Generator, spread: float) -> pin.SE3:
    """A pose of random rotation, its origin within ``spread`` [m] of the world's."""
    return pin.SE3(pin.exp3(rng.normal(size=3) * 2.0), rng.uniform(-spread, spread, size=3))


def box_gap(half_a, pose_a: pin.SE3, half_b, pose_b: pin.SE3) -> float:
    """The compiled separating-axis gap [m] of two boxes (half sides, world poses)."""
    return core_module().box_separation(half_a, pose_a.homogeneous, half_b, pose_b.homogeneous)


def coal_distance(half_a, pose_a: pin.SE3, half_b, pose_b: pin.SE3) -> float:
    """coal's distance [m] between two boxes (negative: penetrating)."""
    result = coal.DistanceResult()
    transform = [coal.Transform3s(pose.rotation, pose.translation) for pose in (pose_a, pose_b)]
    request = coal.DistanceRequest()
    request.gjk_tolerance = 1e-12
    shapes = [coal.Box(*(2 * np.asarray(half))) for half in (half_a, half_b)]
    return coal.distance(shapes[0], transform[0], shapes[1], transform[1], request, result)


def test_the_box_separation_is_a_lower_bound_of_coals_distance() -> None:
    rng = np.random.default_rng(11)
    apart = 0
    for _ in range(3000):
        half_a, half_b = rng.uniform(0.002, 0.05, size=3), rng.uniform(0.002, 0.05, size=3)
        pose_a, pose_b = random_pose(rng, 0.08), random_pose(rng, 0.08)
        gap = core_module().box_separation(half_a, pose_a.homogeneous, half_b, pose_b.homogeneous)
        distance = coal_distance(half_a, pose_a, half_b, pose_b)
        assert gap <= distance + 1e-9, (gap, distance)  # coal's distance (signed: < 0 overlapping) to ~1e-11 m
        apart += gap > 0.0
    assert apart > 500  # the draws were apart often enough to try the bound, and overlapped too
    assert 3000 - apart > 200


def test_the_box_separation_is_the_distance_of_boxes_apart_along_a_face_normal() -> None:
    rng = np.random.default_rng(12)
    for _ in range(200):
        half_a, half_b = rng.uniform(0.002, 0.05, size=3), rng.uniform(0.002, 0.05, size=3)
        rotation = pin.exp3(rng.normal(size=3))
        axis, distance = int(rng.integers(3)), rng.uniform(1e-4, 0.05)
        offset = np.zeros(3)
        offset[axis] = half_a[axis] + half_b[axis] + distance  # b beside a's face, both turned alike
        offset[(axis + 1) % 3] = rng.uniform(-1, 1) * min(half_a[(axis + 1) % 3], half_b[(axis + 1) % 3])
        pose_a = pin.SE3(rotation, rng.normal(size=3) * 0.1)
        pose_b = pin.SE3(rotation, pose_a.translation + rotation @ offset)
        gap = core_module().box_separation(half_a, pose_a.homogeneous, half_b, pose_b.homogeneous)
        assert gap == pytest.approx(distance, abs=1e-12)
        assert gap == pytest.approx(coal_distance(half_a, pose_a, half_b, pose_b), abs=1e-9)


def test_overlapping_boxes_have_no_separating_axis() -> None:
    rng = np.random.default_rng(13)
    for _ in range(300):
        half_a, half_b = rng.uniform(0.002, 0.05, size=3), rng.uniform(0.002, 0.05, size=3)
        pose_a = random_pose(rng, 0.1)
        inside = pose_a.act(rng.uniform(-1, 1, size=3) * half_a)  # b's centre inside a
        pose_b = pin.SE3(pin.exp3(rng.normal(size=3) * 2.0), inside)
        assert core_module().box_separation(half_a, pose_a.homogeneous, half_b, pose_b.homogeneous) <= 0.0


@pytest.mark.parametrize("margin", [0.0, 2e-3])
def test_boxes_the_test_skips_are_boxes_coal_finds_no_contact_between(margin: float) -> None:
    """Pairs brought just past the skip's threshold (the gap a hair to 1 mm beyond the margin and the slack): coal,
    asked as the engine asks it (its tolerance, the security margin), reports no contact for any of them."""
    rng = np.random.default_rng(14)
    request = coal.CollisionRequest(coal.CollisionRequestFlag.CONTACT, 4)
    request.security_margin = margin
    request.gjk_tolerance = request.epa_tolerance = NARROW_TOLERANCE
    near = 0
    for _ in range(400):
        half_a, half_b = rng.uniform(0.002, 0.05, size=3), rng.uniform(0.002, 0.05, size=3)
        pose_a, turn = random_pose(rng, 0.05), pin.exp3(rng.normal(size=3) * 2.0)
        direction = rng.normal(size=3)
        direction /= np.linalg.norm(direction)
        target = margin + SLACK * (1.0 + 1e-6) + rng.choice([1e-12, 1e-9, 1e-6, 1e-3]) * rng.uniform()

        low, high = 0.0, 1.0  # the gap grows along the direction from overlap: bisect to the target
        for _ in range(80):
            middle = 0.5 * (low + high)
            pose_b = pin.SE3(turn, pose_a.translation + middle * direction)
            low, high = (middle, high) if box_gap(half_a, pose_a, half_b, pose_b) < target else (low, middle)
        pose_b = pin.SE3(turn, pose_a.translation + high * direction)
        gap = box_gap(half_a, pose_a, half_b, pose_b)
        assert margin + SLACK < gap < margin + SLACK + 1e-3 + 1e-9
        near += gap < margin + SLACK + 1e-6
        shapes = [coal.Box(*(2 * half)) for half in (half_a, half_b)]
        transforms = [coal.Transform3s(pose.rotation, pose.translation) for pose in (pose_a, pose_b)]
        result = coal.CollisionResult()
        assert coal.collide(shapes[0], transforms[0], shapes[1], transforms[1], request, result) == 0
    assert near > 100  # most pairs within a micrometre past the threshold
