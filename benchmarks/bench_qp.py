"""Internal-force QP: proxsuite (persistent, warm-started) against quadprog (Goldfarb-Idnani), measured in one run.

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

from bhgrasp.grasp import friction_pyramid, grasp_map
from bhgrasp.grasp_forces import ContactForceQP

MU, FACETS, F_MIN = 0.5, 8, 1.0


def sphere_grasp(radius: float = 0.04) -> np.ndarray:
    angles = np.radians([90.0, 210.0, 330.0])
    points = radius * np.column_stack((np.cos(angles), np.sin(angles), np.zeros(3)))
    return grasp_map(points, -points / radius, np.zeros(3))


def quadprog_solve(gmap: np.ndarray, w: np.ndarray) -> np.ndarray:
    """The same QP for quadprog: min 1/2 |f|^2, G f = w, -A f >= 0 per contact, f_n >= f_min."""
    n = gmap.shape[1] // 3
    pyramid, _ = friction_pyramid(MU, FACETS)
    rows = [gmap]
    lower = [w]
    blocks = np.zeros((n * len(pyramid), 3 * n))
    normals = np.zeros((n, 3 * n))
    for i in range(n):
        blocks[i * len(pyramid) : (i + 1) * len(pyramid), 3 * i : 3 * i + 3] = -pyramid
        normals[i, 3 * i + 2] = 1.0
    rows += [blocks, normals]
    lower += [np.zeros(len(blocks)), np.full(n, F_MIN)]
    constraints = np.vstack(rows)
    return quadprog.solve_qp(np.eye(3 * n), np.zeros(3 * n), constraints.T, np.concatenate(lower), meq=6)[0]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--cycles", type=int, default=2000)
    cycles = parser.parse_args().cycles
    gmap = sphere_grasp()
    t = np.arange(cycles) * 1e-3
    wrenches = np.column_stack((0.3 * np.sin(t), 0.2 * np.cos(t), 9.81 * 0.2 + 0.1 * np.sin(2 * t),
                                0.002 * np.sin(t), 0.001 * np.cos(t), 0.0005 * np.sin(3 * t)))  # fmt: skip
    qp = ContactForceQP(3, MU, FACETS, F_MIN)
    qp.solve(gmap, wrenches[0])  # first solve sets the problem up
    start = time.perf_counter()
    results = [qp.solve(gmap, w) for w in wrenches]
    ours = (time.perf_counter() - start) / cycles * 1e6
    raw = qp._qp  # the bare proxsuite problem: update the equality right-hand side and solve, no wrapper
    rows = qp._rows
    start = time.perf_counter()
    for w in wrenches:
        raw.update(b=rows * w, update_preconditioner=False)
        raw.solve()
    bare = (time.perf_counter() - start) / cycles * 1e6
    start = time.perf_counter()
    reference = [quadprog_solve(gmap, w) for w in wrenches]
    theirs = (time.perf_counter() - start) / cycles * 1e6
    start = time.perf_counter()
    for w in wrenches[: max(1, cycles // 10)]:
        ContactForceQP(3, MU, FACETS, F_MIN).solve(gmap, w)
    cold = (time.perf_counter() - start) / max(1, cycles // 10) * 1e6
    gap = max(float(np.max(np.abs(r.forces.ravel() - f))) for r, f in zip(results, reference))
    iterations = np.mean([r.iterations for r in results])
    print(f"{platform.processor() or platform.machine()}, Python {platform.python_version()}, {cycles} cycles")
    print(f"proxsuite warm-started: {ours:8.1f} us/solve ({iterations:.1f} iterations on average)")
    print(f"proxsuite set up cold:  {cold:8.1f} us/solve")
    print(f"bare proxsuite update(b) + solve: {bare:8.1f} us/solve (no input checks, no result object)")
    print(f"quadprog:               {theirs:8.1f} us/solve")
    print(
        f"ratio proxsuite warm / quadprog: {ours / theirs:.2f}; bare / quadprog: {bare / theirs:.2f};"
        f" cold / quadprog: {cold / theirs:.2f}"
    )
    print(
        f"largest force difference between the solvers: {gap:.2e} N; all feasible: {all(r.feasible for r in results)}"
    )


if __name__ == "__main__":
    main()
