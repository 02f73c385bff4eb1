"""The contact detection's kept coal solver (src/narrowphase.cpp) against coal::collide itself, bit for bit.

coal::collide makes a new solver for every query; the compiled engine keeps one and sets it back before each query
to the state a new one starts in.  The truth is coal::collide: the same engine with ``kept_solver`` off calls it.  Two
simulators of one scene, one of each, stepped side by side must give the same bits at every step: a box pinched by
three fingertips, the BH8-280 closing on a box (patches on links and the palm), convex mesh pieces rolling on a
table, and a settled pile of mixed primitives in a bin, pushed about (object-object pairs and walls).
"""

from __future__ import annotations

from collections.abc import Callable

import coal
import numpy as np
from scenes import prism_onto_banana

from bhgrasp.scenarios.box_grasp import box_grasp
from bhgrasp.scenarios.clutter import bin_walls, drop_pile, mixed_objects
from bhgrasp.scenarios.hold import reference_hold
from bhgrasp.sim import Simulator
from bhgrasp.sim.actuation import BarrettActuation

CHECKED = "3.0.3"  # the coal whose collide() src/narrowphase.cpp mirrors (another one runs coal::collide itself)


def coal_collide(simulator: Simulator) -> Simulator:
    """``simulator``'s engine set to let coal::collide make a solver per query (the reference)."""
    native = simulator.engine._engine
    assert native.kept_solver == (coal.__version__ == CHECKED), f"coal {coal.__version__}: re-check the kept solver"
    native.kept_solver = False
    return simulator


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


def test_a_pinched_box_sees_the_same_contacts() -> None:
    kept, reference = reference_hold(), reference_hold()
    coal_collide(reference.simulator)

    def inputs(k, state):
        return kept.controller(state.t, state) * (1.0 + 0.5 * np.sin(k / 40.0)), None

    assert assert_same_bits(kept.simulator, reference.simulator, inputs, 600, kept.state) >= 3


def test_the_barrett_hand_closing_on_a_box_sees_the_same_contacts() -> None:
    setup = box_grasp(mass=0.3, actuation="barrett")

    def simulator() -> Simulator:
        actuation = BarrettActuation(setup.hand, saturate=True)
        return Simulator(setup.simulator.scene, dt=setup.simulator.dt, contact=setup.simulator.law, actuation=actuation)

    kept, reference = simulator(), coal_collide(simulator())
    close = np.array([0.01, 0.02, 0.02, 0.02])  # [N m]
    state = kept.initial_state(setup.q_start)
    assert assert_same_bits(kept, reference, lambda k, s: (close, None), 900, state) >= 6


def test_convex_mesh_pieces_rolling_on_a_table_see_the_same_contacts() -> None:
    kept, reference = prism_onto_banana(), coal_collide(prism_onto_banana())
    state = kept.initial_state()
    assert assert_same_bits(kept, reference, lambda k, s: (np.zeros(8), None), 400, state) >= 4


def test_a_pushed_pile_in_a_bin_sees_the_same_contacts() -> None:
    pile = drop_pile(mixed_objects(6, seed=3), bin_walls(inner=(0.2, 0.16), height=0.1), (-0.08, -0.06, 0.08, 0.06))
    kept = pile.simulator
    reference = coal_collide(Simulator.from_settings(kept.scene, kept.settings, kept.law, kept.actuation))
    pushes = np.random.default_rng(3).normal(scale=2.0, size=(len(pile.objects), 3))  # [N]

    def inputs(k, state):
        return np.zeros(kept.actuation.n_inputs), pushes * np.cos(k / 25.0)

    assert assert_same_bits(kept, reference, inputs, 300, pile.state) >= 10
