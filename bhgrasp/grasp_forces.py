"""Contact forces that produce a required object wrench inside the friction cones: the internal-force QP.

Given the grasp map G (:func:`bhgrasp.grasp.grasp_map`; contact forces in contact frames (t1, t2, n), n into the
object) and the wrench w the contacts must exert on the object (e.g. minus gravity and external loads, or the
output of an object-space controller), :class:`ContactForceQP` solves

    min_f  1/2 |f - f_d|^2          (closest to desired forces f_d; f_d = 0: least internal force)
    s.t.   G f = w,   f_i in the inscribed friction pyramid of contact i,   f_n,i >= f_min

with proxsuite's dense solver, one persistent problem per contact count, warm-started from the previous cycle.
The torque rows of G f = w are divided by the grasp's length r (:func:`~bhgrasp.grasp.default_torque_scale`, the
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

:func:`pseudo_inverse_forces` is the thesis' baseline (5.45), f = G^+ w + (I - G^+ G) f_d: it meets G f = w
exactly whenever G has full row rank but ignores the cones, so it can command slipping forces.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from bhgrasp._validation import as_array, as_real, as_vector
from bhgrasp.errors import InputError
from bhgrasp.grasp import default_torque_scale, friction_pyramid

NEAREST_WEIGHT = 1e4  # W of the nearest problem; 1e5 and above: proxsuite no longer converges on thin cones
PRIMAL_INFEASIBILITY = 1e-6  # proxsuite's eps_primal_inf for the QP (the default 1e-4 flags feasible grasps)
DOUBTFUL_ERROR = 0.1  # nearest |e| <= this * max(1, |f - f_d|): the QP may be feasible (then |e| = |y| / W)
DUALITY_GAP_REL = 1e-12  # relative duality-gap tolerance (besides the absolute one, for forces of 100s of N)
FEASIBLE_RESIDUAL = 1e-6  # |G f - w| <= this * max(1, |w|): the wrench is met
ADMISSIBLE_TOLERANCE = 1e-7  # [N] pyramid and normal-bound violation still counted as inside


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
        status: proxsuite's status name for the QP itself: ``PROXQP_SOLVED``, ``PROXQP_PRIMAL_INFEASIBLE`` or
            ``PROXQP_MAX_ITER_REACHED`` (iteration bound hit; the problem is reported infeasible).
        iterations: proxsuite iterations (inner ones, summed over every solve of the call).
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

    CHECK_ITER = 4  # the check (the QP without the certificate test) may take CHECK_ITER * max_iter outer iterations

    def __init__(
        self,
        n_contacts: int,
        mu: float,
        facets: int = 8,
        min_normal_force: float = 0.0,
        tolerance: float = 1e-9,
        max_iter: int = 50,
        max_iter_in: int = 10,
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
        """
        import proxsuite

        if int(n_contacts) < 1:
            raise InputError(f"`n_contacts` must be >= 1, got {n_contacts!r}")
        for name, value in (("max_iter", max_iter), ("max_iter_in", max_iter_in)):
            if not isinstance(value, (int, np.integer)) or value < 1:
                raise InputError(f"`{name}` must be an integer >= 1, got {value!r}")
        self.n = int(n_contacts)
        self.mu = as_real(mu, "mu")
        self.min_normal_force = as_real(min_normal_force, "min_normal_force")
        self.max_iter, self.max_iter_in = int(max_iter), int(max_iter_in)
        pyramid, _ = friction_pyramid(self.mu, facets)
        self.facets = len(pyramid)
        size = 3 * self.n
        rows = self.n * (self.facets + 1)
        self._C = np.zeros((rows, size))
        self._lower = np.full(rows, -np.inf)
        self._upper = np.zeros(rows)
        for i in range(self.n):
            block = slice(i * self.facets, (i + 1) * self.facets)
            self._C[block, 3 * i : 3 * i + 3] = pyramid
            row = self.n * self.facets + i
            self._C[row, 3 * i + 2] = 1.0
            self._lower[row], self._upper[row] = self.min_normal_force, np.inf
        self._H = np.eye(size)
        self._proxqp = proxsuite.proxqp
        tolerance = as_real(tolerance, "tolerance")
        self._qp = self._make(size, tolerance, PRIMAL_INFEASIBILITY, self.max_iter)
        # eps_primal_inf < 0: the certificate test never fires
        self._check = self._make(size, tolerance, -1.0, self.CHECK_ITER * self.max_iter)
        # the nearest problem in x = (f, e): H = diag(I, W I), [S G, -I] x = S w, the same rows on f
        self._nearest = self._make(size + 6, tolerance, -1.0, self.max_iter)
        self._nearest_H = np.diag(np.concatenate((np.ones(size), np.full(6, NEAREST_WEIGHT))))
        self._nearest_C = np.hstack((self._C, np.zeros((rows, 6))))
        self._warm: bool | tuple = False  # how the QP starts: from its last result, from (x, y, z), from scratch
        self._warm_nearest = self._infeasible = False
        self._grasp_map: np.ndarray | None = None
        self._rows = np.ones(6)
        self._A = np.zeros((6, size))
        self._nearest_A = np.zeros((6, size + 6))

    @property
    def iteration_bound(self) -> int:
        """Most proxsuite iterations one :meth:`solve` takes: ``(2 + CHECK_ITER) * max_iter * (max_iter_in + 1)``."""
        return (2 + self.CHECK_ITER) * self.max_iter * (self.max_iter_in + 1)

    def _make(self, size: int, tolerance: float, primal_infeasibility: float, max_iter: int):
        qp = self._proxqp.dense.QP(size, 6, len(self._C))
        settings = qp.settings
        settings.eps_abs, settings.eps_rel = tolerance, 0.0
        settings.check_duality_gap = True  # without the gap test the forces are only within ~3e-7 N of the optimum
        settings.eps_duality_gap_abs, settings.eps_duality_gap_rel = tolerance, DUALITY_GAP_REL
        settings.eps_primal_inf = primal_infeasibility
        settings.verbose = False
        settings.max_iter, settings.max_iter_in = max_iter, self.max_iter_in
        return qp

    def _run(self, qp, warm: bool | tuple, problem: tuple) -> tuple[str, int, np.ndarray]:
        """One bounded solve of ``problem`` = (H, g, A, b, C, l, u): (status, iterations, x).

        ``warm``: True (from the previous result of ``qp``), a primal-dual point (x, y, z), or False (scratch).
        """
        guess = self._proxqp.InitialGuess
        if warm is False:
            qp.settings.initial_guess = guess.EQUALITY_CONSTRAINED_INITIAL_GUESS
            qp.init(*problem)
            qp.solve()
        else:  # same H, C and bounds; A too, even unchanged: its refactorisation halves the warm iterations
            explicit = warm is not True
            qp.settings.initial_guess = guess.WARM_START if explicit else guess.WARM_START_WITH_PREVIOUS_RESULT
            qp.update(g=problem[1], A=problem[2], b=problem[3], update_preconditioner=False)
            qp.solve(*warm) if explicit else qp.solve()
        info = qp.results.info
        x = qp.results.x.copy()
        status = info.status.name if np.all(np.isfinite(x)) else "PROXQP_NOT_FINITE"
        return status, int(info.iter), x

    def solve(self, grasp_map: Any, wrench: Any, desired: Any = None) -> ContactForceResult:
        """Contact forces [N] for the object wrench ``wrench`` (6,) [N, N m] closest to ``desired`` ((n, 3) or None).

        An infeasible wrench does not raise: the result has ``feasible=False`` and the nearest admissible forces
        (module docstring).  At most :attr:`iteration_bound` solver iterations.

        Raises:
            InputError: Wrong shapes or non-finite inputs.
        """
        size = 3 * self.n
        grasp = as_array(grasp_map, "grasp_map", (6, size))
        w = as_vector(wrench, "wrench", 6)
        f_d = np.zeros(size) if desired is None else as_array(desired, "desired", (self.n, 3)).ravel()
        if self._grasp_map is None or not np.array_equal(grasp, self._grasp_map):
            self._grasp_map = grasp.copy()  # scale the torque rows so that they weigh like the force rows
            self._rows = np.concatenate((np.ones(3), np.full(3, 1.0 / default_torque_scale(grasp))))
            self._A = self._rows[:, None] * grasp
            self._nearest_A = np.hstack((self._A, -np.eye(6)))
        b = self._rows * w
        problem = (self._H, -f_d, self._A, b, self._C, self._lower, self._upper)
        iterations, nearest, doubtful = 0, None, True
        if self._infeasible:  # the last call was infeasible: the nearest problem first, it is likely the answer
            nearest, iterations, doubtful = self._nearest_forces(f_d, b)
            if not doubtful:
                return self._result(grasp, w, nearest, "PROXQP_PRIMAL_INFEASIBLE", iterations)
        status, spent, x = self._run(self._qp, self._warm, problem)
        iterations += spent
        warm = solved = status == "PROXQP_SOLVED"
        if not solved and nearest is None:
            nearest, spent, doubtful = self._nearest_forces(f_d, b)
            iterations += spent
        if not solved and doubtful:  # maybe a fake certificate: the QP from scratch without the test
            check, spent, x = self._run(self._check, False, problem)
            iterations += spent
            solved = check == "PROXQP_SOLVED"
            if solved:  # the next cycle starts the QP from here, not from its own failed iterate
                status, warm = check, (x, self._check.results.y.copy(), self._check.results.z.copy())
        self._warm, self._infeasible = warm if solved else False, not solved
        return self._result(grasp, w, x if solved else nearest, status, iterations)

    def _nearest_forces(self, f_d: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, int, bool]:
        """The nearest problem: admissible forces, iterations, and whether the QP may be feasible after all.

        For a feasible QP the nearest problem's error is |e| = |y| / W (y the multiplier of S G f = S w), small
        against |f - f_d|: ``doubtful`` is |e| <= DOUBTFUL_ERROR max(1, |f - f_d|).
        """
        gradient = np.concatenate((-f_d, np.zeros(6)))
        problem = (self._nearest_H, gradient, self._nearest_A, b, self._nearest_C, self._lower, self._upper)
        status, iterations, x = self._run(self._nearest, self._warm_nearest, problem)
        self._warm_nearest = solved = status == "PROXQP_SOLVED"
        forces = x[: 3 * self.n] if solved else self._admissible(x[: 3 * self.n])
        error = float(np.linalg.norm(self._A @ forces - b))
        return forces, iterations, error <= DOUBTFUL_ERROR * max(1.0, float(np.linalg.norm(forces - f_d)))

    def _admissible(self, forces: np.ndarray) -> np.ndarray:
        """Unconverged ``forces`` moved into the pyramids' inscribed cones and above f_min (NaN -> f_min)."""
        per_contact = np.where(np.isfinite(forces), forces, 0.0).reshape(self.n, 3)
        per_contact[:, 2] = np.maximum(per_contact[:, 2], self.min_normal_force)
        tangential = np.hypot(per_contact[:, 0], per_contact[:, 1])
        limit = self.mu * np.cos(np.pi / self.facets) * per_contact[:, 2]
        per_contact[:, :2] *= np.where(tangential > limit, limit / np.maximum(tangential, 1e-300), 1.0)[:, None]
        return per_contact.ravel()

    def _result(self, grasp, w, forces, status, iterations) -> ContactForceResult:
        per_contact = forces.reshape(self.n, 3)
        error = grasp @ forces - w
        residual = float(np.sqrt(error @ error))
        tangential = np.sqrt(per_contact[:, 0] ** 2 + per_contact[:, 1] ** 2)
        cone = float(np.max(tangential - self.mu * per_contact[:, 2]))
        margin = float(np.min(per_contact[:, 2]) - self.min_normal_force)
        pyramid = float(np.max(self._C[: self.n * self.facets] @ forces))
        admissible = pyramid <= ADMISSIBLE_TOLERANCE and margin >= -ADMISSIBLE_TOLERANCE
        feasible = admissible and residual <= FEASIBLE_RESIDUAL * max(1.0, float(np.linalg.norm(w)))
        return ContactForceResult(per_contact, bool(feasible), residual, cone, margin, status, iterations, error)


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
