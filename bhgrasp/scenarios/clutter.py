"""Clutter: mixed objects dropped into a bin or onto a table and left to settle, with a seed.

:func:`mixed_objects` draws boxes, cylinders, spheres and capsules of household sizes; :func:`bin_walls` builds a
bin of fixed boxes; :func:`drop_pile` drops objects over a rectangle of the world, at random non-overlapping
positions from the floor up (:func:`drop_poses`) and random orientations, and simulates them until every object has
stayed at rest for ``rest_time`` (its fastest point, |v| + |w| r, under ``rest_speed``).  Objects already in place
(``placed``, e.g. one on a stand) settle with them.  The hand stays where it is, held against gravity.  The settled
objects (:attr:`Pile.objects`) start another scene, e.g. a grasp among them
(:mod:`bhgrasp.bench.neighbours`).  Same objects, seed and settings, same bits.

A scene's dynamics run part by part (:mod:`~bhgrasp.sim.scene_parts`), so it builds in time and memory linear in its
objects, but a step still solves the whole scene's velocities densely and costs more than linearly in their number
(BENCHMARKS.md: 27 us for 4 settled objects, 1.7 ms for 32, 10 ms for 64 on the test machine).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
import pinocchio as pin

from bhgrasp._validation import as_generator, as_int, as_positive, as_real, as_vector
from bhgrasp.data import State
from bhgrasp.errors import InputError, NotSettled
from bhgrasp.model.barrett_hand import BarrettHand
from bhgrasp.model.hand import Hand
from bhgrasp.model.hand_dynamics import gravity_torques
from bhgrasp.model.objects import Box, Capsule, Cylinder, FixedBox, RigidObject, Sphere
from bhgrasp.sim import Simulator
from bhgrasp.sim.actuation import FullyActuated
from bhgrasp.sim.contact_law import SpringDamper
from bhgrasp.sim.scene import Environment, Scene

# Household sizes (the YCB set's small and mid-sized objects) [m] and masses [kg] mixed_objects draws from.
SIZES = {
    "box": {"size": ((0.03, 0.09), (0.03, 0.07), (0.025, 0.06))},
    "cylinder": {"radius": (0.02, 0.04), "length": (0.04, 0.12)},
    "sphere": {"radius": (0.02, 0.04)},
    "capsule": {"radius": (0.015, 0.03), "length": (0.02, 0.08)},
}
MASS = (0.05, 0.4)  # [kg]
KINDS = {"box": Box, "cylinder": Cylinder, "sphere": Sphere, "capsule": Capsule}
# The settling contact: a 0.4 kg object landing at 1 m/s sinks 3.7 mm, damping ratio 0.77 at 0.05 kg, 0.27 at 0.4 kg
CONTACT = SpringDamper(stiffness=3e4, damping=60.0, friction=0.8)
# [1/s] the settling scene's object drag (Scene.object_drag): point contacts have no rolling or spinning
# resistance, so a ball rolling on a flat floor or spinning on its contact point would never stop; zero at rest
DRAG = 5.0
GAP = 0.005  # [m] between the bounding spheres of the drop, and above the floor
TRIES = 100  # positions drawn per object and layer


@dataclass(frozen=True)
class Pile:
    """A settled pile: its simulator, the settled state, the objects at their settled poses, the time it took.

    ``objects``: copies of the ``placed`` objects, then of the dropped ones (the scene's order), where they came to
    rest (zero velocity), e.g. to build another scene around them.
    """

    simulator: Simulator
    state: State
    objects: tuple[RigidObject, ...]
    settle_time: float  # [s] simulated

    def support_force(self) -> np.ndarray:
        """The environment's total force on the objects [N, world] (at rest: minus their weight)."""
        scene, state = self.simulator.scene, self.state
        fixed = set(scene.environment_names)
        on_objects = [f for (a, _), f in zip(state.contact_bodies, state.contact_forces) if a in fixed]
        return np.sum(on_objects, axis=0) if on_objects else np.zeros(3)


def mixed_objects(n: int, seed: Any, friction: float = 0.8) -> list[RigidObject]:
    """``n`` objects of kinds, sizes and masses drawn uniformly from :data:`SIZES` and :data:`MASS`.

    Named ``"{kind}{i}"``; placed at the origin (:func:`drop_pile` places them).  ``seed``: an integer or a numpy
    Generator.
    """
    n = as_int(n, "n", 1)
    rng = as_generator(seed, "seed")
    friction = as_real(friction, "friction")
    kinds = list(SIZES)
    objects = []
    for i in range(n):
        kind = kinds[int(rng.integers(len(kinds)))]
        shape = {
            name: (tuple(rng.uniform(*r) for r in ranges) if name == "size" else rng.uniform(*ranges))
            for name, ranges in SIZES[kind].items()
        }
        mass = rng.uniform(*MASS)
        objects.append(KINDS[kind](**shape, mass=mass, friction=friction, name=f"{kind}{i}"))
    return objects


def bin_walls(
    centre: Any = (0.0, 0.0),
    inner: Any = (0.3, 0.2),
    height: float = 0.1,
    floor: float = 0.0,
    thickness: float = 0.01,
    friction: float = 0.8,
) -> list[FixedBox]:
    """A bin: a floor whose top is at z = ``floor`` [m] and four walls ``height`` [m] above it, all fixed boxes.

    ``centre`` (x, y) [m] and ``inner`` (x, y) extent [m] of the floor inside the walls; walls ``thickness`` [m].
    """
    centre, inner = as_vector(centre, "centre", 2), as_vector(inner, "inner", 2)
    if np.any(inner <= 0.0):
        raise InputError(f"`inner` must be two positive extents [m], got {inner.tolist()}")
    height, thickness = as_positive(height, "height"), as_positive(thickness, "thickness")
    floor = as_real(floor, "floor", nonnegative=False)
    outer = inner + 2 * thickness

    def box(name: str, size: Sequence[float], x: float, y: float, z: float) -> FixedBox:
        pose = pin.SE3(np.eye(3), np.array([centre[0] + x, centre[1] + y, z]))
        return FixedBox(size=size, pose=pose, friction=friction, name=name)

    z_wall = floor + 0.5 * height
    half = 0.5 * (inner + thickness)
    return [
        box("bin floor", (*outer, thickness), 0.0, 0.0, floor - 0.5 * thickness),
        box("bin wall -x", (thickness, outer[1], height), -half[0], 0.0, z_wall),
        box("bin wall +x", (thickness, outer[1], height), half[0], 0.0, z_wall),
        box("bin wall -y", (inner[0], thickness, height), 0.0, -half[1], z_wall),
        box("bin wall +y", (inner[0], thickness, height), 0.0, half[1], z_wall),
    ]


def drop_poses(
    objects: Sequence[RigidObject],
    region: Any,
    floor: float,
    rng: np.random.Generator,
    keep_out: Sequence[RigidObject] = (),
) -> list[pin.SE3]:
    """Drop poses over ``region`` = (x_min, y_min, x_max, y_max) [m], from ``floor`` [m] up.

    Each object in turn: up to :data:`TRIES` positions drawn uniformly over the region at the lowest layer, its
    bounding sphere :data:`GAP` above ``floor``; the first whose sphere clears (by GAP) every sphere placed before,
    and in x, y every ``keep_out`` object's (nothing is dropped above one), is taken, else the next layer up (one
    largest bounding diameter + GAP higher) is tried.  Turned at random (uniform on SO(3)).
    """
    region = as_vector(region, "region", 4)
    radii = [item.bounding_radius for item in objects]
    if np.any(region[2:] - region[:2] < 2.0 * max(radii)):
        raise InputError(
            f"`region` {region.tolist()} must be at least {2.0 * max(radii):.3f} m wide each way: the largest "
            "object's bounding diameter"
        )
    layer_height = 2.0 * max(radii) + GAP
    columns = [(item.pose.translation[:2], item.bounding_radius) for item in keep_out]
    spheres: list[tuple[np.ndarray, float]] = []
    poses = []
    for radius in radii:
        low, high = region[:2] + radius, region[2:] - radius
        centre = None
        for layer in range(len(objects) + 1):
            z = floor + GAP + radius + layer * layer_height
            for _ in range(TRIES):
                trial = np.array([*rng.uniform(low, high), z])
                clear = all(np.linalg.norm(trial[:2] - c) >= r + radius + GAP for c, r in columns)
                if clear and all(np.linalg.norm(trial - c) >= r + radius + GAP for c, r in spheres):
                    centre = trial
                    break
            if centre is not None:
                break
        if centre is None:
            raise InputError(f"`region` {region.tolist()} has no room clear of `keep_out` for {len(objects)} objects")
        spheres.append((centre, radius))
        quaternion = rng.normal(size=4)
        rotation = pin.Quaternion(*(quaternion / np.linalg.norm(quaternion))).toRotationMatrix()
        poses.append(pin.SE3(rotation, centre))
    return poses


def drop_pile(
    objects: Sequence[RigidObject],
    environment: Sequence[Environment],
    region: Any,
    floor: float = 0.0,
    seed: Any = 0,
    hand: Hand | None = None,
    q_hand: Any = None,
    dt: float = 5e-4,
    contact: SpringDamper = CONTACT,
    drag: float = DRAG,
    rest_speed: float = 0.01,
    rest_time: float = 0.1,
    max_time: float = 5.0,
    engine: str | None = None,
    placed: Sequence[RigidObject] = (),
) -> Pile:
    """Drop ``objects`` over ``region`` (x_min, y_min, x_max, y_max) [m] onto ``environment`` and let them settle.

    Args:
        objects: Free rigid objects (their poses are replaced by :func:`drop_poses`'; their velocity by zero).
        environment: The fixed shapes they fall onto (a table, :func:`bin_walls`).
        region: The rectangle they are dropped over [m, world].
        floor: Height [m] of the surface under ``region`` (the lowest layer starts just above it).
        seed: Integer or numpy Generator of the drop poses.
        hand: The scene's hand (default: a BH8-280 1 m above the region, out of reach), held at ``q_hand``
            (default neutral) by its gravity torques; its links and the environment do not touch.
        dt: Step [s].  contact: The contact law.
        drag: [1/s] the settling scene's drag on the objects (:data:`DRAG`, ``Scene.object_drag``).
        rest_speed, rest_time: At rest: every object's fastest point below ``rest_speed`` [m/s] for ``rest_time`` [s].
        max_time: Simulated time [s] allowed.
        engine: ``"compiled"``, ``"python"`` or None (the default engine).
        placed: Objects already in place (e.g. one on its stand): first in the scene, kept where they are, no drop
            cell meets their bounding spheres; they settle with the others.

    Raises:
        NotSettled: Still moving after ``max_time`` (the message names the objects and their speeds).
        InputError: Bad arguments (named), e.g. a region narrower than the largest object.
    """
    if not objects or not all(isinstance(item, RigidObject) for item in objects):
        raise InputError(f"`objects` must be a non-empty sequence of RigidObject, got {objects!r}")
    rest_speed, rest_time = as_positive(rest_speed, "rest_speed"), as_positive(rest_time, "rest_time")
    max_time, drag = as_positive(max_time, "max_time"), as_real(drag, "drag")
    rng = as_generator(seed, "seed")
    if not all(isinstance(item, RigidObject) for item in placed):
        raise InputError(f"`placed` must hold RigidObject only, got {placed!r}")
    poses = drop_poses(objects, region, as_real(floor, "floor", nonnegative=False), rng, placed)
    dropped = [*placed, *(_placed(item, pose) for item, pose in zip(objects, poses))]
    if hand is None:
        above = np.array([*(0.5 * (np.asarray(region[:2]) + np.asarray(region[2:]))), floor + 1.0])
        hand = BarrettHand(base_placement=pin.SE3(np.eye(3), above))
    scene = Scene(hand, dropped, environment=environment, environment_touches_hand=False, object_drag=drag)
    simulator = Simulator(scene, dt=dt, contact=contact, actuation=FullyActuated(hand), engine=engine)
    state = simulator.initial_state(q_hand)
    hold = gravity_torques(hand, state.q)
    radii = np.array([item.bounding_radius for item in dropped])
    slices = [scene.object_v_slice(i) for i in range(len(dropped))]
    steps, calm = round(max_time / simulator.dt), 0
    for _ in range(steps):
        state, _ = simulator.step(state, hold)
        speeds = _speeds(state, slices, radii)
        calm = calm + 1 if np.all(speeds < rest_speed) else 0
        if calm * simulator.dt >= rest_time:
            settled = tuple(_placed(item, pose) for item, pose in zip(dropped, state.object_poses))
            return Pile(simulator, state, settled, state.t)
    names = scene.object_names
    raise NotSettled(state.t, dict(zip(names, _speeds(state, slices, radii).tolist())), rest_speed)


def _placed(item: RigidObject, pose: pin.SE3) -> RigidObject:
    """A copy of ``item`` at ``pose``, at rest (its mass kept: a density-defined object's too)."""
    return replace(item, pose=pose, velocity=np.zeros(6), mass=item.mass, density=None)


def _speeds(state: State, slices: list[slice], radii: np.ndarray) -> np.ndarray:
    """Each object's fastest point's speed bound |v| + |w| r [m/s] (v of the COM, w the angular velocity)."""
    v = state.scene_v
    return np.array([np.linalg.norm(v[s][:3]) + np.linalg.norm(v[s][3:]) * r for s, r in zip(slices, radii)])


__all__ = ["CONTACT", "DRAG", "MASS", "SIZES", "Pile", "bin_walls", "drop_pile", "drop_poses", "mixed_objects"]
