"""The implicit step's velocity system by parts (bhgrasp/sim/part_system.py, src/part_system.cpp).

Truths: the dense solve of the same system (NumPy's LAPACK), and the dense step of the same scene; the compiled
sparse step against its Python twin in lockstep, as tests/test_compiled.py holds the dense steps.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
import scipy.sparse as sparse
from test_compiled import assert_agree, lockstep

from bhgrasp.errors import InputError
from bhgrasp.model.objects import Box, Sphere, table
from bhgrasp.scenarios.box_grasp import box_grasp
from bhgrasp.sim import Simulator
from bhgrasp.sim.actuation import BarrettActuation
from bhgrasp.sim.part_system import PartSystem, block_diagonal
from bhgrasp.sim.scene import Scene
from bhgrasp.sim.settings import SPARSE_FROM, SimulatorSettings


def random_spd(rng: np.random.Generator, n: int) -> np.ndarray:
    a = rng.normal(size=(n, n))
    return a @ a.T + n * np.eye(n)


def test_the_system_by_parts_solves_as_the_dense_system() -> None:
    """A hand of 8 velocities driven through a 4-column transmission, five 6-velocity objects, contacts joining the
    hand and objects, two objects, an object and the world, and two points of the hand: the same v+ as the dense
    T^T (A + s sum J^T G J) T w = T^T b, v+ = T w."""
    rng = np.random.default_rng(3)
    sizes = [8, 6, 6, 6, 6, 6]
    starts = np.cumsum([0, *sizes])
    nv = int(starts[-1])
    blocks = [random_spd(rng, n) for n in sizes]
    transmission = np.zeros((8, 4))
    transmission[[0, 1, 2, 3, 4, 5, 6, 7], [0, 1, 1, 2, 2, 3, 3, 3]] = [1.0, 1.0, 0.3, 1.0, 0.3, 1.0, 0.3, 0.5]
    touching = [(0, 1), (1, 2), (2, None), (0, 0), (3, 5), (0, 4), (4, None)]
    jacobians = np.zeros((len(touching), 3, nv))
    for i, (b, a) in enumerate(touching):
        jacobians[i, :, starts[b] : starts[b + 1]] += rng.normal(size=(3, sizes[b]))
        if a is not None:
            jacobians[i, :, starts[a] : starts[a + 1]] -= rng.normal(size=(3, sizes[a]))
    gains = np.array([g @ g.T for g in rng.normal(size=(len(touching), 3, 3))])
    gains[3] = 0.0  # a contact that is off (the compiled twin keeps its entries in the pattern)
    rhs, scale = rng.normal(size=nv), 0.01
    system = PartSystem()
    system.begin(transmission, block_diagonal(blocks))
    stacked = sparse.csr_array(jacobians.reshape(-1, nv))
    by_parts = system.solve(stacked, gains, scale, rhs)
    full = np.zeros((nv, 4 + nv - 8))
    full[:8, :4], full[8:, 4:] = transmission, np.eye(nv - 8)
    dense = np.zeros((nv, nv))
    for block, start, n in zip(blocks, starts, sizes):
        dense[start : start + n, start : start + n] = block
    dense += scale * np.einsum("mki,mkl,mlj->ij", jacobians, gains, jacobians)
    expected = full @ np.linalg.solve(full.T @ dense @ full, full.T @ rhs)
    np.testing.assert_allclose(by_parts, expected, rtol=0, atol=1e-12 * np.abs(expected).max())


def grasp_beside_a_pile(engine: str, linear_solver: str) -> tuple[Simulator, np.ndarray]:
    """The Barrett hand closing on a box on its pedestal (scenarios.box_grasp) beside eight boxes dropped onto a table
    and three spheres dropped onto three of them; its start configuration."""
    setup = box_grasp(mass=0.3, actuation="barrett")
    scene = setup.simulator.scene
    objects = list(scene.objects)
    for i in range(8):
        centre = np.array([0.25 + 0.05 * (i % 4), 0.05 * (i // 4) - 0.05, 0.016])  # 1 mm above the table
        objects.append(Box(size=(0.03,) * 3, mass=0.1, pose=pin.SE3(np.eye(3), centre)))
        if i % 3 == 1:  # 0.5 mm above the box's top
            on_top = centre + np.array([0.0, 0.0, 0.0305])
            objects.append(Sphere(radius=0.015, mass=0.05, pose=pin.SE3(np.eye(3), on_top)))
    pile = Scene(setup.hand, objects, [*scene.environment, table()])
    simulator = Simulator(
        pile,
        dt=5e-4,
        contact=setup.simulator.law,
        actuation=BarrettActuation(setup.hand),
        engine=engine,
        linear_solver=linear_solver,
    )
    return simulator, setup.q_start


CLOSE = np.array([0.02, 0.11, 0.11, 0.11])  # the Barrett motors' torques [N m]: spread, F1, F2, F3


@pytest.mark.parametrize("engine", ["python", "compiled"])
def test_a_grasp_beside_a_pile_steps_sparse_as_it_steps_dense(engine: str) -> None:
    """Contacts coming on and off, boxes' patches and spheres' points, the fingers closing on their box through the
    Barrett transmission (its TorqueSwitches breaking away): the sparse and dense steps agree to round-off along the
    whole run."""
    sparse_run, q_start = grasp_beside_a_pile(engine, "sparse")
    dense_run, _ = grasp_beside_a_pile(engine, "dense")
    state_s = state_d = sparse_run.initial_state(q_start)
    most = 0
    for _ in range(600):
        state_s, info_s = sparse_run.step(state_s, CLOSE)
        state_d, info_d = dense_run.step(state_d, CLOSE)
        np.testing.assert_array_equal(info_s.contacts.pair, info_d.contacts.pair)
        np.testing.assert_array_equal(info_s.contacts.sticking, info_d.contacts.sticking)
        np.testing.assert_array_equal(state_s.actuation_modes, state_d.actuation_modes)
        for a, b in [
            (state_s.scene_q, state_d.scene_q),
            (state_s.scene_v, state_d.scene_v),
            (info_s.contacts.force, info_d.contacts.force),
            (info_s.drive_torques, info_d.drive_torques),
        ]:  # round-off: 1e-10 of the largest entry (or of 1)
            np.testing.assert_allclose(a, b, rtol=0, atol=1e-10 * max(1.0, np.abs(b).max(initial=0.0)))
        most = max(most, len(info_s.contacts))
    assert most >= 40, f"the scene should reach 40 contacts, got {most}"
    assert (state_s.actuation_modes[:3] == 1).all(), "the TorqueSwitches should have broken away"


def test_the_compiled_sparse_step_is_its_python_twin() -> None:
    """The lockstep of tests/test_compiled.py on the grasp beside a pile, both engines solving sparse; the compiled
    engine's broad phase sweeps (128 pairs or more, src/engine.hpp), the Python one tests every pair's spheres."""
    simulator, q_start = grasp_beside_a_pile("python", "sparse")
    assert simulator.settings.solves_sparse(simulator.scene.nv) and len(simulator.scene.pairs) >= 128
    assert_agree(lockstep(simulator, lambda t, s: CLOSE, 400, simulator.initial_state(q_start)), 40)


def test_the_jacobians_by_parts_are_the_dense_ones() -> None:
    """The stacked sparse Jacobians of the contacts (fingers on the box, the box on its pedestal, boxes on the table,
    spheres on boxes) hold the dense Jacobians' values, column for column."""
    simulator, q_start = grasp_beside_a_pile("python", "sparse")
    state = simulator.initial_state(q_start)
    for _ in range(300):
        state, _ = simulator.step(state, CLOSE)
    engine = simulator.engine.contacts
    contacts = engine.detect(state.scene_q, state.contact_memory)
    simulator.engine.parts.compute_joint_jacobians(state.scene_q)
    dense = engine.jacobians(contacts).reshape(-1, simulator.scene.nv)
    assert len(contacts) >= 40 and (contacts.pair < len(simulator.scene.pairs)).all()
    np.testing.assert_array_equal(engine.part_jacobians(contacts).toarray(), dense)


def test_the_linear_solver_option_is_checked_and_auto_follows_the_scene_size() -> None:
    with pytest.raises(InputError, match="linear_solver"):
        SimulatorSettings(linear_solver="cholesky")
    with pytest.raises(InputError, match="implicit integrator only"):
        SimulatorSettings(linear_solver="sparse", integrator="rk4")
    auto = SimulatorSettings()
    assert not auto.solves_sparse(SPARSE_FROM - 1) and auto.solves_sparse(SPARSE_FROM)
    assert not SimulatorSettings(integrator="rk4").solves_sparse(10 * SPARSE_FROM)
    assert SimulatorSettings(linear_solver="sparse").solves_sparse(1)
    assert not SimulatorSettings(linear_solver="dense").solves_sparse(10 * SPARSE_FROM)
