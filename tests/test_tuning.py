"""CMA-ES tuning against known minimisers (shifted sphere, Rosenbrock), and its determinism and failure handling.

The objectives are top-level functions of this module, so process-pool and Dask workers can unpickle them by
reference: pytest's default "prepend" import mode puts ``tests/`` on ``sys.path`` and imports this file as
``test_tuning``, and spawned workers inherit the parent's ``sys.path``.  The default process pool uses the
platform's start method (``fork`` on Linux before Python 3.14); a ``spawn`` pool is tested explicitly too.
"""

from __future__ import annotations

import functools
import math
import multiprocessing
import os
import subprocess
import sys
from concurrent.futures import Executor, Future, ProcessPoolExecutor, ThreadPoolExecutor
from typing import Any

import numpy as np
import pytest

from bhgrasp.errors import InputError
from bhgrasp.tuning import TuningError, TuningResult, cma_es

CENTRE = np.array([3.0, -2.0, 1.0])
ARRAY_FIELDS = ("best", "history_parameters", "history_fitness", "generation_best", "sigma")


def shifted_sphere(x: np.ndarray, centre: np.ndarray = CENTRE) -> float:
    return float(np.sum((x - centre) ** 2))


def rosenbrock(x: np.ndarray) -> float:
    return float(100.0 * (x[1] - x[0] ** 2) ** 2 + (1.0 - x[0]) ** 2)


ROSENBROCK_SHIFT = np.array([-1.3, 0.4])  # the shifted Rosenbrock's minimum (0 there)


def shifted_rosenbrock(x: np.ndarray) -> float:
    return rosenbrock(np.asarray(x) - ROSENBROCK_SHIFT + 1.0)


def sphere_touching_global_rng(x: np.ndarray) -> float:
    np.random.random(3)  # noqa: NPY002  (deliberately) consumes numpy's global generator: must not change what CMA-ES samples
    return shifted_sphere(x)


def sphere_failing_right(x: np.ndarray) -> float:
    if x[0] > 4.0:
        raise ValueError(f"x[0] = {x[0]:.3f} is too far right")
    return shifted_sphere(x)


def sphere_returning_junk(x: np.ndarray) -> Any:
    if x[1] > 1.0:
        return math.nan
    if x[2] > 2.0:
        return "not a number"
    return shifted_sphere(x)


def always_failing(x: np.ndarray) -> float:
    raise RuntimeError("simulation diverged")


def sphere_killing_worker(x: np.ndarray) -> float:
    if x[0] > 1.0:
        os._exit(1)  # the worker process dies: the pool breaks
    return shifted_sphere(x)


def assert_same_result(a: TuningResult, b: TuningResult) -> None:
    for name in ARRAY_FIELDS:
        assert np.array_equal(getattr(a, name), getattr(b, name), equal_nan=True), name
    assert (a.best_fitness, a.generations, a.evaluations, a.failures, a.stop, a.criteria) == (
        b.best_fitness,
        b.generations,
        b.evaluations,
        b.failures,
        b.stop,
        b.criteria,
    )


def assert_stop_is_real(result: TuningResult, n: int, population: int, tol_fun: float, tol_x: float) -> None:
    """Check the criteria cma reports against the run's own history, by cma's definitions.

    tolfun: the last generation's fitness values, and the best values of the last 10 + 30 n / population
    generations, each span less than tol_fun.  tolx: every step size sigma sqrt(C_ii) is below tol_x, so the last
    generation's candidates (mean + sigma N(0, C), 6 standard deviations cover any of 6 samples) lie within a few
    tol_x of each other (bounds only shrink distances: cma's boundary transform has slope <= 1).
    """
    assert set(result.criteria) <= {"tolfun", "tolx", "tolfunhist"} and result.criteria, result.criteria
    assert "tolfun" in result.criteria or "tolx" in result.criteria
    last = slice(result.evaluations - population, None)
    recent = result.generation_best[-int(10 + 30 * n / population) :]
    if "tolfun" in result.criteria:
        assert result.criteria["tolfun"] == tol_fun
        assert np.ptp(result.history_fitness[last]) < tol_fun and np.ptp(recent) < tol_fun
    if "tolfunhist" in result.criteria:  # cma's default 1e-12 on the same history
        assert len(recent) > 9 and np.ptp(recent) < result.criteria["tolfunhist"]
    if "tolx" in result.criteria:
        assert result.criteria["tolx"] == tol_x
        assert np.all(np.ptp(result.history_parameters[last], axis=0) < 12.0 * tol_x)
    assert result.stop == str(result.criteria)


@pytest.fixture(scope="module")
def serial_sphere() -> TuningResult:
    """The serial reference run that the parallel executors must reproduce exactly."""
    return cma_es(shifted_sphere, np.zeros(3), 1.0, seed=7, max_generations=25, population=6, executor="serial")


class SubmitFailsAfter(Executor):
    """Evaluates synchronously in ``submit``; the call after the first ``limit`` raises, as a lost cluster would."""

    def __init__(self, limit: int) -> None:
        self.limit = limit
        self.submitted = 0

    def submit(self, fn: Any, /, *args: Any, **kwargs: Any) -> Future:
        if self.submitted == self.limit:
            raise RuntimeError("connection to the cluster lost")
        self.submitted += 1
        future: Future = Future()
        try:
            future.set_result(fn(*args, **kwargs))
        except Exception as error:
            future.set_exception(error)
        return future


# --- convergence -----------------------------------------------------------------------------------------------


def test_shifted_sphere_converges_from_a_far_start_to_its_centre() -> None:
    result = cma_es(shifted_sphere, [10.0, 10.0, 10.0], 2.0, seed=1, max_generations=300, executor="serial")
    population = 4 + math.floor(3 * math.log(3))  # cma's default
    assert np.max(np.abs(result.best - CENTRE)) < 1e-4
    assert result.best_fitness == shifted_sphere(result.best)
    assert "tolfun" in result.stop and result.generations < 300  # stopped by tol_fun, not the generation cap
    assert result.evaluations == result.generations * population
    assert result.history_parameters.shape == (result.evaluations, 3)
    assert result.history_fitness.shape == (result.evaluations,)
    assert result.generation_best.shape == result.sigma.shape == (result.generations,)
    per_generation = result.history_fitness.reshape(result.generations, population)
    assert np.array_equal(result.generation_best, per_generation.min(axis=1))
    assert np.array_equal(result.history_fitness, [shifted_sphere(x) for x in result.history_parameters])
    running = np.minimum.accumulate(result.generation_best)
    assert np.all(np.diff(running) <= 0.0) and running[-1] == result.best_fitness
    assert result.generation_best[0] > 1e2 and result.sigma[-1] < 1e-3  # it really travelled and contracted
    assert result.failures == ()


def test_one_parameter_is_supported() -> None:
    result = cma_es(functools.partial(shifted_sphere, centre=np.array([-4.0])), [5.0], 1.0, seed=3, executor="serial")
    assert abs(result.best[0] + 4.0) < 1e-4


def test_rosenbrock_reaches_its_minimum_at_one_one() -> None:
    result = cma_es(rosenbrock, [-1.2, 1.0], 0.5, seed=2, max_generations=600, executor="serial", tol_fun=1e-14)
    assert np.max(np.abs(result.best - 1.0)) < 1e-3
    assert result.best_fitness == rosenbrock(result.best)


def test_bounded_shifted_rosenbrock_stops_on_cma_criteria_at_its_minimum() -> None:
    result = cma_es(
        shifted_rosenbrock,
        [0.0, 0.0],
        0.5,
        seed=3,
        max_generations=5000,
        bounds=([-2.0, -1.0], [1.0, 2.0]),
        executor="serial",
        tol_fun=1e-12,
        tol_x=1e-8,
        max_evaluations=20_000,
    )
    assert np.max(np.abs(result.best - ROSENBROCK_SHIFT)) < 1e-4
    assert result.best_fitness < 1e-10 and result.evaluations < 20_000
    assert_stop_is_real(result, 2, 6, 1e-12, 1e-8)


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_a_minimum_on_a_bound_is_found_and_the_stop_criterion_holds(seed: int) -> None:
    """Sphere centred at (1.5, -0.7) in the box [-1, 1]^2: the constrained minimum (1, -0.7) is on the bound x = 1."""
    centre = np.array([1.5, -0.7])
    objective = functools.partial(shifted_sphere, centre=centre)
    result = cma_es(
        objective,
        [0.0, 0.0],
        0.5,
        seed=seed,
        max_generations=5000,
        bounds=(-1.0, 1.0),
        executor="serial",
        tol_fun=1e-11,
        tol_x=1e-7,
        max_evaluations=20_000,
    )
    assert np.all(result.history_parameters <= 1.0) and np.all(result.history_parameters >= -1.0)
    assert np.max(np.abs(result.best - [1.0, -0.7])) < 1e-4
    assert result.best_fitness == pytest.approx(0.25, abs=1e-8)  # (1.5 - 1)^2
    assert_stop_is_real(result, 2, 6, 1e-11, 1e-7)


def test_the_evaluation_cap_stops_a_run_that_has_not_converged() -> None:
    result = cma_es(
        shifted_rosenbrock,
        [0.0, 0.0],
        0.5,
        seed=3,
        max_generations=5000,
        executor="serial",
        tol_fun=1e-12,
        tol_x=1e-8,
        max_evaluations=60,
    )
    assert result.criteria == {"maxfevals": 60}
    assert 60 < result.evaluations <= 60 + 6  # cma stops after the first generation past the cap
    assert result.stop == "{'maxfevals': 60}"
    capped = cma_es(shifted_sphere, np.zeros(3), 1.0, seed=7, max_generations=5, executor="serial")
    assert capped.stop == "max_generations" and capped.criteria == {"maxiter": 5}


def test_bounded_runs_to_convergence_are_deterministic_per_seed() -> None:
    def run(seed: int) -> TuningResult:
        return cma_es(
            shifted_rosenbrock,
            [0.0, 0.0],
            0.5,
            seed=seed,
            max_generations=5000,
            bounds=([-2.0, -1.0], [1.0, 2.0]),
            executor="serial",
            tol_fun=1e-10,
            tol_x=1e-6,
        )

    first, again, other = run(5), run(5), run(6)
    assert_same_result(first, again)
    assert not np.array_equal(first.history_parameters[:6], other.history_parameters[:6])


# --- determinism and executors ---------------------------------------------------------------------------------


def test_same_seed_gives_a_bitwise_identical_result_and_another_seed_does_not() -> None:
    def run(seed: int, global_seed: int) -> TuningResult:
        np.random.seed(global_seed)  # noqa: NPY002  numpy's global generator is not what CMA-ES samples from
        return cma_es(sphere_touching_global_rng, np.zeros(3), 1.0, seed=seed, max_generations=15, executor="serial")

    first, again, other = run(11, 0), run(11, 12345), run(12, 0)
    assert_same_result(first, again)
    assert first.history_parameters.shape == other.history_parameters.shape
    assert not np.array_equal(first.history_parameters, other.history_parameters)
    assert not np.array_equal(first.history_parameters[0], other.history_parameters[0])


def test_default_process_pool_reproduces_the_serial_run(serial_sphere: TuningResult) -> None:
    # The pool uses multiprocessing's default start method: "fork" here (Linux, Python < 3.14), "spawn" on
    # macOS/Windows, "forkserver" on Linux from Python 3.14; the spawn test below covers the non-fork methods.
    objective = functools.partial(shifted_sphere, centre=CENTRE)  # a partial of a top-level function pickles
    assert_same_result(cma_es(objective, np.zeros(3), 1.0, seed=7, max_generations=25, population=6), serial_sphere)


def test_spawn_process_pool_reproduces_the_serial_run(serial_sphere: TuningResult) -> None:
    with ProcessPoolExecutor(max_workers=2, mp_context=multiprocessing.get_context("spawn")) as pool:
        result = cma_es(shifted_sphere, np.zeros(3), 1.0, seed=7, max_generations=25, population=6, executor=pool)
    assert_same_result(result, serial_sphere)


@pytest.mark.parametrize("processes", [False, True], ids=["threads", "processes"])
def test_dask_client_executor_reproduces_the_serial_run(serial_sphere: TuningResult, processes: bool) -> None:
    distributed = pytest.importorskip("distributed")
    with (
        distributed.LocalCluster(
            n_workers=2, threads_per_worker=1, processes=processes, dashboard_address=None
        ) as cluster,
        distributed.Client(cluster) as client,
    ):
        executor = client.get_executor()
        result = cma_es(shifted_sphere, np.zeros(3), 1.0, seed=7, max_generations=25, population=6, executor=executor)
    assert_same_result(result, serial_sphere)


def test_progress_bar_shows_generations(capsys: pytest.CaptureFixture[str]) -> None:
    cma_es(shifted_sphere, np.zeros(3), 1.0, seed=7, max_generations=5, executor="serial", progress=True)
    err = capsys.readouterr().err
    assert "CMA-ES" in err and "5/5" in err and "best=" in err


# --- failures --------------------------------------------------------------------------------------------------


def test_failing_candidates_are_recorded_and_penalised(monkeypatch: pytest.MonkeyPatch) -> None:
    import cma

    told: list[list[float]] = []
    tell = cma.CMAEvolutionStrategy.tell

    def spy(self: Any, solutions: Any, function_values: Any, *args: Any, **kwargs: Any) -> Any:
        told.append(list(function_values))
        return tell(self, solutions, function_values, *args, **kwargs)

    monkeypatch.setattr(cma.CMAEvolutionStrategy, "tell", spy)
    result = cma_es(sphere_failing_right, np.zeros(3), 3.0, seed=5, max_generations=120, executor="serial")
    failed = ~np.isfinite(result.history_fitness)
    assert 0 < failed.sum() == len(result.failures)
    assert np.all(np.isinf(result.history_fitness[failed]))
    assert np.all(result.history_parameters[failed, 0] > 4.0) and np.all(result.history_parameters[~failed, 0] <= 4.0)
    assert all(": ValueError: x[0] = " in f and "is too far right" in f for f in result.failures)
    population = len(told[0])
    first = int(np.flatnonzero(failed)[0])
    generation, candidate = divmod(first, population)
    assert result.failures[0].startswith(f"generation {generation}, candidate {candidate}: ")
    assert np.max(np.abs(result.best - CENTRE)) < 1e-4 and result.best_fitness == shifted_sphere(result.best)
    assert len(told) == result.generations and np.all(np.isfinite(told))  # CMA-ES never sees inf/NaN
    seen = result.history_fitness[: (generation + 1) * population]
    assert told[generation][candidate] == 10.0 * seen[np.isfinite(seen)].max()  # 10 x the worst finite so far


def test_nan_and_non_numbers_count_as_failures() -> None:
    result = cma_es(
        sphere_returning_junk, np.zeros(3), 1.5, seed=4, max_generations=10, executor="serial", failure_fitness=1e3
    )
    assert any("ValueError: objective returned nan, not a finite number" in f for f in result.failures)
    assert any("TypeError: objective returned 'not a number', not a number" in f for f in result.failures)
    assert np.isinf(result.history_fitness).sum() == len(result.failures)
    assert np.isfinite(result.best_fitness)


def test_a_generation_that_fails_entirely_raises_with_the_partial_result() -> None:
    with pytest.raises(
        TuningError,
        match=r"all 5 candidates of generation 0 failed: generation 0, candidate 0: "
        r"RuntimeError: simulation diverged",
    ) as caught:
        cma_es(always_failing, np.zeros(2), 1.0, seed=1, population=5, executor="serial")
    partial = caught.value.partial
    assert (partial.generations, partial.evaluations, len(partial.failures)) == (0, 5, 5)
    assert partial.history_parameters.shape == (5, 2) and np.all(np.isinf(partial.history_fitness))
    assert np.all(np.isnan(partial.best)) and partial.best_fitness == math.inf
    assert partial.failures[4] == "generation 0, candidate 4: RuntimeError: simulation diverged"
    assert isinstance(caught.value, RuntimeError)


def test_executor_whose_submit_fails_keeps_every_finished_evaluation() -> None:
    reference = cma_es(shifted_sphere, np.zeros(3), 1.0, seed=9, max_generations=5, population=4, executor="serial")
    failing = SubmitFailsAfter(10)
    with pytest.raises(
        TuningError, match=r"executor failed in generation 2: RuntimeError: connection to the"
    ) as caught:
        cma_es(shifted_sphere, np.zeros(3), 1.0, seed=9, max_generations=5, population=4, executor=failing)
    partial = caught.value.partial
    assert (partial.generations, partial.evaluations) == (2, 10)  # 2 full generations + 2 candidates of the third
    assert np.array_equal(partial.history_parameters, reference.history_parameters[:10])
    assert np.array_equal(partial.history_fitness, reference.history_fitness[:10])
    assert np.array_equal(partial.sigma, reference.sigma[:2])
    assert partial.best_fitness == reference.history_fitness[:10].min()


def test_shut_down_executor_raises_tuning_error() -> None:
    pool = ThreadPoolExecutor(max_workers=1)
    pool.shutdown()
    with pytest.raises(TuningError, match=r"generation 0: RuntimeError: cannot schedule new futures") as caught:
        cma_es(shifted_sphere, np.zeros(3), 1.0, seed=1, executor=pool)
    assert caught.value.partial.evaluations == 0


@pytest.mark.skipif(sys.platform == "win32", reason="os._exit in a worker")
def test_a_dying_worker_breaks_the_pool_and_raises_tuning_error() -> None:
    with pytest.raises(TuningError, match=r"executor failed in generation \d+: BrokenProcessPool") as caught:
        cma_es(sphere_killing_worker, np.zeros(3), 1.0, seed=3, max_generations=30, population=4)
    partial = caught.value.partial
    finite = np.isfinite(partial.history_fitness)
    assert partial.evaluations >= 4 * partial.generations
    assert np.all(finite)  # a candidate lost with the worker is not recorded, not even as a failure
    assert np.array_equal(partial.history_fitness, [shifted_sphere(x) for x in partial.history_parameters])


# --- bounds and validation -------------------------------------------------------------------------------------


def test_every_candidate_respects_the_bounds() -> None:
    lower, upper = np.array([0.0, 0.0, -np.inf]), np.array([1.0, 1.0, 0.5])
    result = cma_es(
        shifted_sphere, [0.5, 0.5, 0.0], 0.3, seed=6, max_generations=80, bounds=(lower, upper), executor="serial"
    )
    assert np.all(result.history_parameters >= lower) and np.all(result.history_parameters <= upper)
    assert np.max(np.abs(result.best - [1.0, 0.0, 0.5])) < 1e-2  # the optimum clipped to the box


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"x0": [0.0, math.nan]}, r"`x0` must be finite"),
        ({"x0": []}, r"`x0` must hold at least 1 parameter"),
        ({"x0": np.zeros((2, 2))}, r"`x0` must have shape"),
        ({"sigma0": 0.0}, r"`sigma0` must be a positive"),
        ({"sigma0": -1.0}, r"`sigma0` must be a positive"),
        ({"seed": None}, r"`seed` must be an int >= 0"),
        ({"seed": 1.5}, r"`seed` must be an int >= 0"),
        ({"seed": "3"}, r"`seed` must be an int >= 0"),
        ({"seed": True}, r"`seed` must be an int >= 0"),
        ({"seed": -1}, r"`seed` must be an int >= 0"),
        ({"population": 1}, r"`population` must be an int >= 2"),
        ({"population": 4.0}, r"`population` must be an int >= 2"),
        ({"max_generations": 0}, r"`max_generations` must be an int >= 1"),
        ({"bounds": ([0.0, 1.0], [1.0, 1.0])}, r"lower < upper"),
        ({"bounds": ([1.0, 1.0], [0.0, 2.0])}, r"lower < upper"),
        ({"bounds": ([0.5, -1.0], [1.0, 1.0])}, r"`x0` = .* must lie within `bounds`"),
        ({"bounds": ([0.0, 0.0, 0.0], [1.0, 1.0, 1.0])}, r"`bounds` must be \(lower, upper\)"),
        ({"bounds": ([math.nan, 0.0], [1.0, 1.0])}, r"`bounds` must not hold NaN"),
        ({"executor": "threads"}, r"`executor` must be None, 'serial'"),
        ({"executor": object()}, r"`executor` must have a submit\(\) method"),
        ({"failure_fitness": math.inf}, r"`failure_fitness` must be a finite number"),
        ({"tol_fun": -1.0}, r"`tol_fun` must be a finite number >= 0"),
        ({"tol_x": -1.0}, r"`tol_x` must be a finite number >= 0"),
        ({"tol_x": math.nan}, r"`tol_x` must be a finite number >= 0"),
        ({"max_evaluations": 0}, r"`max_evaluations` must be an int >= 1"),
        ({"max_evaluations": 10.0}, r"`max_evaluations` must be an int >= 1"),
        ({"objective": 3.0}, r"`objective` must be callable"),
        ({"objective": lambda x: 0.0, "executor": None}, r"`objective` must be picklable"),
    ],
)
def test_bad_inputs_raise_input_error(kwargs: dict[str, Any], message: str) -> None:
    arguments: dict[str, Any] = {"objective": shifted_sphere, "x0": [0.0, 0.0], "seed": 1, "executor": "serial"}
    with pytest.raises(InputError, match=message):
        cma_es(**(arguments | kwargs))


def test_the_seed_is_a_required_argument() -> None:
    with pytest.raises(TypeError, match="seed"):
        cma_es(shifted_sphere, [0.0, 0.0], executor="serial")  # type: ignore[call-arg]


def test_importing_tuning_does_not_import_cma_tqdm_or_dask() -> None:
    code = (
        "import sys, bhgrasp.tuning; "
        "loaded = [m for m in sys.modules if m.split('.')[0] in ('cma', 'tqdm', 'dask', 'distributed')]; "
        "assert not loaded, loaded"
    )
    subprocess.run([sys.executable, "-c", code], check=True)


# ---------------------------------------------------------------------- batched objectives
def hold_cost_batch(candidates: list[np.ndarray]) -> list[float]:
    """The reference hold for many (log10 posture gain, squeeze scale) at once in a BatchSimulator: the box's fall
    [mm] over 0.1 s plus 0.5 x the squeeze scale (a squeeze costs effort); one value per candidate."""
    from bhgrasp.scenarios.hold import SQUEEZE, reference_hold
    from bhgrasp.sim.batch import BatchSimulator

    hold = reference_hold()
    q0, fingers, forces = hold.state.q, list(SQUEEZE), np.array(list(SQUEEZE.values()))
    gain = np.array([10.0 ** x[0] for x in candidates])
    squeeze = np.array([x[1] for x in candidates])

    def controller(t, batch):
        tips = np.einsum("nkij,ki->nj", batch.fingertip_jacobians(fingers), forces)
        return batch.gravity_torques() + gain[:, None] * (q0 - batch.q) + squeeze[:, None] * tips

    batch = BatchSimulator(hold.simulator, [hold.state] * len(candidates)).run(controller, 0.1)
    drop = 1e3 * (hold.box_height - batch.object_positions()[:, 2])
    return [float(d + 0.5 * s) for d, s in zip(drop, squeeze)]


def test_a_batched_objective_gives_the_run_of_its_candidates_one_by_one() -> None:
    """A generation evaluated in batches of 3 (one BatchSimulator each) or one candidate at a time, serially or on
    a process pool: a batch gives the bits of separate runs, so CMA-ES takes the same path to the bit."""
    from bhgrasp.tuning import BatchedObjective

    settings = {
        "x0": [0.3, 0.8],
        "sigma0": 0.2,
        "seed": 3,
        "max_generations": 3,
        "population": 5,
        "bounds": ([-1.0, 0.05], [1.0, 2.0]),
    }
    batched = cma_es(BatchedObjective(hold_cost_batch, size=3), executor="serial", **settings)
    alone = cma_es(BatchedObjective(hold_cost_batch, size=1), executor="serial", **settings)
    pooled = cma_es(BatchedObjective(hold_cost_batch, size=3), executor=None, **settings)
    for other in (alone, pooled):
        for name in ARRAY_FIELDS:
            np.testing.assert_array_equal(getattr(other, name), getattr(batched, name))
    assert batched.evaluations == 15 and np.isfinite(batched.history_fitness).all()


def failing_batch(candidates: list[np.ndarray]) -> list[float]:
    """NaN for a candidate whose first coordinate is negative; the whole call fails if one exceeds 2."""
    if any(x[0] > 2.0 for x in candidates):
        raise RuntimeError("a candidate beyond 2")
    return [float("nan") if x[0] < 0.0 else float(np.sum(x**2)) for x in candidates]


def test_a_batched_call_that_fails_fails_its_candidates_only() -> None:
    from bhgrasp.tuning import BatchedObjective

    result = cma_es(
        BatchedObjective(failing_batch, size=2),
        x0=[0.5, 0.5],
        sigma0=1.5,
        seed=0,
        max_generations=4,
        population=6,
        executor="serial",
    )
    assert any("not a finite number" in failure for failure in result.failures)
    assert any("RuntimeError: a candidate beyond 2" in failure for failure in result.failures)
    assert np.isfinite(result.best_fitness)
    with pytest.raises(InputError, match="`size` must be a positive integer"):
        BatchedObjective(failing_batch, size=0)
