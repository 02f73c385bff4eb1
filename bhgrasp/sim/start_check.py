"""A scene that starts wrong says so: interpenetrating bodies and objects the step cannot resolve, before a step.

:func:`start_problems` reads a start configuration as the first step would see it and names

- every collision pair that starts **interpenetrated** deeper than :data:`START_DEPTH_SHARE` of the simulator's
  ``max_penetration`` (5 mm by default): its bodies, its depth and the force its contact spring releases at once;
- every free object whose contact the step cannot **resolve**: one that may move further in one step than its
  smallest half-thickness ``h`` (it can pass through a surface unseen, "tunnelling"), with the ``dt = h / u`` it
  needs, and one the contact law lets sink deeper than ``h`` or than ``max_penetration`` (at rest under gravity, or
  stopping from its speed: a 0.35 kg can falling 0.3 m onto k = 1e4 N/m stops 18 mm deep).
  Its speed ``u`` is what it may reach at its first contact: its initial speed plus its spin at its bounding radius,
  plus the speed of a fall through its gap to the nearest environment shape, ``sqrt(2 g gap)``;
- with an explicit integrator, a contact spring too **stiff** for ``dt`` on the lightest object (``_too_stiff``).

The stopping depth of a body of mass ``m`` arriving at ``u`` on the law ``f = k d^e`` (``e = 1`` linear) is the ``d``
at which the spring's energy ``k d^(e+1) / (e+1)`` equals ``m u^2 / 2``; at rest it sinks ``d = (m g / k)^(1/e)``.
:class:`~bhgrasp.sim.simulator.Simulator` runs the check when it builds an initial state and warns, raises, or stays
quiet by its ``start_check`` setting; it also names the problems when a run that started with them diverges.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Sequence
from dataclasses import dataclass

import coal
import numpy as np
import pinocchio as pin

from bhgrasp.data import ContactSet
from bhgrasp.errors import InputError
from bhgrasp.model.objects import RigidObject
from bhgrasp.sim.contact_law import SpringDamper
from bhgrasp.sim.scene import Scene
from bhgrasp.sim.scene_parts import SceneParts

START_DEPTH_SHARE = 0.25  # a start deeper than this share of max_penetration is named


class StartWarning(UserWarning):
    """A simulation starts interpenetrated or with an object its step cannot resolve (see :class:`StartProblem`)."""


@dataclass(frozen=True)
class StartProblem:
    """One thing wrong with a start configuration.

    Attributes:
        kind: ``"interpenetrated"``, ``"unresolved"`` or ``"too stiff"``.
        bodies: The bodies concerned (a pair, or one object).
        value: The depth [m] of an interpenetration, or the ``dt`` [s] an unresolved or too stiff object needs (0
            when the contact law, not ``dt``, is what cannot hold it).
        message: What is wrong (and, for an object, what to change), in words.
        limit: The depth [m] an interpenetration may have, or the object's smallest half-thickness [m].
    """

    kind: str
    bodies: tuple[str, ...]
    value: float
    message: str
    limit: float


def start_problems(
    scene: Scene,
    q: np.ndarray,
    v: np.ndarray,
    contacts: ContactSet,
    law: SpringDamper,
    dt: float,
    max_depth: float,
    integrator: str = "implicit",
) -> list[StartProblem]:
    """What is wrong with starting ``scene`` at ``(q, v)`` whose contacts are ``contacts`` (module docstring)."""
    limit = START_DEPTH_SHARE * max_depth
    problems = _interpenetrations(scene, q, contacts, law, limit) + _unresolved(scene, q, v, law, dt, max_depth)
    return problems + _too_stiff(scene, law, dt, integrator)


def _too_stiff(scene: Scene, law: SpringDamper, dt: float, integrator: str) -> list[StartProblem]:
    """The lightest free object whose contact spring an explicit integrator cannot step: omega dt beyond its bound.

    A mass m on a spring k oscillates at omega = sqrt(k / m); semi-implicit Euler is stable while omega dt < 2, the
    classical Runge-Kutta step while omega dt < 2.785 (its stability interval on the imaginary axis, 2 sqrt(2)).  The
    implicit step has no such bound.  (The linear law's stiffness; Hunt-Crossley's grows with depth and is not
    checked.)
    """
    bound = {"semi-implicit": 2.0, "rk4": 2.0 * math.sqrt(2.0)}.get(integrator)
    masses = [
        (item.mass, name) for item, name in zip(scene.objects, scene.object_names) if isinstance(item, RigidObject)
    ]
    if bound is None or law.normal_law != "linear" or not masses:
        return []
    mass, name = min(masses)
    omega = math.sqrt(law.stiffness / mass)
    if omega * dt < bound:
        return []
    needed = bound / omega
    message = (
        f"{name} ({mass:.3g} kg) on the contact stiffness {law.stiffness:.3g} N/m rings at {omega:.3g} rad/s, too fast "
        f"for the {integrator} step at dt = {dt:g} s: dt < {needed:.3g} s, a softer contact, or integrator='implicit'"
    )
    return [StartProblem("too stiff", (name,), needed, message, 0.0)]


def report(problems: list[StartProblem], mode: str) -> None:
    """Warn of ``problems`` (``mode`` ``"warn"``), raise them (``"error"``) or neither (``"off"``, or none)."""
    if not problems or mode == "off":
        return
    text = summary(problems)
    if mode == "error":
        raise InputError(text + " (Simulator(start_check='warn') runs it anyway)")
    warnings.warn(text, StartWarning, stacklevel=3)


def summary(problems: list[StartProblem], shown: int = 3) -> str:
    """The problems in one sentence: the deepest ``shown`` interpenetrations (and how many more), every object."""
    deep = sorted((p for p in problems if p.kind == "interpenetrated"), key=lambda p: -p.value)
    parts = []
    if deep:
        listed = "; ".join(p.message for p in deep[:shown]) + (
            f"; and {len(deep) - shown} more" if len(deep) > shown else ""
        )
        pairs = f"{len(deep)} body pair{'s' * (len(deep) > 1)}"
        parts.append(
            f"{pairs} start interpenetrated deeper than {deep[0].limit * 1e3:.3g} mm "
            f"({START_DEPTH_SHARE:g} of max_penetration): {listed}; move them apart"
        )
    parts += [p.message for p in problems if p.kind != "interpenetrated"]
    return "the scene starts wrong: " + "; ".join(parts)


def pair_distances(scene: Scene, q: np.ndarray, indices: Sequence[int]) -> np.ndarray:
    """Coal's signed distance [m] between the two shapes of each collision pair ``indices`` at configuration ``q``.

    Negative: the shapes overlap by that much.
    """
    parts = SceneParts(scene.hand_model, scene.model)
    geometry_data = pin.GeometryData(scene.geometry)
    parts.forward_kinematics(q)
    parts.update_geometry_placements(scene.geometry, geometry_data)
    distances = []
    for index in indices:
        pair = scene.pairs[index]
        shapes = [scene.geometry.geometryObjects[g].geometry for g in (pair.geom_a, pair.geom_b)]
        a, b = (geometry_data.oMg[g] for g in (pair.geom_a, pair.geom_b))
        where_a, where_b = coal.Transform3s(a.rotation, a.translation), coal.Transform3s(b.rotation, b.translation)
        result = coal.DistanceResult()
        distances.append(coal.distance(shapes[0], where_a, shapes[1], where_b, coal.DistanceRequest(), result))
    return np.array(distances, dtype=float)


def _interpenetrations(
    scene: Scene, q: np.ndarray, contacts: ContactSet, law: SpringDamper, limit: float
) -> list[StartProblem]:
    """Each pair of bodies in contact whose shapes overlap deeper than ``limit`` [m], by coal's signed distance.

    (Not the contacts' own depths: those measure a patch point's overlap to the nearest faces, which for a link
    sunk whole in a plane is a side face: a box 146 mm deep read 58 mm.)
    """
    deepest: dict[tuple[str, str], float] = {}  # per pair of bodies (a body may have several geometries)
    indices = sorted({int(k) for k in contacts.pair})
    for index, distance in zip(indices, pair_distances(scene, q, indices)):
        bodies = (scene.pairs[index].body_a, scene.pairs[index].body_b)
        deepest[bodies] = max(deepest.get(bodies, 0.0), -float(distance))
    problems = []
    for (body_a, body_b), depth in deepest.items():
        if depth <= limit:
            continue
        force = law.stiffness * depth ** (1.0 if law.normal_law == "linear" else law.exponent)
        message = f"{body_b} {depth * 1e3:.3g} mm inside {body_a} (its contact pushes {force:.3g} N at once)"
        problems.append(StartProblem("interpenetrated", (body_a, body_b), depth, message, limit))
    return problems


def _unresolved(
    scene: Scene, q: np.ndarray, v: np.ndarray, law: SpringDamper, dt: float, max_depth: float
) -> list[StartProblem]:
    gravity = float(np.linalg.norm(scene.hand.gravity))
    exponent = 1.0 if law.normal_law == "linear" else law.exponent
    problems = []
    for index, item in enumerate(scene.objects):
        if not isinstance(item, RigidObject):
            continue  # a spring-mounted object moves along its spring only
        name = scene.object_names[index]
        half = _half_thickness(item)
        twist = scene.object_twist(q, v, index)
        pose = scene.object_pose(q, index)
        gap, below = _gap(scene, item.geometry(), pose)
        fall = math.sqrt(2.0 * gravity * gap) if below is not None else 0.0
        speed = float(np.linalg.norm(twist[:3]) + np.linalg.norm(twist[3:]) * item.bounding_radius) + fall
        onto = f" (falling {gap * 1e3:.3g} mm onto {below})" if below is not None and fall > 0.0 else ""
        if speed * dt > half:
            problems.append(
                StartProblem(
                    "unresolved",
                    (name,),
                    half / speed,
                    f"{name} may move {speed * dt * 1e3:.3g} mm in one step at {speed:.3g} m/s{onto}, more than its "
                    f"smallest half-thickness {half * 1e3:.3g} mm: it can pass through a surface unseen; "
                    f"dt <= {half / speed:.3g} s resolves it",
                    half,
                )
            )
        resting = (item.mass * gravity / law.stiffness) ** (1.0 / exponent) if below is not None else 0.0
        stopping = ((exponent + 1.0) * item.mass * speed**2 / (2.0 * law.stiffness)) ** (1.0 / (exponent + 1.0))
        sink = max(resting, stopping)
        if sink > max_depth:
            problems.append(
                StartProblem(
                    "unresolved",
                    (name,),
                    0.0,
                    f"{name} sinks {sink * 1e3:.3g} mm into what it meets{onto} (contact stiffness "
                    f"{law.stiffness:.3g}), more than max_penetration {max_depth * 1e3:.3g} mm, where a run is "
                    "declared diverged: stiffen the contact or drop it from lower",
                    half,
                )
            )
        elif sink > half:
            problems.append(
                StartProblem(
                    "unresolved",
                    (name,),
                    0.0,
                    f"{name} sinks {sink * 1e3:.3g} mm into what it meets (contact stiffness {law.stiffness:.3g}), "
                    f"more than its smallest half-thickness {half * 1e3:.3g} mm: stiffen the contact or make it larger",
                    half,
                )
            )
    return problems


def _half_thickness(item: RigidObject) -> float:
    """The smallest half-thickness [m] of the shapes an object collides with (a decomposed mug's walls, not its hull).

    Half the smallest edge of each shape's bounding box in the body frame.
    """
    halves = []
    for shape in item.collision_shapes():
        shape.computeLocalAABB()
        halves.append(0.5 * float(np.min(shape.aabb_local.max_ - shape.aabb_local.min_)))
    return min(halves)


def _gap(scene: Scene, shape: coal.CollisionGeometry, pose) -> tuple[float, str | None]:
    """Distance [m] from an object down to the nearest environment shape below it, and that shape's name.

    Below: the shape's nearest point lies within 60 deg of straight down from the object's centre.  ``(inf, None)``
    if none does (no environment, no gravity, or only walls beside or above it).
    """
    gravity = np.asarray(scene.hand.gravity, dtype=float)
    nearest, name = math.inf, None
    if not np.any(gravity):
        return nearest, name
    down = gravity / np.linalg.norm(gravity)
    transform = coal.Transform3s(pose.rotation, pose.translation)
    for geom, env_name in zip(scene.environment_geometries, scene.environment_names):
        geometry_object = scene.geometry.geometryObjects[geom]
        placement = geometry_object.placement
        result = coal.DistanceResult()
        distance = coal.distance(
            shape,
            transform,
            geometry_object.geometry,
            coal.Transform3s(placement.rotation, placement.translation),
            coal.DistanceRequest(),
            result,
        )
        toward = np.asarray(result.getNearestPoint2()) - pose.translation  # from the object's centre
        below = down @ toward > 0.5 * np.linalg.norm(toward)
        if below and distance < nearest:
            nearest, name = max(distance, 0.0), env_name
    return nearest, name


__all__ = ["START_DEPTH_SHARE", "StartProblem", "StartWarning", "pair_distances", "report", "start_problems", "summary"]
