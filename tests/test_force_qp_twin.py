"""The compiled internal-force QP (``src/force_qp.cpp``) against its Python twin (``bhgrasp/grasp/_force_qp.py``).

Both run the same three proxsuite dense problems with the same settings and the same state machine; only the
arithmetic of proxsuite differs.  The twin calls proxsuite's Python module, which on an x86 CPU with AVX2 or AVX-512
is a build vectorised for it (``proxsuite_pywrap_avx2``/``_avx512``: wider Eigen packets, FMA), while the compiled
solver uses proxsuite's headers without -march flags (SSE2, like the plain ``proxsuite_pywrap``).  So:

* against the plain module (a subprocess that hides the CPU's vector extensions from proxsuite's loader) the two
  agree bit for bit wherever only proxsuite runs: forces, verdict, status and iterations of every random request
  below (each a first solve) and of every cycle of the two-contact loops (whose G of rank 5 never lets the last
  active set answer); the metrics (residual, margins) to round-off, as NumPy's BLAS and Eigen sum G f in different
  orders (<= 1e-14 N).  Where the last active set answers (the QP's optimum from one small Cholesky solve, NumPy's
  and SciPy's in the twin, Eigen's in C++; proxsuite's warm start is left as it was), only those forces differ:
  measured, the same verdict, status and iterations in every cycle, the forces within 8e-14 N, and in the drifting
  loop 2.3e-9 N under OpenBLAS's Haswell kernels, 1.4e-8 N under its AVX-512 ones (active sets whose M M^T is
  ill-conditioned amplify the factorisations' round-off; each answer is still proven optimal to eps_abs; tolerance:
  1e-7 N, as below);
* against the vectorised module, round-off differs, and so do paths now and then (and, its Eigen kernels peeling
  unaligned heads, with the heap's alignment too).  Measured on an AVX-512 machine over the eight 1200-cycle loops
  and 150 random requests below: the same feasible verdict in every cycle; forces within 1.3e-13 N (|f| ~ 1-10 N),
  except in the drifting loop (2.1e-8 N: its ill-conditioned active sets, as above);
  iteration counts different in 1 % of the feasible cycles (by <= 11) and 16 % of the infeasible ones (by up to
  ~760: whether and when the QP's infeasibility certificate fires within max_iter is decided by tests at their
  threshold), the same in total to 0.1 %; the QP's status PROXQP_PRIMAL_INFEASIBLE against PROXQP_MAX_ITER_REACHED
  in 2 to 6 of the 9,600 loop cycles, all infeasible and answered by the same nearest forces (to 5e-16 N).

Tolerance on the forces against the vectorised module: 1e-7 N.  Each solve stops when the residuals are below
eps_abs = 1e-9 and the duality gap below 1e-9 + 1e-12 |objective|; the two runs follow the same iterates up to
round-off (differences ~1e-14 N), and when a stopping test flips they stop one or more iterations apart, each within
the stopping tolerance of the unique optimum (H = I is strongly convex): about eps_abs times the conditioning of the
active constraints (<= 100 for these grasps), 1e-7 N.  Not covered: a nearest problem that ends at max_iter (e.g.
warm-started across a large jump of the grasp map) returns a projected iterate, not an optimum, and the engines'
differ more (5e-5 N once in 6000 random jumps); the loops below change slowly, as a control loop does.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import bhgrasp
import bhgrasp.grasp.forces as grasp_forces
from bhgrasp import _native
from bhgrasp.errors import CompiledEngineUnavailable, InputError
from bhgrasp.grasp import ContactForceQP, default_torque_scale, friction_cone_edges, grasp_map

core = pytest.importorskip("bhgrasp._core")

FORCE_TOLERANCE = 1e-7  # [N] against the vectorised proxsuite module (module docstring)
METRIC_TOLERANCE = 1e-12  # [N, N m] residuals, margins: NumPy's BLAS and Eigen sum G f in different orders
INFEASIBLE_STATUSES = {"PROXQP_PRIMAL_INFEASIBLE", "PROXQP_MAX_ITER_REACHED"}


def sphere_contacts(angles, radius=0.04, tilt=0.0):
    """Contacts at ``angles`` [rad] on a sphere's circle of latitude -tilt, normals towards the centre."""
    angles = np.asarray(angles, dtype=float)
    points = radius * np.column_stack(
        (np.cos(angles) * np.cos(tilt), np.sin(angles) * np.cos(tilt), np.full(len(angles), -np.sin(tilt)))
    )
    return grasp_map(points, -points / radius, np.zeros(3))


def spread(n):
    return 2 * np.pi * np.arange(n) / n + 0.3


def loop_wrench(s):
    """A vertical force that swings between pushing down and lifting, with side forces and torques [N, N m]."""
    return np.array(
        [
            0.5 * np.sin(6 * s),
            0.3 * np.sin(4 * s),
            3.0 * np.sin(6 * np.pi * s),
            0.01 * np.cos(5 * s),
            0.004 * np.sin(3 * s),
            0.002,
        ]
    )


def two_contact_wrench(gmap):
    """G f for forces whose tangential part swings from inside to far outside the cones; two contacts 137 deg apart
    can squeeze only along the line between them, 21.5 deg off their normals, outside cones of mu < 0.39."""

    def wrench(s):
        slope = 0.8 * (1.0 + np.sin(2 * np.pi * 3 * s))  # |f_t| / f_n in [0, 1.6]
        normal = 2.0 + 1.5 * np.cos(2 * np.pi * 2 * s)
        angle = 4 * s
        forces = [[slope * normal * np.cos(angle + k), slope * normal * np.sin(angle + k), normal] for k in (0, 1)]
        return gmap @ np.ravel(forces)

    return wrench


def antipodal_wrench(s):
    """Two antipodal contacts on the equator: feasible exactly when the torque about their axis is 0 (half the
    time: a gated axial torque), whatever the forces (squeezing buys friction)."""
    axis = np.array([np.cos(0.3), np.sin(0.3), 0.0])
    across = np.cross(axis, [0.0, 0.0, 1.0])
    axial = 0.01 * max(0.0, np.sin(2 * np.pi * 3 * s))
    torque = axial * axis + 0.004 * np.cos(5 * s) * across + np.array([0.0, 0.0, 0.002])
    return np.concatenate(([0.5 * np.sin(6 * s), 0.2, 3.0 * np.sin(6 * np.pi * s)], torque))


def drifting_grasp(s):
    """Three contacts that slide slowly around and across the equator (the grasp map changes every cycle)."""
    return sphere_contacts(
        spread(3) + 0.1 * np.sin(2 * np.pi * s * np.array([1.0, 2.0, 3.0])), tilt=-0.6 + 0.9 * np.sin(np.pi * s) ** 2
    )


def loops():
    """(name, n, mu, f_min, G or G(s), wrench(s)), s in [0, 1): control loops that cross in and out of feasibility."""
    two = sphere_contacts([0.3, 0.3 + 2.4], tilt=-0.2)
    return [
        ("2 contacts 137 deg apart, mu 0.3", 2, 0.3, 1.0, two, two_contact_wrench(two)),
        ("2 contacts, antipodal", 2, 0.8, 1.0, sphere_contacts(spread(2)), antipodal_wrench),
        ("3 above the equator, mu 0.3", 3, 0.3, 1.0, sphere_contacts(spread(3), tilt=-0.6), loop_wrench),
        ("3 above the equator, mu 0.6", 3, 0.6, 1.0, sphere_contacts(spread(3), tilt=-0.6), loop_wrench),
        ("3 below the equator, mu 1", 3, 1.0, 0.5, sphere_contacts(spread(3), tilt=0.3), loop_wrench),
        ("3 frictionless", 3, 0.0, 1.0, sphere_contacts(spread(3), tilt=0.4), loop_wrench),
        ("4 above the equator, mu 0.5", 4, 0.5, 1.0, sphere_contacts(spread(4), tilt=-0.5), loop_wrench),
        ("3 drifting contacts, mu 0.4", 3, 0.4, 1.0, drifting_grasp, loop_wrench),
    ]


def random_requests(count, seed=0):
    """(G, w, mu, f_min, desired): random grasps of 2-4 contacts; wrenches from forces inside the cones
    (feasible), random ones (mostly infeasible) and degenerate ones (every contact on a pyramid edge at f_min)."""
    rng = np.random.default_rng(seed)
    for k in range(count):
        n = int(rng.integers(2, 5))
        directions = rng.normal(size=(n, 3))
        directions /= np.linalg.norm(directions, axis=1, keepdims=True)
        normals = -directions + 0.4 * rng.normal(size=(n, 3))
        normals /= np.linalg.norm(normals, axis=1, keepdims=True)
        gmap = grasp_map(rng.uniform(0.02, 0.06) * directions, normals, np.zeros(3))
        mu = 0.0 if k % 10 == 0 else float(rng.uniform(0.0, 1.0))
        f_min = float(rng.choice([0.0, 0.5, 1.0]))
        edges = friction_cone_edges(mu, 8)
        if k % 3 == 0:
            wrench = np.concatenate((rng.normal(scale=2.0, size=3), rng.normal(scale=0.05, size=3)))
        elif k % 3 == 1:
            normal = f_min + rng.uniform(0.0, 3.0, n)
            forces = normal[:, None] * edges[rng.integers(8, size=n)] / edges[0, 2] * rng.uniform(0.0, 1.0, (n, 1))
            forces[:, 2] = normal
            wrench = gmap @ forces.ravel()
        else:
            f_min = max(f_min, 0.5)
            wrench = gmap @ (f_min * edges[rng.integers(8, size=n)] / edges[0, 2]).ravel()
        desired = None if k % 2 else np.tile([0.0, 0.0, 3.0], (n, 1))
        yield gmap, wrench, mu, f_min, desired


def lockstep(cycles=1200, requests=150):
    """Every loop and the random requests through both engines: per case, the largest force difference [N], the
    cycles whose verdict, status, iterations or any metric differ, and the feasible and infeasible counts."""
    summary = {}
    for name, n, mu, f_min, gmap, wrench in loops():
        compiled = ContactForceQP(n, mu, min_normal_force=f_min, engine="compiled")
        python = ContactForceQP(n, mu, min_normal_force=f_min, engine="python")
        desired = np.tile([0.0, 0.0, 3.0], (n, 1))
        pairs = []
        for s in np.arange(cycles) / cycles:
            g = gmap(s) if callable(gmap) else gmap
            pairs.append((compiled.solve(g, wrench(s), desired), python.solve(g, wrench(s), desired)))
        summary[name] = compare(pairs)
    pairs = []
    for gmap, wrench, mu, f_min, desired in random_requests(requests):
        n = gmap.shape[1] // 3
        pairs.append(
            tuple(
                ContactForceQP(n, mu, min_normal_force=f_min, engine=engine).solve(gmap, wrench, desired)
                for engine in ("compiled", "python")
            )
        )
    summary["random requests"] = compare(pairs)
    return summary


def compare(pairs):
    metrics = max(
        max(
            float(np.max(np.abs(a.wrench_error - b.wrench_error))),
            abs(a.wrench_residual - b.wrench_residual),
            abs(a.cone_violation - b.cone_violation),
            abs(a.normal_margin - b.normal_margin),
        )
        for a, b in pairs
    )
    return {
        "forces": max(float(np.max(np.abs(a.forces - b.forces))) for a, b in pairs),
        "force_bits": sum(not np.array_equal(a.forces, b.forces) for a, b in pairs),
        "metrics": metrics,
        "feasible": sum(a.feasible != b.feasible for a, b in pairs),
        "status": [(a.status, b.status) for a, b in pairs if a.status != b.status],
        "iterations": [a.iterations - b.iterations for a, b in pairs if a.iterations != b.iterations],
        "verdicts": [sum(a.feasible for a, _ in pairs), sum(not a.feasible for a, _ in pairs)],
    }


@pytest.fixture(scope="module")
def summary():
    return lockstep()


def test_every_loop_crosses_feasibility(summary):
    for name, case in summary.items():
        feasible, infeasible = case["verdicts"]
        if name == "3 frictionless":
            assert feasible == 0, name  # the weight needs friction
        elif name == "3 below the equator, mu 1":
            assert infeasible == 0, name  # the feasible-only loop
        else:
            assert feasible >= 40 and infeasible >= 40, (name, case["verdicts"])


def test_the_engines_agree_against_the_vectorised_proxsuite(summary):
    for name, case in summary.items():
        assert case["feasible"] == 0, name
        assert case["forces"] <= FORCE_TOLERANCE, (name, case["forces"])
        assert case["metrics"] <= 10 * FORCE_TOLERANCE, (name, case["metrics"])  # |G| <= ~3 here
        for compiled, python in case["status"]:  # only whether an infeasible QP's certificate fired in time
            assert {compiled, python} <= INFEASIBLE_STATUSES, (name, compiled, python)
        assert len(case["status"]) <= 0.01 * sum(case["verdicts"]), name


PLAIN_PROXSUITE = """
import json, sys, types
fake = types.ModuleType("proxsuite.instructionset")  # proxsuite's loader then picks the plain proxsuite_pywrap
fake.has_AVX512F = fake.has_AVX2 = lambda: False
sys.modules["proxsuite.instructionset"] = fake
import proxsuite
if proxsuite._submodule.__name__ != "proxsuite.proxsuite_pywrap":
    print(json.dumps(None))
else:
    sys.path.insert(0, sys.argv[1])
    import test_force_qp_twin
    print(json.dumps(test_force_qp_twin.lockstep()))
"""


@pytest.mark.slow  # 15 s
def test_the_engines_agree_bit_for_bit_against_the_plain_proxsuite():
    """Same arithmetic (proxsuite without vector extensions on both sides): identical where proxsuite alone runs."""
    run = subprocess.run(
        [sys.executable, "-c", PLAIN_PROXSUITE, str(Path(__file__).parent)],
        capture_output=True,
        text=True,
        check=True,
        timeout=600,
    )
    summary = json.loads(run.stdout.strip().splitlines()[-1])
    if summary is None:
        pytest.skip("proxsuite's plain module proxsuite_pywrap cannot be selected")
    for name, case in summary.items():
        assert case["feasible"] == 0 and case["status"] == [], (name, case)
        if name == "random requests" or name.startswith("2 contacts"):  # proxsuite alone
            assert case["forces"] == 0.0 and case["force_bits"] == 0, (name, case)
            assert case["iterations"] == [] and case["metrics"] <= METRIC_TOLERANCE, (name, case)
        else:  # the last active set's Cholesky solves round differently (module docstring)
            assert case["forces"] <= FORCE_TOLERANCE and case["metrics"] <= FORCE_TOLERANCE, (name, case)
            assert case["iterations"] == [], (name, case)


def test_torque_scale_has_the_bits_of_default_torque_scale():
    rng = np.random.default_rng(0)
    for k in range(3000):
        n = int(rng.integers(1, 7))
        gmap = rng.normal(size=(6, 3 * n)) * 10 ** rng.uniform(-4, 2)
        if k % 5 == 0:
            gmap[3:, :3] = 0.0  # a contact at the reference
        assert grasp_forces._torque_scale(gmap) == default_torque_scale(gmap)
    assert grasp_forces._torque_scale(np.vstack((np.eye(3, 9), np.zeros((3, 9))))) == 1.0


def test_the_constants_are_the_same():
    for name in (
        "NEAREST_WEIGHT",
        "PRIMAL_INFEASIBILITY",
        "DOUBTFUL_ERROR",
        "DUALITY_GAP_REL",
        "FEASIBLE_RESIDUAL",
        "ADMISSIBLE_TOLERANCE",
        "CHECK_ITER",
        "ACTIVE_TOLERANCE",
        "FULL_RANK",
    ):
        assert getattr(core.ContactForceQP, name) == getattr(grasp_forces, name), name


def test_engine_selection(monkeypatch):
    assert ContactForceQP(3, 0.5).engine == "compiled"
    assert ContactForceQP(3, 0.5, engine="python").engine == "python"
    with pytest.raises(InputError, match="`engine` must be one of"):
        ContactForceQP(3, 0.5, engine="c++")
    monkeypatch.setattr(_native, "DEFAULT_ENGINE", "c")
    with pytest.raises(InputError, match="BHGRASP_ENGINE='c': expected one of"):
        ContactForceQP(3, 0.5)
    monkeypatch.setattr(_native, "DEFAULT_ENGINE", "compiled")
    monkeypatch.delattr(bhgrasp, "_core")  # the core does not load: no silent fallback
    monkeypatch.setitem(sys.modules, "bhgrasp._core", None)
    for engine in (None, "compiled"):
        with pytest.raises(CompiledEngineUnavailable, match="engine='python' for one object"):
            ContactForceQP(3, 0.5, engine=engine)
    assert ContactForceQP(3, 0.5, engine="python").engine == "python"
    monkeypatch.setattr(_native, "DEFAULT_ENGINE", "python")  # BHGRASP_ENGINE=python
    assert ContactForceQP(3, 0.5).engine == "python"


@pytest.mark.parametrize("engine", ["compiled", "python"])
def test_the_last_active_set_answers_most_cycles_with_the_qps_optimum(engine):
    """On the drifting loop the last solved call's active set answers most feasible cycles (0 proxsuite iterations,
    the faces the forces sit on change now and then); each such answer is the optimum of the same QP solved from
    scratch by a new solver (proxsuite alone), to the solvers' tolerance, and meets the wrench and the pyramids."""
    _, n, mu, f_min, gmap, wrench = loops()[-1]
    assert callable(gmap)
    qp = ContactForceQP(n, mu, min_normal_force=f_min, engine=engine)
    desired = np.tile([0.0, 0.0, 3.0], (n, 1))
    shortcut = solved_by_proxsuite = 0
    for s in np.arange(600) / 600:
        g, w = gmap(s), wrench(s)
        result = qp.solve(g, w, desired)
        if result.iterations == 0:
            fresh = ContactForceQP(n, mu, min_normal_force=f_min, engine=engine).solve(g, w, desired)
            assert result.status == "PROXQP_SOLVED" and result.feasible and fresh.feasible, s
            np.testing.assert_allclose(result.forces, fresh.forces, rtol=0, atol=FORCE_TOLERANCE, err_msg=f"s = {s}")
            # proven to eps_abs = 1e-9 per scaled row: the unscaled 2-norm and the exact cone within a few times that
            assert result.wrench_residual <= 1e-8 and max(result.cone_violation, -result.normal_margin) <= 1e-8
            shortcut += 1
        else:
            solved_by_proxsuite += result.feasible
    assert shortcut > 300 and solved_by_proxsuite >= 10, (shortcut, solved_by_proxsuite)
