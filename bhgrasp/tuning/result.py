"""What a CMA-ES run records: each evaluation, the history so far, the result and the error that carries it."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from bhgrasp.errors import BhgraspError
from bhgrasp.parallel import describe_error


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
class Evaluation:
    """One finished evaluation: the candidate index and its fitness, or the error it raised."""

    index: int
    fitness: float = math.inf
    error: Exception | None = None


@dataclass
class History:
    """The record of a run so far, turned into a :class:`TuningResult` by :meth:`result`."""

    n: int
    parameters: list[np.ndarray] = field(default_factory=list)
    fitness: list[float] = field(default_factory=list)
    generation_best: list[float] = field(default_factory=list)
    sigma: list[float] = field(default_factory=list)
    failures: list[str] = field(default_factory=list)

    def record(self, generation: int, candidates: list[np.ndarray], outcomes: list[Evaluation]) -> None:
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


__all__ = ["Evaluation", "History", "TuningError", "TuningResult"]
