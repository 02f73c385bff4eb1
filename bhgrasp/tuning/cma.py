"""The CMA-ES loop: ask a generation, evaluate it on the parallel map, tell cma, stop on its criteria or a cap."""

from __future__ import annotations

import math
import numbers
import os
from collections.abc import Callable
from concurrent.futures import Executor
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np

from bhgrasp._validation import as_int, as_positive, as_real
from bhgrasp.errors import InputError
from bhgrasp.parallel import describe_error, executor_for, parallel_map, progress_bar
from bhgrasp.tuning.arguments import as_bounds, as_start, check_objective_and_executor
from bhgrasp.tuning.result import Evaluation, History, TuningError, TuningResult

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
    x0 = as_start(x0)
    sigma0 = as_positive(sigma0, "sigma0")
    seed = as_int(seed, "seed", minimum=0)
    max_generations = as_int(max_generations, "max_generations", minimum=1)
    population = None if population is None else as_int(population, "population", minimum=2)
    lower, upper = as_bounds(bounds, x0)
    failure_fitness = None if failure_fitness is None else as_real(failure_fitness, "failure_fitness", False)
    tol_fun = as_real(tol_fun, "tol_fun")
    options: dict[str, Any] = {"tolfun": tol_fun, "maxiter": max_generations}
    if tol_x is not None:
        options["tolx"] = as_real(tol_x, "tol_x")
    if max_evaluations is not None:
        options["maxfevals"] = as_int(max_evaluations, "max_evaluations", minimum=1)
    check_objective_and_executor(objective, executor)
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
        self.history = History(strategy.N)

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
) -> tuple[list[Evaluation], BaseException | None]:
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
            outcomes.append(Evaluation(outcome.index, error=outcome.error))
        else:
            try:
                outcomes.append(Evaluation(outcome.index, fitness=_as_fitness(outcome.value)))
            except Exception as error:
                outcomes.append(Evaluation(outcome.index, error=error))
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


__all__ = ["PENALTY_FACTOR", "PENALTY_WITHOUT_FITNESS", "BatchedObjective", "Objective", "cma_es"]
