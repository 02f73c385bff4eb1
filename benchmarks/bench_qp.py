"""Internal-force QP: proxsuite against OSQP and quadprog on the same problems, measured in one run.

proxsuite is persistent and warm-started, OSQP (ADMM) too, quadprog (Goldfarb-Idnani) solves each from scratch.
``ContactForceQP`` runs compiled (``src/force_qp.cpp``) when ``bhgrasp._core`` loads; its Python twin is timed too.
Three frictional point contacts on a sphere (8-facet pyramids, f_min = 1 N) must produce a wrench that drifts
slowly from cycle to cycle, as in a control loop.  Prints microseconds per solve and the ratio to quadprog on
the same problems (compare ratios, not absolute times).  Usage: ``python benchmarks/bench_qp.py [--cycles N]``.
"""

from __future__ import annotations

import argparse
import platform
import time

import numpy as np
import quadprog

from bhgrasp.grasp import ContactForceQP, friction_pyramid, grasp_map

MU, FACETS, F_MIN = 0.5, 8, 1.0


def sphere_grasp(radius: float = 0.04) -> np.ndarray:
    angles = np.radians([90.0, 210.0, 330.0])
    points = radius * np.column_stack((np.cos(angles), np.sin(angles), np.zeros(3)))
    return grasp_map(points, -points / radius, np.zeros(3))


def cone_rows(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Pyramid rows P f <= 0 (every facet of every contact) and normal-force rows e_n f (>= f_min), n contacts."""
    pyramid, _ = friction_pyramid(MU, FACETS)
    blocks = np.zeros((n * len(pyramid), 3 * n))
    normals = np.zeros((n, 3 * n))
    for i in range(n):
        blocks[i * len(pyramid) : (i + 1) * len(pyramid), 3 * i : 3 * i + 3] = pyramid
        normals[i, 3 * i + 2] = 1.0
    return blocks, normals


def quadprog_solve(gmap: np.ndarray, w: np.ndarray) -> np.ndarray:
    """The same QP for quadprog: min 1/2 |f|^2, G f = w, -P f >= 0 per contact, f_n >= f_min."""
    n = gmap.shape[1] // 3
    blocks, normals = cone_rows(n)
    constraints = np.vstack((gmap, -blocks, normals))
    lower = np.concatenate((w, np.zeros(len(blocks)), np.full(n, F_MIN)))
    return quadprog.solve_qp(np.eye(3 * n), np.zeros(3 * n), constraints.T, lower, meq=6)[0]


class OSQPForces:
    """The same QP in OSQP (set up once; each cycle updates the bounds and warm-starts from the last solution)."""

    def __init__(self, gmap: np.ndarray, w: np.ndarray) -> None:
        import osqp
        from scipy import sparse

        n = gmap.shape[1] // 3
        blocks, normals = cone_rows(n)
        self.lower_rest = np.concatenate((np.full(len(blocks), -np.inf), np.full(n, F_MIN)))
        self.upper_rest = np.concatenate((np.zeros(len(blocks)), np.full(n, np.inf)))
        self.solver = osqp.OSQP()
        self.solver.setup(sparse.identity(3 * n, format="csc"), np.zeros(3 * n),
                          sparse.csc_matrix(np.vstack((gmap, blocks, normals))),
                          np.concatenate((w, self.lower_rest)), np.concatenate((w, self.upper_rest)),
                          eps_abs=1e-9, eps_rel=1e-9, polish=True, verbose=False, warm_starting=True)  # fmt: skip

    def solve(self, w: np.ndarray) -> np.ndarray:
        """Forces (3n,) [N] for the wrench ``w``."""
        self.solver.update(l=np.concatenate((w, self.lower_rest)), u=np.concatenate((w, self.upper_rest)))
        return self.solver.solve().x


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--cycles", type=int, default=2000)
    cycles = parser.parse_args().cycles
    gmap = sphere_grasp()
    t = np.arange(cycles) * 1e-3
    wrenches = np.column_stack((0.3 * np.sin(t), 0.2 * np.cos(t), 9.81 * 0.2 + 0.1 * np.sin(2 * t),
                                0.002 * np.sin(t), 0.001 * np.cos(t), 0.0005 * np.sin(3 * t)))  # fmt: skip
    qp = ContactForceQP(3, MU, FACETS, F_MIN)  # compiled (src/force_qp.cpp) when bhgrasp._core loads
    qp.solve(gmap, wrenches[0])  # first solve sets the problem up
    start = time.perf_counter()
    results = [qp.solve(gmap, w) for w in wrenches]
    ours = (time.perf_counter() - start) / cycles * 1e6
    twin = ContactForceQP(3, MU, FACETS, F_MIN, engine="python")
    twin.solve(gmap, wrenches[0])
    start = time.perf_counter()
    for w in wrenches:
        twin.solve(gmap, w)
    python = (time.perf_counter() - start) / cycles * 1e6
    raw = twin._solver._qp  # the bare proxsuite problem: update the equality right-hand side and solve, no wrapper
    rows = twin._solver._rows
    start = time.perf_counter()
    for w in wrenches:
        raw.update(b=rows * w, update_preconditioner=False)
        raw.solve()
    bare = (time.perf_counter() - start) / cycles * 1e6
    start = time.perf_counter()
    reference = [quadprog_solve(gmap, w) for w in wrenches]
    theirs = (time.perf_counter() - start) / cycles * 1e6
    admm = OSQPForces(gmap, wrenches[0])
    admm.solve(wrenches[0])
    start = time.perf_counter()
    osqp_forces = [admm.solve(w) for w in wrenches]
    osqp_time = (time.perf_counter() - start) / cycles * 1e6
    start = time.perf_counter()
    for w in wrenches[: max(1, cycles // 10)]:
        ContactForceQP(3, MU, FACETS, F_MIN).solve(gmap, w)
    cold = (time.perf_counter() - start) / max(1, cycles // 10) * 1e6
    gap = max(float(np.max(np.abs(r.forces.ravel() - f))) for r, f in zip(results, reference))
    osqp_gap = max(float(np.max(np.abs(a - f))) for a, f in zip(osqp_forces, reference))
    iterations = np.mean([r.iterations for r in results])
    print(f"{platform.processor() or platform.machine()}, Python {platform.python_version()}, {cycles} cycles")
    print(f"proxsuite warm-started: {ours:8.1f} us/solve ({iterations:.1f} iterations on average; {qp.engine})")
    print(f"the same, Python twin:  {python:8.1f} us/solve (engine='python')")
    print(f"proxsuite set up cold:  {cold:8.1f} us/solve")
    print(f"bare proxsuite update(b) + solve: {bare:8.1f} us/solve (no input checks, no result object)")
    print(f"OSQP warm-started:      {osqp_time:8.1f} us/solve (eps 1e-9, polished)")
    print(f"quadprog:               {theirs:8.1f} us/solve")
    print(
        f"ratio proxsuite warm / quadprog: {ours / theirs:.2f}; bare / quadprog: {bare / theirs:.2f};"
        f" cold / quadprog: {cold / theirs:.2f}; OSQP / quadprog: {osqp_time / theirs:.2f}"
    )
    print(
        f"largest force difference to quadprog: proxsuite {gap:.2e} N, OSQP {osqp_gap:.2e} N;"
        f" all feasible: {all(r.feasible for r in results)}"
    )


if __name__ == "__main__":
    main()
