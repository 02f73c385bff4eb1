"""One parallel map: a function over items, here, on a local process pool or on any Executor (a Dask cluster too).

:func:`parallel_map` submits every item (or every chunk of ``batch`` items) at once and yields one
:class:`Outcome` per item, in item order or as they finish.  A call that raises is an outcome with its ``error``,
never an exception of the map, so one bad case cannot stop a sweep; a task the executor itself loses (a worker
process that died, a pool shut down, ``submit`` refused) is an outcome with ``lost = True``, so a caller can tell
a broken executor from a failed case.  :func:`executor_for` gives the executor a run submits to: ``"serial"`` (this
process), one it creates and shuts down (``None``: a process pool), or the caller's, used unchanged and left open
(e.g. ``distributed.Client(...).get_executor()``).  :func:`progress_bar` is the one tqdm bar the runs show, on
stderr.

Used by the sweeps (:mod:`bhgrasp.sweep`, and through them the grasp benchmark), CMA-ES (:mod:`bhgrasp.tuning`)
and the thesis' chapter 4.  Results never depend on the executor: the outcomes carry their item's index.
"""

from __future__ import annotations

import asyncio
import os
import pickle
import time
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import BrokenExecutor, CancelledError, Executor, Future, ProcessPoolExecutor, as_completed
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any, Literal

from bhgrasp.errors import InputError

ExecutorLike = Executor | Literal["serial"] | None
EXECUTOR_FAILURES = (BrokenExecutor, CancelledError, asyncio.CancelledError)  # a future lost to its executor


@dataclass(frozen=True)
class Outcome:
    """One item's result.

    Attributes:
        index: The item's position in the mapped sequence.
        value: What the function returned (``None`` on a failure).
        error: The exception it raised, or the executor's if the task was lost; ``None`` on success.
        lost: True if the executor lost the task (it never ran, or its worker died): not the item's fault.
        wall_time: Seconds the call took where it ran (a batch's time shared among its items).
    """

    index: int
    value: Any = None
    error: BaseException | None = None
    lost: bool = False
    wall_time: float = 0.0

    @property
    def ok(self) -> bool:
        """True if the call returned."""
        return self.error is None

    def result(self) -> Any:
        """The value, or the error raised (as ``Future.result``)."""
        if self.error is not None:
            raise self.error
        return self.value


def call(task: tuple[Callable[..., Any], tuple[Any, ...]]) -> Any:
    """``function(*arguments)`` of ``task = (function, arguments)``: map it over tasks of different functions."""
    function, arguments = task
    return function(*arguments)


class RemoteError(Exception):
    """An exception of a worker that could not travel back as itself (it does not pickle): its type and message."""


def describe_error(error: BaseException) -> str:
    """``"<ExceptionType>: <message>"`` (a :class:`RemoteError` already reads so)."""
    return str(error) if isinstance(error, RemoteError) else f"{type(error).__name__}: {error}"


@contextmanager
def executor_for(executor: ExecutorLike, workers: int | None = None) -> Iterator[Executor | Literal["serial"]]:
    """The executor to submit to, shut down on exit if this call created it.

    Args:
        executor: ``None``: a :class:`~concurrent.futures.ProcessPoolExecutor` of ``workers`` processes (default the
            CPU count), created here and shut down (pending tasks cancelled) on exit.  ``"serial"``: run in this
            process.  Any :class:`~concurrent.futures.Executor`: used unchanged and left open.
        workers: Processes of the pool created for ``None`` (a positive int).

    Raises:
        InputError: ``executor`` is none of these, or ``workers`` is not a positive int.
    """
    if executor == "serial" or _submits(executor):
        yield executor
        return
    if executor is not None:
        raise InputError(f"`executor` must be None, 'serial' or a concurrent.futures.Executor, got {executor!r}")
    if workers is not None and (isinstance(workers, bool) or not isinstance(workers, int) or workers < 1):
        raise InputError(f"`workers` must be a positive integer (processes), got {workers!r}")
    pool = ProcessPoolExecutor(max_workers=workers or os.cpu_count() or 1)
    try:
        yield pool
    finally:
        pool.shutdown(wait=True, cancel_futures=True)


def parallel_map(
    function: Callable[[Any], Any],
    items: Sequence[Any],
    executor: Executor | Literal["serial"] = "serial",
    *,
    batch: int | None = None,
    ordered: bool = True,
    progress: str | None = None,
) -> Iterator[Outcome]:
    """``function`` over ``items``: every task submitted now, one :class:`Outcome` per item yielded as read.

    Args:
        function: Top-level (picklable, for a process pool) ``item -> value``; with ``batch``, ``list of items ->
            sequence of values``, one per item in order (a call that raises, or returns another count, fails each of
            its items).
        items: The inputs.
        executor: ``"serial"`` (each call made as the outcomes are read) or an
            :class:`~concurrent.futures.Executor` (see :func:`executor_for`).
        batch: Items per call (one task each); ``None``: one item per call.
        ordered: Yield in item order; ``False``: as the tasks finish (a batch's items together).
        progress: A tqdm bar with this label over the items, on stderr; ``None``: none.

    Returns:
        An iterator of outcomes; the tasks are already submitted when it is returned, so the caller may do other
        work (or map again on the same executor) before reading it.
    """
    if batch is not None and (isinstance(batch, bool) or not isinstance(batch, int) or batch < 1):
        raise InputError(f"`batch` must be a positive integer (items per call), got {batch!r}")
    if executor != "serial" and not _submits(executor):
        raise InputError(f"`executor` must be 'serial' or a concurrent.futures.Executor, got {executor!r}")
    size = batch or 1
    chunks = [list(range(start, min(start + size, len(items)))) for start in range(0, len(items), size)]
    call = _call_batch if batch is not None else _call_one
    bar = progress_bar(len(items), progress or "", "item", enabled=progress is not None)
    if executor == "serial":
        return _read_serial(call, function, items, chunks, bar)
    futures: list[Future | BaseException] = []
    for chunk in chunks:
        try:
            futures.append(executor.submit(call, function, chunk, [items[i] for i in chunk], True))
        except Exception as error:  # the executor refused: this task and every later one are lost
            futures += [error] * (len(chunks) - len(futures))
            break
    return _read_futures(futures, chunks, ordered, bar)


def _submits(executor: Any) -> bool:
    """True for an :class:`~concurrent.futures.Executor`, or anything with its ``submit`` (duck typing)."""
    if isinstance(executor, Executor):
        return True
    return not isinstance(executor, str) and callable(getattr(executor, "submit", None))


def _read_serial(call, function, items, chunks, bar) -> Iterator[Outcome]:
    try:
        for chunk in chunks:
            outcomes = call(function, chunk, [items[i] for i in chunk], False)
            bar.update(len(outcomes))
            yield from outcomes
    finally:
        bar.close()


def _read_futures(futures: list, chunks: list[list[int]], ordered: bool, bar) -> Iterator[Outcome]:
    tasks = list(zip(futures, chunks))
    pending = [future for future in futures if isinstance(future, Future)]
    if not ordered:
        chunk_of = {future: chunk for future, chunk in tasks if isinstance(future, Future)}
        refused = [(future, chunk) for future, chunk in tasks if not isinstance(future, Future)]
        tasks = [*((future, chunk_of[future]) for future in as_completed(pending)), *refused]
    try:
        for future, chunk in tasks:
            outcomes = _outcomes_of(future, chunk)
            bar.update(len(outcomes))
            yield from outcomes
    finally:
        bar.close()
        for future in pending:
            future.cancel()


def _outcomes_of(future: Future | BaseException, chunk: list[int]) -> list[Outcome]:
    """A task's outcomes, or each of its items lost with the executor's error."""
    if isinstance(future, BaseException):
        return [Outcome(index, error=future, lost=True) for index in chunk]
    try:
        return future.result()
    except EXECUTOR_FAILURES as error:
        return [Outcome(index, error=error, lost=True) for index in chunk]
    except Exception as error:  # e.g. Dask's KilledWorker: the task failed where it ran
        return [Outcome(index, error=error) for index in chunk]


def _call_one(function: Callable, chunk: list[int], items: list[Any], remote: bool) -> list[Outcome]:
    """One item's call as its outcome (runs in a worker, or here)."""
    start = time.perf_counter()
    try:
        value = function(items[0])
    except Exception as error:
        return [Outcome(chunk[0], error=_portable(error) if remote else error, wall_time=time.perf_counter() - start)]
    return [Outcome(chunk[0], value, wall_time=time.perf_counter() - start)]


def _call_batch(function: Callable, chunk: list[int], items: list[Any], remote: bool) -> list[Outcome]:
    """One batch's call as its items' outcomes (runs in a worker, or here); the call's time is shared."""
    start = time.perf_counter()
    try:
        values = list(function(list(items)))
        if len(values) != len(items):
            raise InputError(f"the batched function returned {len(values)} results for {len(items)} items")
    except Exception as error:
        wall = (time.perf_counter() - start) / len(items)
        error = _portable(error) if remote else error
        return [Outcome(index, error=error, wall_time=wall) for index in chunk]
    wall = (time.perf_counter() - start) / len(items)
    return [Outcome(index, value, wall_time=wall) for index, value in zip(chunk, values)]


def _portable(error: Exception) -> Exception:
    """``error`` if it survives pickling (to travel back from a worker), else a :class:`RemoteError` naming it."""
    try:
        pickle.loads(pickle.dumps(error))
    except Exception:
        return RemoteError(f"{type(error).__name__}: {error}")
    return error


class _Silent:
    """A progress bar that shows nothing."""

    def update(self, n: int = 1) -> None:
        """Nothing."""

    def set_postfix(self, **values: Any) -> None:
        """Nothing."""

    def close(self) -> None:
        """Nothing."""


def progress_bar(total: int, label: str, unit: str, *, initial: int = 0, enabled: bool = True) -> Any:
    """A tqdm bar over ``total`` ``unit``s named ``label``, on stderr; with ``enabled`` false, a silent one.

    Either has ``update``, ``set_postfix`` and ``close``.
    """
    if not enabled:
        return _Silent()
    from tqdm import tqdm

    return tqdm(total=total, initial=initial, desc=label, unit=unit, mininterval=0.5)


__all__ = [
    "EXECUTOR_FAILURES",
    "ExecutorLike",
    "Outcome",
    "RemoteError",
    "call",
    "describe_error",
    "executor_for",
    "parallel_map",
    "progress_bar",
]
