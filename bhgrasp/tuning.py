"""Seeded CMA-ES minimisation with serial, process-pool or Dask evaluation (thesis ch. 4.7).

:func:`cma_es` minimises any scalar ``objective(x)`` with the covariance matrix adaptation evolution strategy of the
``cma`` package (ask/tell loop), evaluating each generation's candidates in parallel.  It is used to tune
impedance parameters against the fitness (4.49), the mean of ``|f_d - f_k|`` over a run.  A run ends on cma's own
termination criteria (``tol_fun``, ``tol_x`` and cma's defaults) or on a cap (``max_generations``,
``max_evaluations``); :attr:`TuningResult.criteria` is cma's ``stop()`` dictionary, saying which fired.

Evaluation runs in a :class:`~concurrent.futures.ProcessPoolExecutor` created for the run (default), in-process
(``executor="serial"``), or on any :class:`~concurrent.futures.Executor`, e.g. a Dask
``distributed.Client.get_executor()``.  Results are collected in candidate order, never completion order, and the
sampling uses a generator private to the run, so the same seed and objective give a bitwise identical
:class:`TuningResult` whatever the executor.

A :class:`BatchedObjective` evaluates many candidates per call (e.g. one :class:`~bhgrasp.sim.batch.BatchSimulator`
per call, one task of the executor each); since a batch gives the bits of separate runs, the result is the same.

A candidate whose evaluation raises, or returns NaN/inf or a non-number, is recorded (``failures``, fitness
``inf`` in the history) and handed to CMA-ES with a finite penalty; if a whole generation fails, or the executor
itself breaks, :class:`TuningError` is raised carrying the result so far.  (A Dask task that kills its workers
ends with ``KilledWorker``; the cluster survives, so that counts as a failed candidate.)  ``cma``, ``tqdm`` and
the process pool are imported only when :func:`cma_es` runs.
"""

from __future__ import annotations

import math
import numbers
import os
import pickle
from collections.abc import Callable
from concurrent.futures import Executor
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np

from bhgrasp._validation import as_positive, as_real, as_vector
from bhgrasp.errors import BhgraspError, InputError
from bhgrasp.parallel import describe_error, executor_for, parallel_map, progress_bar

Objective = Callable[[np.ndarray], float]
PENALTY_FACTOR = 10.0  # a failed candidate counts as PENALTY_FACTOR x the worst finite fitness seen so far
PENALTY_WITHOUT_FITNESS = 1e6  # ... or this, when no finite positive fitness has been seen yet


@dataclass(frozen=True)
class BatchedObjective:
    """An objective that evaluates many candidates in one call (e.g. on a :class:`~bhgrasp.sim.batch.BatchSimulator`).

    Attributes:
        function: Top-level ``(candidates) -> fitness values``: a list of (n,) arrays in, one finite fitness per
            candidate out, in order (picklable for a process pool).
        size: Candidates per call; a generation is cut into ``ceil(population / size)`` calls, each one task of
            the executor.  A call that raises fails all its candidates; a non-finite value fails its own.
    """

    function: Callable[[list[np.ndarray]], Any]
    size: int = 64

    def __post_init__(self) -> None:
        if isinstance(self.size, bool) or not isinstance(self.size, int) or self.size < 1:
            raise InputError(f"`size` must be a positive integer (candidates per call), got {self.size!r}")

    def __call__(self, x: np.ndarray) -> float:
        """One candidate alone (a batch of one)."""
        return self.function([x])[0]


@dataclass(frozen=True)
class TuningResult:
    """Outcome of a CMA-ES run; every row and index is in evaluation order (generation by generation).

    Indices in ``failures`` and error messages are 0-based: candidate ``i`` of generation ``g`` is history row
    ``g * population + i`` (except in the unfinished last generation of a :attr:`TuningError.partial`).

    Attributes:
        best: (n,) parameters of the lowest finite fitness, in the optimiser's coordinates; NaN if no evaluation
            succeeded (only possible in a :attr:`TuningError.partial`).
        best_fitness: Objective value at ``best``; ``inf`` if no evaluation succeeded.
        generations: Number of completed generations (candidates evaluated and told to CMA-ES).
        evaluations: Number of finished evaluations, failed ones included.
        history_parameters: (evaluations, n) every evaluated candidate.
        history_fitness: (evaluations,) their fitness; ``inf`` for a failed evaluation.
        generation_best: (generations,) lowest fitness of each generation.
        sigma: (generations,) CMA-ES step size after each generation.
        failures: ``"generation g, candidate i: <ExceptionType>: <message>"`` of every failed evaluation.
        stop: Why the run stopped: ``"max_generations"``, the text of cma's stop dictionary (e.g.
            ``"{'tolfun': 1e-09}"``), or, in a partial result, the error.
        criteria: cma's own ``stop()`` dictionary after the last generation, verbatim (criterion -> its
            threshold, e.g. ``{'tolfun': 1e-09}`` or ``{'maxfevals': 600}``; ``maxiter`` is our
            ``max_generations``); empty if no criterion fired (a partial result).
    """

    best: np.ndarray
    best_fitness: float
    generations: int
    evaluations: int
    history_parameters: np.ndarray
    history_fitness: np.ndarray
    generation_best: np.ndarray
    sigma: np.ndarray
    failures: tuple[str, ...]
    stop: str
    criteria: dict[str, Any] = field(default_factory=dict)


class TuningError(BhgraspError, RuntimeError):
    """A tuning run could not continue: every candidate of a generation failed, or the executor broke.

    Attributes:
        partial: The :class:`TuningResult` so far, keeping every evaluation that finished before the error.
    """

    def __init__(self, message: str, partial: TuningResult) -> None:
        super().__init__(message)
        self.partial = partial


@dataclass
class _Outcome:
    """One finished evaluation: the candidate index and its fitness, or the error it raised."""

    index: int
    fitness: float = math.inf
    error: Exception | None = None


@dataclass
class _History:
    """The record of a run so far, turned into a :class:`TuningResult` by :meth:`result`."""

    n: int
    parameters: list[np.ndarray] = field(default_factory=list)
    fitness: list[float] = field(default_factory=list)
    generation_best: list[float] = field(default_factory=list)
    sigma: list[float] = field(default_factory=list)
    failures: list[str] = field(default_factory=list)

    def record(self, generation: int, candidates: list[np.ndarray], outcomes: list[_Outcome]) -> None:
        """Append the finished evaluations of one generation, in candidate order."""
        for outcome in outcomes:
            self.parameters.append(np.array(candidates[outcome.index], dtype=np.float64))
            self.fitness.append(outcome.fitness)
            if outcome.error is not None:
                error = outcome.error
                self.failures.append(f"generation {generation}, candidate {outcome.index}: {describe_error(error)}")

    def worst_finite(self) -> float | None:
        """The largest finite fitness recorded, or ``None`` if there is none."""
        finite = [value for value in self.fitness if math.isfinite(value)]
        return max(finite) if finite else None

    def result(self, stop: str, criteria: dict[str, Any] | None = None) -> TuningResult:
        """The :class:`TuningResult` of everything recorded so far."""
        fitness = np.array(self.fitness, dtype=np.float64)
        parameters = np.array(self.parameters, dtype=np.float64).reshape(len(self.fitness), self.n)
        if np.any(np.isfinite(fitness)):
            index = int(np.argmin(fitness))
            best, best_fitness = parameters[index].copy(), float(fitness[index])
        else:
            best, best_fitness = np.full(self.n, np.nan), math.inf
        return TuningResult(
            best=best,
            best_fitness=best_fitness,
            generations=len(self.generation_best),
            evaluations=len(self.fitness),
            history_parameters=parameters,
            history_fitness=fitness,
            generation_best=np.array(self.generation_best, dtype=np.float64),
            sigma=np.array(self.sigma, dtype=np.float64),
            failures=tuple(self.failures),
            stop=stop,
            criteria=dict(criteria or {}),
        )


def cma_es(
    objective: Objective,
    x0: Any,
    sigma0: float = 0.5,
    *,
    seed: int,
    max_generations: int = 50,
    population: int | None = None,
    bounds: tuple[Any, Any] | None = None,
    executor: Executor | Literal["serial"] | None = None,
    progress: bool = False,
    failure_fitness: float | None = None,
    tol_fun: float = 1e-9,
    tol_x: float | None = None,
    max_evaluations: int | None = None,
) -> TuningResult:
    """Minimise ``objective`` with a seeded CMA-ES, evaluating each generation's candidates in parallel.

    Args:
        objective: ``objective(x) -> float`` for ``x`` of shape (n,).  For the default process pool it must be
            picklable: a top-level function, or a :func:`functools.partial` of one.
        x0: (n,) start point, n >= 1, finite.
        sigma0: Initial step size (> 0), in the units of ``x``; about a quarter of the search range is typical.
        seed: Non-negative int seeding a generator private to the run: same seed and objective, same result.
        max_generations: Largest number of generations (>= 1).
        population: Candidates per generation (>= 2); default cma's ``4 + floor(3 ln n)``.
        bounds: ``(lower, upper)``, each (n,) or a scalar, ``lower < upper`` (infinite allowed), with ``x0``
            inside; every candidate is then inside too.  ``None``: unbounded.
        executor: ``None``: a process pool of ``min(population, os.cpu_count())`` workers, created for the run
            and shut down at its end (the platform's default start method, ``fork`` on Linux before Python
            3.14; the objective is checked to pickle, so ``spawn`` and ``forkserver`` work too).
            ``"serial"``: evaluate in this process.  An :class:`~concurrent.futures.Executor` (e.g. a Dask
            ``Client.get_executor()``): used unchanged via ``submit`` and left open.
        progress: Show a tqdm bar over generations with the best fitness so far.
        failure_fitness: Finite fitness told to CMA-ES for a failed evaluation.  Default: ``10 x`` the worst
            finite fitness seen so far (this generation included); ``1e6`` if there is none, ``worst + 1e6`` if
            it is not positive.
        tol_fun: cma's ``tolfun`` (>= 0): stop once the fitness values of the last generation, and the best
            values of the last ``floor(10 + 30 n / population)`` generations, each span less.
        tol_x: cma's ``tolx`` (>= 0, in the units of ``x``): stop once every coordinate's step size
            (``sigma sqrt(C_ii)``, and the evolution path) is below it.  ``None``: cma's default (1e-11).
        max_evaluations: cma's ``maxfevals`` (>= 1), a safety cap: the run stops after the first generation
            that takes the evaluation count past it (at most one generation more).  ``None``: no cap.

    cma's other default criteria (``tolstagnation``, ``tolflatfitness``, ``tolfunhist``, ``tolxstagnation``,
    ``tolconditioncov``, ...) stay active; :attr:`TuningResult.criteria` says which fired.

    Returns:
        The :class:`TuningResult`; ``stop`` says whether ``max_generations`` or a cma criterion ended the run.

    Raises:
        InputError: On a bad argument.
        TuningError: If every candidate of a generation fails, or the executor fails (``submit`` raises, it is
            shut down, a worker process dies); ``.partial`` keeps every evaluation finished before.
    """
    x0 = _as_start(x0)
    sigma0 = as_positive(sigma0, "sigma0")
    seed = _as_int(seed, "seed", minimum=0)
    max_generations = _as_int(max_generations, "max_generations", minimum=1)
    population = None if population is None else _as_int(population, "population", minimum=2)
    lower, upper = _as_bounds(bounds, x0)
    failure_fitness = None if failure_fitness is None else as_real(failure_fitness, "failure_fitness", False)
    tol_fun = as_real(tol_fun, "tol_fun")
    options: dict[str, Any] = {"tolfun": tol_fun, "maxiter": max_generations}
    if tol_x is not None:
        options["tolx"] = as_real(tol_x, "tol_x")
    if max_evaluations is not None:
        options["maxfevals"] = _as_int(max_evaluations, "max_evaluations", minimum=1)
    _check_objective_and_executor(objective, executor)
    strategy = _strategy(x0, sigma0, seed, population, lower, upper, options)
    run = _Run(objective, strategy, max_generations, failure_fitness, progress)
    workers = min(strategy.popsize, os.cpu_count() or 1)
    with executor_for(executor, workers) as runner:
        return run.execute(runner)


class _Run:
    """The ask/evaluate/tell loop of one :func:`cma_es` call."""

    def __init__(
        self, objective: Objective, strategy: Any, max_generations: int, failure_fitness: float | None, progress: bool
    ) -> None:
        self.objective = objective
        self.strategy = strategy
        self.max_generations = max_generations
        self.failure_fitness = failure_fitness
        self.progress = progress
        self.history = _History(strategy.N)

    def execute(self, executor: Executor | Literal["serial"]) -> TuningResult:
        """Run every generation, evaluating on ``executor`` (``"serial"``: in this process)."""
        bar = progress_bar(self.max_generations, "CMA-ES", "generation", enabled=self.progress)
        try:
            for generation in range(self.max_generations):
                stop = self._generation(generation, executor)
                bar.set_postfix(best=f"{min(self.history.generation_best):.6g}", refresh=False)
                bar.update()
                if stop:
                    return self.history.result(stop, self.strategy.stop())
            return self.history.result("max_generations", self.strategy.stop())
        finally:
            bar.close()

    def _generation(self, generation: int, executor: Executor | Literal["serial"]) -> str:
        """Ask, evaluate and tell one generation; return why to stop, or ``""`` to go on."""
        candidates = self.strategy.ask()
        outcomes, broken = _evaluate(executor, self.objective, candidates)
        self.history.record(generation, candidates, outcomes)
        if broken is not None:
            message = f"the executor failed in generation {generation}: {describe_error(broken)}"
            raise TuningError(message, self.history.result(message)) from broken
        if all(outcome.error is not None for outcome in outcomes):
            first = self.history.failures[-len(outcomes)]
            message = f"all {len(outcomes)} candidates of generation {generation} failed: {first}"
            raise TuningError(message, self.history.result(message)) from outcomes[0].error
        penalty = self._penalty()
        self.strategy.tell(candidates, [penalty if o.error is not None else o.fitness for o in outcomes])
        self.history.generation_best.append(min(outcome.fitness for outcome in outcomes))
        self.history.sigma.append(float(self.strategy.sigma))
        return _stop_reason(self.strategy)

    def _penalty(self) -> float:
        """The finite fitness told to CMA-ES for a failed evaluation."""
        if self.failure_fitness is not None:
            return self.failure_fitness
        worst = self.history.worst_finite()
        if worst is None or worst <= 0.0:
            return PENALTY_WITHOUT_FITNESS if worst is None else worst + PENALTY_WITHOUT_FITNESS
        return min(PENALTY_FACTOR * worst, float(np.finfo(np.float64).max))


def _evaluate(
    executor: Executor | Literal["serial"], objective: Objective, candidates: list[np.ndarray]
) -> tuple[list[_Outcome], BaseException | None]:
    """A generation's evaluations in candidate order, and the executor's failure (``None`` if it worked).

    Each candidate is evaluated on a copy, so an objective cannot alter what CMA-ES is told; after an executor's
    failure the evaluations already finished are kept.  A :class:`BatchedObjective` is called with ``size``
    candidates at a time, one task each.
    """
    batched = isinstance(objective, BatchedObjective)
    function = objective.function if batched else objective
    outcomes, broken = [], None
    xs = [x.copy() for x in candidates]
    for outcome in parallel_map(function, xs, executor, batch=objective.size if batched else None):
        if outcome.lost:
            broken = broken or outcome.error
        elif outcome.error is not None:
            outcomes.append(_Outcome(outcome.index, error=outcome.error))
        else:
            try:
                outcomes.append(_Outcome(outcome.index, fitness=_as_fitness(outcome.value)))
            except Exception as error:
                outcomes.append(_Outcome(outcome.index, error=error))
    return outcomes, broken


def _as_fitness(value: Any) -> float:
    """``value`` as a finite float, else raise ``TypeError``/``ValueError`` naming what the objective returned."""
    if isinstance(value, np.ndarray) and value.shape == () and value.dtype.kind in "iuf":
        value = value.item()
    if not isinstance(value, numbers.Real) or isinstance(value, (bool, np.bool_)):
        raise TypeError(f"objective returned {value!r}, not a number")
    number = float(value)
    if not math.isfinite(number):
        raise ValueError(f"objective returned {number!r}, not a finite number")
    return number


def _stop_reason(strategy: Any) -> str:
    """Why cma stops now, ``""`` if it does not; its ``maxiter`` (our ``max_generations``) gets our name."""
    criteria = dict(strategy.stop())
    if not criteria:
        return ""
    criteria.pop("maxiter", None)
    return str(criteria) if criteria else "max_generations"


def _strategy(
    x0: np.ndarray,
    sigma0: float,
    seed: int,
    population: int | None,
    lower: np.ndarray | None,
    upper: np.ndarray | None,
    termination: dict[str, Any],
) -> Any:
    """The ``cma.CMAEvolutionStrategy``, sampling from a generator of its own rather than numpy's global one."""
    import cma

    generator = np.random.default_rng(seed)

    def randn(*shape: int) -> np.ndarray:
        return generator.standard_normal(shape)

    options: dict[str, Any] = {
        "seed": math.nan,  # cma leaves numpy's global generator alone: sampling uses `randn` only
        "randn": randn,
        "verbose": -9,
        **termination,
    }
    if population is not None:
        options["popsize"] = population
    if lower is not None and upper is not None:
        options["bounds"] = [lower.tolist(), upper.tolist()]
    return cma.CMAEvolutionStrategy(x0.tolist(), sigma0, options)


def _as_start(x0: Any) -> np.ndarray:
    """``x0`` as a finite (n,) array, n >= 1."""
    x0 = as_vector(x0, "x0")
    if x0.size == 0:
        raise InputError("`x0` must hold at least 1 parameter, got shape (0,)")
    return x0.copy()


def _as_int(value: Any, name: str, minimum: int) -> int:
    """``value`` as an int >= ``minimum`` (bools and non-integral numbers are rejected)."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)) or value < minimum:
        raise InputError(f"`{name}` must be an int >= {minimum}, got {value!r}")
    return int(value)


def _as_bounds(bounds: Any, x0: np.ndarray) -> tuple[np.ndarray | None, np.ndarray | None]:
    """``(lower, upper)`` as (n,) arrays with ``lower < upper`` and ``lower <= x0 <= upper``, or ``(None, None)``."""
    if bounds is None:
        return None, None
    try:
        lower, upper = bounds
        lower, upper = (np.broadcast_to(np.asarray(b, dtype=np.float64), x0.shape).copy() for b in (lower, upper))
    except (TypeError, ValueError) as error:
        raise InputError(f"`bounds` must be (lower, upper), each a number or of shape {x0.shape}") from error
    if np.any(np.isnan(lower) | np.isnan(upper)):
        raise InputError(f"`bounds` must not hold NaN, got lower {lower}, upper {upper}")
    if np.any(lower >= upper):
        raise InputError(f"`bounds` need lower < upper, got lower {lower}, upper {upper}")
    if np.any((x0 < lower) | (x0 > upper)):
        raise InputError(f"`x0` = {x0} must lie within `bounds`, lower {lower}, upper {upper}")
    return lower, upper


def _check_objective_and_executor(objective: Any, executor: Any) -> None:
    """Require a callable objective, a valid executor, and a picklable objective for the default process pool."""
    if not callable(objective):
        raise InputError(f"`objective` must be callable, got {objective!r}")
    if isinstance(executor, str) and executor != "serial":
        raise InputError(f"`executor` must be None, 'serial' or a concurrent.futures.Executor, got {executor!r}")
    if executor is not None and not isinstance(executor, str) and not callable(getattr(executor, "submit", None)):
        raise InputError(f"`executor` must have a submit() method like concurrent.futures.Executor, got {executor!r}")
    if executor is None:
        try:
            pickle.dumps(objective)
        except Exception as error:
            raise InputError(
                "`objective` must be picklable to run in a process pool (a top-level function or a "
                f"functools.partial of one), got {objective!r}; or pass executor='serial'"
            ) from error


__all__ = ["BatchedObjective", "TuningError", "TuningResult", "cma_es"]
