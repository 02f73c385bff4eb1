"""The Python twin of the compiled internal-force QP ``bhgrasp._core.ContactForceQP`` (``src/force_qp.cpp``).

:class:`~bhgrasp.grasp.forces.ContactForceQP` checks its inputs and runs one of the two (its ``engine``); the
docstring of :mod:`bhgrasp.grasp.forces` states the problems, the check of a doubtful certificate, the warm starts
and the iteration bound.  Both classes have one interface on validated arrays: :meth:`~ContactForceQPPython.holds`
and :meth:`~ContactForceQPPython.set_grasp_map` (the grasp map and its torque scale, when it changes), then
:meth:`~ContactForceQPPython.solve`, whose answer is the fields of
:class:`~bhgrasp.grasp.forces.ContactForceResult` in order.  The same three proxsuite dense problems, settings and
state machine, line for line (the active set's optimum by NumPy's and SciPy's Cholesky there, Eigen's in C++);
``tests/test_force_qp_twin.py`` holds the two in lockstep.
"""

from __future__ import annotations

import numpy as np

NEAREST_WEIGHT = 1e4  # W of the nearest problem; 1e5 and above: proxsuite no longer converges on thin cones
PRIMAL_INFEASIBILITY = 1e-6  # proxsuite's eps_primal_inf for the QP (the default 1e-4 flags feasible grasps)
DOUBTFUL_ERROR = 0.1  # nearest |e| <= this * max(1, |f - f_d|): the QP may be feasible (then |e| = |y| / W)
DUALITY_GAP_REL = 1e-12  # relative duality-gap tolerance (besides the absolute one, for forces of 100s of N)
FEASIBLE_RESIDUAL = 1e-6  # |G f - w| <= this * max(1, |w|): the wrench is met
ADMISSIBLE_TOLERANCE = 1e-7  # [N] pyramid and normal-bound violation still counted as inside
CHECK_ITER = 4  # the check (the QP without the certificate test) may take CHECK_ITER * max_iter outer iterations
ACTIVE_TOLERANCE = 1e-8  # [N] a solved row this close to its bound (or 10 eps_abs), its multiplier nonzero, is active
FULL_RANK = 1e-6  # least over largest diagonal entry of M M^T's Cholesky factor L: below it M is rank-deficient


class ContactForceQPPython:
    """Three persistent proxsuite problems (the QP, the check, the nearest problem) and the state between calls.

    Args:
        n_contacts: n >= 1.
        mu: Friction coefficient >= 0.
        pyramid: (facets, 3) rows of :func:`~bhgrasp.grasp.cones.friction_pyramid`.
        inscribed: mu cos(pi / facets), the inscribed cone's slope.
        min_normal_force: f_min [N] >= 0.
        tolerance: proxsuite's eps_abs (and the absolute duality-gap tolerance).
        max_iter: Outer iterations of the QP and of the nearest problem (the check: CHECK_ITER times more).
        max_iter_in: Inner iterations per outer one.
    """

    def __init__(self, n_contacts, mu, pyramid, inscribed, min_normal_force, tolerance, max_iter, max_iter_in):
        import proxsuite

        self.n, self.mu, self.inscribed, self.min_normal_force = n_contacts, mu, inscribed, min_normal_force
        self.max_iter_in, self.tolerance = max_iter_in, tolerance
        self._active_tolerance = max(ACTIVE_TOLERANCE, 10.0 * tolerance)
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
        self._qp = self._make(size, tolerance, PRIMAL_INFEASIBILITY, max_iter)
        # eps_primal_inf < 0: the certificate test never fires
        self._check = self._make(size, tolerance, -1.0, CHECK_ITER * max_iter)
        # the nearest problem in x = (f, e): H = diag(I, W I), [S G, -I] x = S w, the same rows on f
        self._nearest = self._make(size + 6, tolerance, -1.0, max_iter)
        self._nearest_H = np.diag(np.concatenate((np.ones(size), np.full(6, NEAREST_WEIGHT))))
        self._nearest_C = np.hstack((self._C, np.zeros((rows, 6))))
        self._warm: bool | tuple = False  # how the QP starts: from its last result, from (x, y, z), from scratch
        self._warm_nearest = self._infeasible = False
        self._active: tuple[np.ndarray, np.ndarray] | None = None  # the last solved call's active rows and sides
        self._grasp_map: np.ndarray | None = None
        self._rows = np.ones(6)
        self._A = np.zeros((6, size))
        self._nearest_A = np.zeros((6, size + 6))

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

    def holds(self, grasp: np.ndarray) -> bool:
        """Whether ``grasp`` (6, 3n) equals, entry for entry, the grasp map last set."""
        return self._grasp_map is not None and np.array_equal(grasp, self._grasp_map)

    def set_grasp_map(self, grasp: np.ndarray, torque_scale: float) -> None:
        """A new grasp map G and its torque scale r [m]: the rows S G f = S w, S = diag(1, 1, 1, 1/r, 1/r, 1/r)."""
        self._grasp_map = grasp.copy()  # scale the torque rows so that they weigh like the force rows
        self._rows = np.concatenate((np.ones(3), np.full(3, 1.0 / torque_scale)))
        self._A = self._rows[:, None] * grasp
        self._nearest_A = np.hstack((self._A, -np.eye(6)))

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

    def solve(self, w: np.ndarray, f_d: np.ndarray) -> tuple:
        """The forces for the wrench ``w`` (6,) closest to ``f_d`` (3n,), for the grasp map last set."""
        b = self._rows * w
        problem = (self._H, -f_d, self._A, b, self._C, self._lower, self._upper)
        iterations, nearest, doubtful = 0, None, True
        if not self._infeasible and self._active is not None:  # the last active set still holds: no QP
            optimum = self._active_set_forces(f_d, b)
            if optimum is not None:
                return self._result(w, optimum, "PROXQP_SOLVED", 0)
        if self._infeasible:  # the last call was infeasible: the nearest problem first, it is likely the answer
            nearest, iterations, doubtful = self._nearest_forces(f_d, b)
            if not doubtful:
                return self._result(w, nearest, "PROXQP_PRIMAL_INFEASIBLE", iterations)
        status, spent, x = self._run(self._qp, self._warm, problem)
        iterations += spent
        warm = solved = status == "PROXQP_SOLVED"
        if solved:
            self._remember_active(x, self._qp.results.z)
        if not solved and nearest is None:
            nearest, spent, doubtful = self._nearest_forces(f_d, b)
            iterations += spent
        if not solved and doubtful:  # maybe a fake certificate: the QP from scratch without the test
            check, spent, x = self._run(self._check, False, problem)
            iterations += spent
            solved = check == "PROXQP_SOLVED"
            if solved:  # the next cycle starts the QP from here, not from its own failed iterate
                status, warm = check, (x, self._check.results.y.copy(), self._check.results.z.copy())
                self._remember_active(x, warm[2])
        self._warm, self._infeasible = warm if solved else False, not solved
        if not solved:
            self._active = None
        return self._result(w, x if solved else nearest, status, iterations)

    def _remember_active(self, forces: np.ndarray, multipliers: np.ndarray) -> None:
        """The rows at a bound with a nonzero multiplier (proxsuite's z: > 0 upper, < 0 lower) in a solved call."""
        values = self._C @ forces
        bound = np.where(multipliers > 0.0, self._upper, self._lower)
        rows = np.flatnonzero((multipliers != 0.0) & (np.abs(values - bound) <= self._active_tolerance))
        full_rank = 6 + len(rows) <= 3 * self.n  # else M M^T is singular
        self._active = (rows, np.where(multipliers[rows] > 0.0, 1.0, -1.0)) if full_rank else None

    def _active_set_forces(self, f_d: np.ndarray, b: np.ndarray) -> np.ndarray | None:
        """The QP's optimum if the last active set K still holds, else None (the warm starts are left as they are).

        min 1/2 |f - f_d|^2 with M f = r, M = [A; C_K], r = [b; bounds of K]: f = f_d - M^T lambda with
        (M M^T) lambda = M f_d - r.  Kept only with its proof of optimality at the QP's tolerance: M f = r and every
        row inside its bounds to eps_abs, each multiplier of K of its bound's sign (>= -eps_abs).
        """
        import scipy.linalg  # here: importing bhgrasp.grasp does not import scipy

        rows, sides = self._active
        tolerance = self.tolerance
        system = np.vstack((self._A, self._C[rows]))
        bounds = np.concatenate((b, np.where(sides > 0.0, self._upper[rows], self._lower[rows])))
        try:
            factor = np.linalg.cholesky(system @ system.T)
        except np.linalg.LinAlgError:
            return None
        pivots = np.diag(factor)  # M of full row rank, not only in round-off (two contacts' G has rank 5)
        if not pivots.min() >= FULL_RANK * pivots.max():
            return None
        multipliers = scipy.linalg.cho_solve((factor, True), system @ f_d - bounds)
        forces = f_d - system.T @ multipliers
        if not np.all(np.isfinite(forces)) or np.max(np.abs(system @ forces - bounds)) > tolerance:
            return None
        values = self._C @ forces
        if np.any(values > self._upper + tolerance) or np.any(values < self._lower - tolerance):
            return None
        if np.any(sides * multipliers[6:] < -tolerance):
            return None
        return forces

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
        limit = self.inscribed * per_contact[:, 2]
        per_contact[:, :2] *= np.where(tangential > limit, limit / np.maximum(tangential, 1e-300), 1.0)[:, None]
        return per_contact.ravel()

    def _result(self, w: np.ndarray, forces: np.ndarray, status: str, iterations: int) -> tuple:
        """(forces (n, 3), feasible, residual, cone violation, normal margin, status, iterations, G f - w)."""
        per_contact = forces.reshape(self.n, 3)
        error = self._grasp_map @ forces - w
        residual = float(np.sqrt(error @ error))
        tangential = np.sqrt(per_contact[:, 0] ** 2 + per_contact[:, 1] ** 2)
        cone = float(np.max(tangential - self.mu * per_contact[:, 2]))
        margin = float(np.min(per_contact[:, 2]) - self.min_normal_force)
        pyramid = float(np.max(self._C[: self.n * self.facets] @ forces))
        admissible = pyramid <= ADMISSIBLE_TOLERANCE and margin >= -ADMISSIBLE_TOLERANCE
        feasible = admissible and residual <= FEASIBLE_RESIDUAL * max(1.0, float(np.linalg.norm(w)))
        return per_contact, bool(feasible), residual, cone, margin, status, iterations, error
