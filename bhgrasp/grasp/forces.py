"""Contact forces that produce a required object wrench inside the friction cones: the internal-force QP.

Given the grasp map G (:func:`bhgrasp.grasp.frames.grasp_map`; contact forces in contact frames (t1, t2, n), n into the
object) and the wrench w the contacts must exert on the object (e.g. minus gravity and external loads, or the
output of an object-space controller), :class:`ContactForceQP` solves

    min_f  1/2 |f - f_d|^2          (closest to desired forces f_d; f_d = 0: least internal force)
    s.t.   G f = w,   f_i in the inscribed friction pyramid of contact i,   f_n,i >= f_min

with proxsuite's dense solver, one persistent problem per contact count, warm-started from the previous cycle.
The torque rows of G f = w are divided by the grasp's length r (:func:`~bhgrasp.grasp.quality.default_torque_scale`, the
largest lever) so that they weigh like the force rows: S = diag(1, 1, 1, 1/r, 1/r, 1/r).

No wrench raises or stalls.  When no such f exists the result has ``feasible=False`` and the *nearest admissible*
forces: inside every pyramid and normal bound, with the wrench closest to w,

    min_f,e  1/2 |f - f_d|^2 + W/2 |e|^2   s.t.   S (G f - w) = e,   the same pyramids and normal bounds,

W = :data:`NEAREST_WEIGHT`.  This problem is always feasible and strictly convex, so its answer is unique; its
scaled wrench error |e| exceeds the least one any admissible forces reach, e*, by at most |f* - f_d|^2 / (W |e|)
(f* the least-error forces closest to f_d).  ``wrench_residual`` and ``wrench_error`` give the miss.

Every call is bounded: at most three proxsuite solves, the QP and the nearest problem of at most ``max_iter``
outer iterations each and the check of at most ``CHECK_ITER * max_iter``, each outer one of at most
``max_iter_in + 1`` inner ones, so ``iterations`` <= :attr:`ContactForceQP.iteration_bound` (6 * 50 * 11 = 3300
by default; typically <= 26 for a feasible problem from scratch, a few warm-started, ~20 to prove an infeasible
one).  First the QP, whose infeasibility certificate (proxsuite's ``eps_primal_inf`` test) ends an infeasible one
in about a dozen iterations; if it is not solved, the nearest problem; if that one's error is so small that the
QP may be feasible after all (warm starts and near-degenerate optima fake a certificate now and then, e.g. 1 % of
the cycles of ``benchmarks/bench_qp.py`` from scratch), the check: the QP from scratch without the certificate
test.  After an infeasible call the next one tries the nearest problem first, so a persistently infeasible
request costs one warm-started solve per cycle.

After a solved call the next one first tries its active set K (the pyramid faces and normal bounds the forces sit on,
with nonzero multipliers): the forces closest to f_d with S G f = S w and the rows of K at their bounds,
f = f_d - M^T lambda with (M M^T) lambda = M f_d - r for M = [S G; C_K], one small Cholesky solve.  They are the QP's
optimum when M has full row rank (``FULL_RANK``), every row holds and every multiplier of K has its bound's sign,
both to the QP's tolerance (the KKT conditions; K is read from proxsuite's answer to ``ACTIVE_TOLERANCE``); then no
proxsuite solve runs (``iterations`` 0, status ``PROXQP_SOLVED``), and the next proxsuite solve starts from its own
last result, however many calls ago.  A control loop changes K only when a force reaches or leaves a face, so most
cycles take this path; two contacts never do (their G has rank 5).

This runs compiled (``src/force_qp.cpp``, proxsuite's C++ API, the same problems, settings and steps) when the default
engine is the compiled one (:mod:`bhgrasp._native`), otherwise in Python (``bhgrasp/grasp/_force_qp.py``, the readable
twin; ``engine="python"`` picks it); ``tests/test_force_qp_twin.py`` holds the two in lockstep.

:func:`pseudo_inverse_forces` is the thesis' baseline (5.45), f = G^+ w + (I - G^+ G) f_d: it meets G f = w
exactly whenever G has full row rank but ignores the cones, so it can command slipping forces.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from bhgrasp._native import engine_name, required_core
from bhgrasp._validation import as_array, as_real, as_vector
from bhgrasp.errors import InputError
from bhgrasp.grasp._force_qp import (  # noqa: F401  (the constants are part of this module's API)
    ACTIVE_TOLERANCE,
    ADMISSIBLE_TOLERANCE,
    CHECK_ITER,
    DOUBTFUL_ERROR,
    DUALITY_GAP_REL,
    FEASIBLE_RESIDUAL,
    FULL_RANK,
    NEAREST_WEIGHT,
    PRIMAL_INFEASIBILITY,
    ContactForceQPPython,
)
from bhgrasp.grasp.cones import friction_pyramid


@dataclass(frozen=True)
class ContactForceResult:
    """Contact forces for one wrench.

    Attributes:
        forces: (n, 3) contact-frame forces (t1, t2, n) [N] on the object, inside the pyramids and normal bounds
            whether or not the wrench is met.
        feasible: Whether the forces meet the wrench, |G f - w| <= 1e-6 max(1, |w|).  ``False``: no admissible
            forces do (or none were found within :attr:`ContactForceQP.iteration_bound`), and ``forces`` are
            the nearest admissible ones (module docstring).
        wrench_residual: |G f - w| [N, N m] of the returned forces (0 up to solver tolerance when feasible).
        cone_violation: Largest |f_t| - mu f_n over contacts [N] for the *exact* cone (<= 0 inside).
        normal_margin: Smallest f_n - f_min [N] (>= 0 when the bounds hold).
        status: proxsuite's status name for the QP itself: ``PROXQP_SOLVED`` (also for the optimum on the last
            active set, module docstring), ``PROXQP_PRIMAL_INFEASIBLE`` or ``PROXQP_MAX_ITER_REACHED`` (iteration
            bound hit; the problem is reported infeasible).
        iterations: proxsuite iterations (inner ones, summed over every solve of the call; 0: the last active set's
            optimum, no proxsuite solve).
        wrench_error: G f - w (6,) [N, N m] of the returned forces.
    """

    forces: np.ndarray
    feasible: bool
    wrench_residual: float
    cone_violation: float
    normal_margin: float
    status: str
    iterations: int
    wrench_error: np.ndarray


class ContactForceQP:
    """Persistent proxsuite QP for the contact forces of ``n_contacts`` frictional point contacts.

    Re-use one instance across control cycles: the problem keeps its structure and starts from the last solution
    (from scratch after an infeasible cycle).  A call never takes more than :attr:`iteration_bound` iterations.
    """

    CHECK_ITER = CHECK_ITER  # the check (the QP without the certificate test) may take CHECK_ITER * max_iter

    def __init__(
        self,
        n_contacts: int,
        mu: float,
        facets: int = 8,
        min_normal_force: float = 0.0,
        tolerance: float = 1e-9,
        max_iter: int = 50,
        max_iter_in: int = 10,
        engine: str | None = None,
    ) -> None:
        """Set up the problem structure.

        Args:
            n_contacts: Number of contacts n >= 1.
            mu: Friction coefficient (>= 0); the cones are inscribed pyramids with ``facets`` sides.
            facets: Sides of each friction pyramid (>= 3).
            min_normal_force: f_min [N] >= 0, the least normal force per contact.
            tolerance: Absolute solver tolerance (residuals and duality gap).
            max_iter: Outer (proximal) iterations of the QP and of the nearest problem, >= 1; the check may take
                ``CHECK_ITER`` times more (feasible problems from scratch: <= 17 outer iterations in 3300 random
                and control-loop cases, one case 79).
            max_iter_in: Inner (semi-smooth Newton) iterations per outer one, >= 1.
            engine: ``None`` (default): the default engine (:func:`~bhgrasp._native.default_engine`, compiled
                unless ``BHGRASP_ENGINE=python``); ``"compiled"``: the compiled solver of ``bhgrasp._core``;
                ``"python"``: the Python twin.  :attr:`engine` tells which.

        Raises:
            InputError: A bad argument.
            CompiledEngineUnavailable: The engine is the compiled one but ``bhgrasp._core`` does not load.
        """
        if int(n_contacts) < 1:
            raise InputError(f"`n_contacts` must be >= 1, got {n_contacts!r}")
        for name, value in (("max_iter", max_iter), ("max_iter_in", max_iter_in)):
            if not isinstance(value, (int, np.integer)) or value < 1:
                raise InputError(f"`{name}` must be an integer >= 1, got {value!r}")
        engine = engine_name(engine)
        args = solver_arguments(n_contacts, mu, facets, min_normal_force, tolerance, max_iter, max_iter_in)
        self.n, self.mu, pyramid, _, self.min_normal_force, _, self.max_iter, self.max_iter_in = args
        self.facets = len(pyramid)
        core = required_core("the compiled QP") if engine == "compiled" else None
        self._solver = ContactForceQPPython(*args) if core is None else core.ContactForceQP(*args)
        self.engine = "python" if core is None else "compiled"
        self._no_desired = np.zeros(3 * self.n)
        self._no_desired.flags.writeable = False

    @property
    def iteration_bound(self) -> int:
        """Most proxsuite iterations one :meth:`solve` takes: ``(2 + CHECK_ITER) * max_iter * (max_iter_in + 1)``."""
        return (2 + self.CHECK_ITER) * self.max_iter * (self.max_iter_in + 1)

    def solve(self, grasp_map: Any, wrench: Any, desired: Any = None) -> ContactForceResult:
        """Contact forces [N] for the object wrench ``wrench`` (6,) [N, N m] closest to ``desired`` ((n, 3) or None).

        An infeasible wrench does not raise: the result has ``feasible=False`` and the nearest admissible forces
        (module docstring).  At most :attr:`iteration_bound` solver iterations.

        Raises:
            InputError: Wrong shapes or non-finite inputs.
        """
        grasp = as_array(grasp_map, "grasp_map", (6, 3 * self.n))
        w = as_vector(wrench, "wrench", 6)
        f_d = self._no_desired if desired is None else as_array(desired, "desired", (self.n, 3)).ravel()
        solver = self._solver
        if not solver.holds(grasp):  # scale the torque rows so that they weigh like the force rows
            solver.set_grasp_map(grasp, _torque_scale(grasp))
        return ContactForceResult(*solver.solve(w, f_d))


def solver_arguments(
    n_contacts: int,
    mu: float,
    facets: int = 8,
    min_normal_force: float = 0.0,
    tolerance: float = 1e-9,
    max_iter: int = 50,
    max_iter_in: int = 10,
) -> tuple:
    """What :class:`ContactForceQP` (same arguments, same defaults) passes its solver's constructor.

    (n, mu, pyramid (facets, 3), mu cos(pi / facets), f_min, tolerance, max_iter, max_iter_in), converted and checked
    as :class:`ContactForceQP` does (``n_contacts`` and the iteration limits are checked there, before).  The compiled
    SMC-adaptive law (:mod:`bhgrasp.controllers._smc_law`) builds its QPs from the same arguments.
    """
    mu = as_real(mu, "mu")
    min_normal_force = as_real(min_normal_force, "min_normal_force")
    pyramid, _ = friction_pyramid(mu, facets)
    return (
        int(n_contacts),
        mu,
        pyramid,
        mu * np.cos(np.pi / len(pyramid)),
        min_normal_force,
        as_real(tolerance, "tolerance"),
        int(max_iter),
        int(max_iter_in),
    )


def _torque_scale(grasp: np.ndarray) -> float:
    """:func:`~bhgrasp.grasp.quality.default_torque_scale` [m] of a validated G, without its input checks.

    The same NumPy operations, so the same bits (``tests/test_force_qp_twin.py``), in a third of the time: a moving
    grasp changes its map every cycle.
    """
    blocks = grasp[3:].reshape(3, -1, 3)
    lever = math.sqrt(np.add.reduce(blocks * blocks, axis=(0, 2)).max()) / math.sqrt(2.0)
    return lever if lever > 0.0 else 1.0


def internal_forces(
    grasp_map: Any, wrench: Any, mu: float, min_normal_force: float = 0.0, desired: Any = None, facets: int = 8
) -> ContactForceResult:
    """One-shot :class:`ContactForceQP` (the API of DESIGN.md): contact forces producing ``wrench`` in the cones.

    For a control loop, keep a :class:`ContactForceQP` instead: it warm-starts from the previous cycle.
    """
    columns = np.shape(grasp_map)[-1] if np.ndim(grasp_map) == 2 else 0
    if columns == 0 or columns % 3:
        raise InputError(f"`grasp_map` must have shape (6, 3n), got shape {np.shape(grasp_map)}")
    return ContactForceQP(columns // 3, mu, facets, min_normal_force).solve(grasp_map, wrench, desired)


def pseudo_inverse_forces(grasp_map: Any, wrench: Any, desired: Any = None) -> np.ndarray:
    """Thesis (5.45): f = G^+ w + (I - G^+ G) f_d, (n, 3) contact-frame forces [N]; no cone constraint at all."""
    grasp = np.asarray(grasp_map, dtype=float)
    if grasp.ndim != 2 or grasp.shape[0] != 6 or grasp.shape[1] % 3 or not np.all(np.isfinite(grasp)):
        raise InputError(f"`grasp_map` must be a finite (6, 3n) array, got shape {grasp.shape}")
    n = grasp.shape[1] // 3
    w = as_vector(wrench, "wrench", 6)
    f_d = np.zeros(3 * n) if desired is None else as_array(desired, "desired", (n, 3)).ravel()
    pinv = np.linalg.pinv(grasp)
    return (pinv @ w + (np.eye(3 * n) - pinv @ grasp) @ f_d).reshape(n, 3)


def cone_violations(forces: Any, mu: float) -> np.ndarray:
    """Per contact |f_t| - mu f_n [N] (> 0: outside the exact friction cone, the contact would slip)."""
    forces = as_array(forces, "forces", (None, 3))
    mu = as_real(mu, "mu")
    return np.array([np.linalg.norm(f[:2]) - mu * f[2] for f in forces])


__all__ = ["ContactForceQP", "ContactForceResult", "cone_violations", "internal_forces", "pseudo_inverse_forces"]
