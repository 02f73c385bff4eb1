"""Contact forces that produce a required object wrench inside the friction cones: the internal-force QP.

Given the grasp map G (:func:`bhgrasp.grasp.grasp_map`; contact forces in contact frames (t1, t2, n), n into the
object) and the wrench w the contacts must exert on the object (e.g. minus gravity and external loads, or the
output of an object-space controller), :class:`ContactForceQP` solves

    min_f  1/2 |f - f_d|^2          (closest to desired forces f_d; f_d = 0: least internal force)
    s.t.   G f = w,   f_i in the inscribed friction pyramid of contact i,   f_n,i >= f_min

with proxsuite's dense solver, one persistent problem per contact count, warm-started from the previous cycle.
When no such f exists the result says so and by how much: a second QP keeps every cone and normal bound and
minimises |G f - w|^2 instead, so ``wrench_residual`` is the smallest wrench error any admissible forces reach.

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

_RELAXED_WEIGHT = 1e6  # weight of |G f - w|^2 against 1/2 |f - f_d|^2 in the relaxed problem
_INFEASIBILITY_TOLERANCE = 1e-14  # 1e-10 still flagged a degenerate feasible optimum (all cones active)


@dataclass(frozen=True)
class ContactForceResult:
    """Contact forces for one wrench.

    Attributes:
        forces: (n, 3) contact-frame forces (t1, t2, n) [N] on the object.
        feasible: Whether the requested wrench is met within the cones and normal bounds.
        wrench_residual: |G f - w| [N, N m] of the returned forces (0 up to solver tolerance when feasible).
        cone_violation: Largest |f_t| - mu f_n over contacts [N] for the *exact* cone (<= 0 inside).
        normal_margin: Smallest f_n - f_min [N] (>= 0 when the bounds hold).
        status: The solver's status name.
        iterations: Solver iterations of the main problem.
    """

    forces: np.ndarray
    feasible: bool
    wrench_residual: float
    cone_violation: float
    normal_margin: float
    status: str
    iterations: int


class ContactForceQP:
    """Persistent proxsuite QP for the contact forces of ``n_contacts`` frictional point contacts.

    Re-use one instance across control cycles: the problem keeps its structure and starts from the last solution.
    """

    def __init__(
        self, n_contacts: int, mu: float, facets: int = 8, min_normal_force: float = 0.0, tolerance: float = 1e-9
    ) -> None:
        """Set up the problem structure.

        Args:
            n_contacts: Number of contacts n >= 1.
            mu: Friction coefficient (>= 0); the cones are inscribed pyramids with ``facets`` sides.
            facets: Sides of each friction pyramid (>= 3).
            min_normal_force: f_min [N] >= 0, the least normal force per contact.
            tolerance: Absolute solver tolerance.
        """
        import proxsuite

        if int(n_contacts) < 1:
            raise InputError(f"`n_contacts` must be >= 1, got {n_contacts!r}")
        self.n = int(n_contacts)
        self.mu = as_real(mu, "mu")
        self.min_normal_force = as_real(min_normal_force, "min_normal_force")
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
        self._qp = self._make(size, 6, rows, as_real(tolerance, "tolerance"))
        self._relaxed = self._make(size, 0, rows, as_real(tolerance, "tolerance"))
        self._initialised = False
        self._grasp_map: np.ndarray | None = None
        self._rows = np.ones(6)
        self._A = np.zeros((6, size))

    def _make(self, size: int, n_eq: int, n_in: int, tolerance: float):
        qp = self._proxqp.dense.QP(size, n_eq, n_in)
        qp.settings.eps_abs = tolerance
        qp.settings.eps_rel = 0.0
        qp.settings.eps_primal_inf = _INFEASIBILITY_TOLERANCE  # the default 1e-4 flags feasible grasps whose torque
        qp.settings.eps_dual_inf = _INFEASIBILITY_TOLERANCE  # rows are ~r = 4 cm smaller than their force rows
        qp.settings.verbose = False
        qp.settings.max_iter = 10_000
        qp.settings.initial_guess = self._proxqp.InitialGuess.WARM_START_WITH_PREVIOUS_RESULT
        return qp

    def solve(self, grasp_map: Any, wrench: Any, desired: Any = None) -> ContactForceResult:
        """Contact forces [N] for the object wrench ``wrench`` (6,) [N, N m] closest to ``desired`` ((n, 3) or None).

        Raises:
            InputError: Wrong shapes or non-finite inputs.
        """
        size = 3 * self.n
        grasp = as_array(grasp_map, "grasp_map", (6, size))
        w = as_vector(wrench, "wrench", 6)
        f_d = np.zeros(size) if desired is None else as_array(desired, "desired", (self.n, 3)).ravel()
        g = -f_d
        changed = self._grasp_map is None or not np.array_equal(grasp, self._grasp_map)
        if changed:  # scale the torque rows so that they weigh like the force rows
            self._grasp_map = grasp.copy()
            self._rows = np.concatenate((np.ones(3), np.full(3, 1.0 / default_torque_scale(grasp))))
            self._A = self._rows[:, None] * grasp
        b = self._rows * w
        if not self._initialised:
            self._qp.init(self._H, g, self._A, b, self._C, self._lower, self._upper)
            self._initialised = True
        elif changed:
            self._qp.update(g=g, A=self._A, b=b, update_preconditioner=False)
        else:
            self._qp.update(g=g, b=b, update_preconditioner=False)
        self._qp.solve()
        status = self._qp.results.info.status
        if status != self._proxqp.QPSolverOutput.PROXQP_SOLVED:  # a warm start can mislead the infeasibility test
            self._qp.settings.initial_guess = self._proxqp.InitialGuess.EQUALITY_CONSTRAINED_INITIAL_GUESS
            self._qp.init(self._H, g, self._A, b, self._C, self._lower, self._upper)
            self._qp.solve()
            self._qp.settings.initial_guess = self._proxqp.InitialGuess.WARM_START_WITH_PREVIOUS_RESULT
            status = self._qp.results.info.status
        solved = status == self._proxqp.QPSolverOutput.PROXQP_SOLVED
        forces = self._qp.results.x.copy()
        if not solved or not np.all(np.isfinite(forces)):
            forces = self._closest(grasp, w, f_d)
        return self._result(grasp, w, forces, solved, status.name, int(self._qp.results.info.iter))

    def _closest(self, grasp: np.ndarray, w: np.ndarray, f_d: np.ndarray) -> np.ndarray:
        """Admissible forces with the smallest wrench error: min W |G f - w|^2 + 1/2 |f - f_d|^2 in the cones."""
        hessian = _RELAXED_WEIGHT * grasp.T @ grasp + self._H
        g = -_RELAXED_WEIGHT * grasp.T @ w - f_d
        self._relaxed.init(hessian, g, None, None, self._C, self._lower, self._upper)
        self._relaxed.solve()
        return self._relaxed.results.x.copy()

    def _result(self, grasp, w, forces, solved, status, iterations) -> ContactForceResult:
        per_contact = forces.reshape(self.n, 3)
        error = grasp @ forces - w
        residual = float(np.sqrt(error @ error))
        tangential = np.sqrt(per_contact[:, 0] ** 2 + per_contact[:, 1] ** 2)
        cone = float(np.max(tangential - self.mu * per_contact[:, 2]))
        margin = float(np.min(per_contact[:, 2]) - self.min_normal_force)
        feasible = residual <= 1e-6 * max(1.0, float(np.linalg.norm(w)))
        return ContactForceResult(per_contact, feasible, residual, cone, margin, status, iterations)


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
