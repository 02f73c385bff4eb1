"""A scene that starts wrong says so before its first step, and a run that diverges from it names why.

Truths: the depth of a hand placed inside a plane (the plane's distance of its links, from coal apart); the step a
falling 1 um box needs, h / sqrt(2 g gap); the sag of a heavy box on a soft contact, m g / k; scenes that start
right (the demo, a box resting at its static depth) report nothing.
"""

from __future__ import annotations

import math
import warnings

import coal
import numpy as np
import pinocchio as pin
import pytest
from scenes import G, far_hand

import bhgrasp as bh
from bhgrasp.errors import InputError, SimulationDiverged
from bhgrasp.model.objects import Box, Plane, table
from bhgrasp.scenarios.box_grasp import box_grasp
from bhgrasp.sim.scene import Scene
from bhgrasp.sim.simulator import Simulator
from bhgrasp.sim.start_check import StartWarning
from bhgrasp.sim.state_check import coordinate_owner

TILT = 0.3  # [rad] the plane's tilt about y


def hand_in_a_tilted_plane(engine: str, start_check: str = "warn") -> Simulator:
    """The BH8-280 at the origin, fingers up, a plane tilted 0.3 rad whose solid side reaches 170 mm up its normal."""
    normal = np.array([math.sin(TILT), 0.0, math.cos(TILT)])
    plane = Plane(normal=normal, offset=0.17, name="incline")
    scene = Scene(bh.BarrettHand(gravity=(0.0, 0.0, -G)), [], [plane])
    return Simulator(scene, engine=engine, start_check=start_check)


@pytest.mark.parametrize("engine", ["python", "compiled"])
def test_a_hand_started_inside_a_plane_is_named_and_so_is_its_divergence(engine: str) -> None:
    simulator = hand_in_a_tilted_plane(engine)
    depths = plane_depths(simulator.scene)  # closed form, per link
    deep = sorted((d, link) for link, d in depths.items() if d > 0.005)
    with pytest.warns(StartWarning, match=rf"{len(deep)} body pairs start interpenetrated deeper than 5 mm") as caught:
        state = simulator.initial_state()
    assert f"{deep[-1][1]} {deep[-1][0] * 1e3:.3g} mm inside incline" in str(caught[0].message)
    problems = simulator.check_start(state)
    assert sorted(p.bodies[1] for p in problems) == sorted(link for _, link in deep)
    for problem in problems:
        assert problem.bodies[0] == "incline"
        assert problem.value == pytest.approx(depths[problem.bodies[1]], rel=1e-9)
    cause = r"\(coordinate 2, joint F1_distal\) = [0-9.e+]+; likely because .* start interpenetrated"
    with pytest.raises(SimulationDiverged, match=cause):
        simulator.run(lambda t, s: np.zeros(8), 0.01, state=state, progress=False)


def plane_depths(scene: Scene) -> dict[str, float]:
    """Each moving hand link's deepest overlap with the plane at the neutral pose, d - min n.x over its shapes.

    In closed form: a box's corner furthest along -n, a sphere's point, a cylinder's rim point (axis a, radius r,
    half-length h: c.n - r sqrt(1 - (a.n)^2) - h |a.n|).
    """
    plane = scene.environment[0]
    n = plane.normal
    data = scene.model.createData()
    geometry_data = pin.GeometryData(scene.geometry)
    pin.updateGeometryPlacements(scene.model, data, scene.geometry, geometry_data, pin.neutral(scene.model))
    depths: dict[str, float] = {}
    for index in scene.hand_geometries:
        item = scene.geometry.geometryObjects[index]
        if item.parentJoint == 0:
            continue  # the palm: fixed, the environment does not collide with it
        placement, shape = geometry_data.oMg[index], item.geometry
        centre = placement.translation @ n
        if isinstance(shape, coal.Box):
            lowest = centre - np.abs(placement.rotation.T @ n) @ shape.halfSide
        elif isinstance(shape, coal.Sphere):
            lowest = centre - shape.radius
        else:
            along = float(placement.rotation[:, 2] @ n)
            lowest = centre - shape.radius * math.sqrt(max(1.0 - along * along, 0.0)) - shape.halfLength * abs(along)
        link = scene.model.frames[item.parentFrame].name
        depths[link] = max(depths.get(link, -math.inf), plane.offset - lowest)
    return depths


def test_the_start_check_warns_raises_or_stays_quiet_by_option() -> None:
    with pytest.raises(InputError, match=r"starts wrong: .* \(Simulator\(start_check='warn'\) runs it anyway\)"):
        hand_in_a_tilted_plane("compiled", "error").initial_state()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        hand_in_a_tilted_plane("compiled", "off").initial_state()
    with pytest.raises(InputError, match="`start_check` must be one of"):
        Simulator(Scene(far_hand()), start_check="loud")
    assert hand_in_a_tilted_plane("compiled").with_settings(start_check="off").settings.start_check == "off"


def test_a_box_too_small_for_dt_is_named_with_the_dt_it_needs() -> None:
    """A 1 um box 1 mm above the table reaches sqrt(2 g gap) = 0.14 m/s: dt must be h / u = 3.6 us, not 1 ms."""
    tiny = Box(size=(1e-6,) * 3, density=1000.0, pose=pin.SE3(np.eye(3), np.array([0.0, 0.0, 1e-3])), name="speck")
    simulator = Simulator(Scene(far_hand((0.0, 0.0, -G)), [tiny], [table()]))
    with pytest.warns(StartWarning, match=r"speck may move 0\.14 mm in one step .* dt <= 3\.57e-06 s resolves it"):
        state = simulator.initial_state()
    (problem,) = simulator.check_start(state)
    half, gap = 0.5e-6, 1e-3 - 0.5e-6
    assert problem.value == pytest.approx(half / math.sqrt(2 * G * gap), rel=1e-6)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        simulator.with_settings(dt=0.9 * problem.value).initial_state()  # a step that resolves it: nothing to say


def test_a_heavy_box_on_a_soft_contact_is_named_with_its_sag() -> None:
    """10 kg on k = 1e4 N/m sinks m g / k = 9.81 mm, more than the 5 mm half-thickness of a 10 mm slab."""
    slab = Box(size=(0.1, 0.1, 0.01), mass=10.0, pose=pin.SE3(np.eye(3), np.array([0.0, 0.0, 0.005])), name="slab")
    simulator = Simulator(Scene(far_hand((0.0, 0.0, -G)), [slab], [table()]))
    with pytest.warns(StartWarning, match=r"slab sinks 9\.81 mm into what it meets .* half-thickness 5 mm"):
        simulator.initial_state()


def test_a_can_dropped_onto_a_soft_contact_is_named_before_it_diverges() -> None:
    """0.35 kg falling 0.3 m reaches u = sqrt(2 g 0.3) = 2.43 m/s and stops u sqrt(m / k) = 14.4 mm deep on k = 1e4
    N/m: under its 33 mm half-width but past a max_penetration of 10 mm, where the run would be declared diverged."""
    can = bh.Cylinder(radius=0.033, length=0.1, mass=0.35, pose=pin.SE3(np.eye(3), np.array([0.0, 0.0, 0.35])))
    simulator = Simulator(Scene(far_hand((0.0, 0.0, -G)), [can], [table()]), max_penetration=0.01)
    stop = math.sqrt(2 * G * 0.3) * math.sqrt(0.35 / 1e4)
    with pytest.warns(StartWarning, match=rf"sinks {stop * 1e3:.3g} mm .* more than max_penetration 10 mm"):
        simulator.initial_state()


def test_scenes_that_start_right_say_nothing() -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        setup = box_grasp()  # the demo: fingers open, the box on its pedestal
        assert setup.simulator.check_start(setup.state) == []
        resting = Box(size=(0.06, 0.05, 0.05), mass=0.2, pose=pin.SE3(np.eye(3), np.array([0.0, 0.0, 0.0248])))
        simulator = Simulator(Scene(far_hand((0.0, 0.0, -G)), [resting], [table()]))
        assert simulator.check_start(simulator.initial_state()) == []


def test_a_coordinate_is_named_by_its_joint_or_object() -> None:
    scene = Scene(far_hand(), [Box(size=(0.1,) * 3, mass=1.0, name="crate")])
    assert coordinate_owner(scene, 0, velocity=True) == "joint F1_spread"
    assert coordinate_owner(scene, scene.nv_hand + 4, velocity=True) == "object crate"
    assert coordinate_owner(scene, scene.nq_hand + 6, velocity=False) == "object crate"


def test_the_fall_is_measured_to_what_lies_below_not_to_a_wall_beside() -> None:
    """A box 0.45 m over the table with a wall 25 mm to its side falls onto the table: u = sqrt(2 g 0.45)."""
    box = Box(size=(0.05,) * 3, mass=0.3, pose=pin.SE3(np.eye(3), np.array([0.0, 0.0, 0.475])), name="crate")
    wall = bh.FixedBox(size=(0.02, 0.4, 1.0), pose=pin.SE3(np.eye(3), np.array([0.06, 0.0, 0.5])), name="wall")
    law = bh.SpringDamper(stiffness=1e3)  # soft: it stops u sqrt(m / k) = 51 mm deep, past max_penetration
    simulator = Simulator(Scene(far_hand((0.0, 0.0, -G)), [box], [table(), wall]), contact=law, start_check="off")
    (problem,) = simulator.check_start(simulator.initial_state())
    stop = math.sqrt(2 * G * 0.45) * math.sqrt(0.3 / 1e3)
    assert f"sinks {stop * 1e3:.3g} mm into what it meets (falling 450 mm onto table)" in problem.message


def test_a_name_with_braces_does_not_break_the_divergence_message() -> None:
    from types import SimpleNamespace

    from bhgrasp.sim.settings import SimulatorSettings
    from bhgrasp.sim.start_check import StartProblem
    from bhgrasp.sim.state_check import describe_divergence

    problem = StartProblem("unresolved", ("cup {big}",), 0.0, "cup {big} sinks 30 mm", 0.01)
    record = SimpleNamespace(kind=3, index=0, value=250.0)
    error = describe_divergence(0.001, record, SimulatorSettings(), None, (problem,))
    assert "likely because the scene starts wrong: cup {big} sinks 30 mm" in str(error)


@pytest.mark.parametrize(("integrator", "bound"), [("semi-implicit", 2.0), ("rk4", 2.0 * math.sqrt(2.0))])
def test_a_contact_too_stiff_for_an_explicit_step_is_named_with_the_dt_it_needs(integrator: str, bound: float) -> None:
    """A 10 g box on k = 1e6 N/m rings at omega = sqrt(k / m) = 1e4 rad/s: at dt = 1 ms far past the explicit
    steps' stability bounds (omega dt < 2, and 2 sqrt(2) for RK4); the implicit step has none."""
    box = Box(size=(0.02,) * 3, mass=0.01, pose=pin.SE3(np.eye(3), np.array([0.0, 0.0, 0.01])), name="die")
    law = bh.SpringDamper(stiffness=1e6, damping=1.0)
    scene = Scene(far_hand((0.0, 0.0, -G)), [box], [table()])
    explicit = Simulator(scene, contact=law, integrator=integrator, start_check="off")
    (problem,) = [p for p in explicit.check_start(explicit.initial_state()) if p.kind == "too stiff"]
    assert problem.value == pytest.approx(bound / 1e4, rel=1e-12)
    assert f"dt < {bound / 1e4:.3g} s" in problem.message
    implicit = Simulator(scene, contact=law, start_check="off")
    assert [p for p in implicit.check_start(implicit.initial_state()) if p.kind == "too stiff"] == []
