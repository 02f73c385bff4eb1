"""The one parallel map: the same outcomes here, on processes and threads; failures and lost tasks as values."""

from __future__ import annotations

import ast
import os
import threading
from concurrent.futures import Executor, Future, ProcessPoolExecutor, ThreadPoolExecutor
from pathlib import Path
from typing import Any

import pytest

from bhgrasp.errors import InputError
from bhgrasp.parallel import RemoteError, call, executor_for, parallel_map, progress_bar


def square_or_fail(x: int) -> int:
    if x == 3:
        raise ValueError(f"three is refused ({x})")
    return x * x


def squares(xs: list[int]) -> list[int]:
    if 5 in xs:
        raise ValueError("a batch holding five")
    return [x * x for x in xs]


def one_short(xs: list[int]) -> list[int]:
    return [x for x in xs[1:]]


def raise_unpicklable(_: int) -> None:
    raise ValueError("holds a lock", threading.Lock())  # no pickler takes a lock (tblib's, which Dask installs, too)


def die(x: int) -> int:
    if x == 2:
        os._exit(3)  # the worker process dies: its pool breaks
    return x


def as_table(outcomes) -> list[tuple[int, Any, str]]:
    return [(o.index, o.value, "" if o.ok else f"{type(o.error).__name__}: {o.error}") for o in outcomes]


EXPECTED = [(0, 0, ""), (1, 1, ""), (2, 4, ""), (3, None, "ValueError: three is refused (3)"), (4, 16, ""), (5, 25, "")]


def test_serial_processes_and_threads_give_the_same_outcomes_in_item_order() -> None:
    items = list(range(6))
    assert as_table(parallel_map(square_or_fail, items)) == EXPECTED
    with executor_for(None, workers=2) as pool:
        assert as_table(parallel_map(square_or_fail, items, pool)) == EXPECTED
        unordered = as_table(parallel_map(square_or_fail, items, pool, ordered=False))
    assert sorted(unordered) == EXPECTED
    with ThreadPoolExecutor(3) as threads:
        assert as_table(parallel_map(square_or_fail, items, threads)) == EXPECTED
    outcomes = list(parallel_map(square_or_fail, items))
    assert all(o.wall_time >= 0.0 and not o.lost for o in outcomes)


def test_a_batch_fails_together_and_only_itself() -> None:
    table = as_table(parallel_map(squares, list(range(7)), batch=3))
    assert table[:3] == [(0, 0, ""), (1, 1, ""), (2, 4, "")]
    assert [row[2] for row in table[3:6]] == ["ValueError: a batch holding five"] * 3
    assert table[6] == (6, 36, "")
    with executor_for(None, workers=2) as pool:
        assert as_table(parallel_map(squares, list(range(7)), pool, batch=3)) == table
    short = as_table(parallel_map(one_short, [1, 2, 3, 4], batch=2))
    assert {row[2] for row in short} == {"InputError: the batched function returned 1 results for 2 items"}


def test_a_worker_exception_that_does_not_pickle_comes_back_named() -> None:
    (here,) = parallel_map(raise_unpicklable, [0])
    assert isinstance(here.error, ValueError)  # in this process: the exception itself
    with executor_for(None, workers=1) as pool:
        (there,) = parallel_map(raise_unpicklable, [0], pool)
    assert isinstance(there.error, RemoteError) and not there.lost
    assert str(there.error).startswith("ValueError: ('holds a lock', <unlocked _thread.lock object")


class RefusesAfter(Executor):
    """Runs each call in ``submit``; refuses the call after the first ``limit``, as a lost cluster would."""

    def __init__(self, limit: int) -> None:
        self.limit, self.submitted = limit, 0

    def submit(self, fn: Any, /, *args: Any, **kwargs: Any) -> Future:
        if self.submitted == self.limit:
            raise RuntimeError("cluster gone")
        self.submitted += 1
        future: Future = Future()
        future.set_result(fn(*args, **kwargs))
        return future


def test_tasks_the_executor_loses_are_marked_lost_and_the_finished_ones_kept() -> None:
    outcomes = list(parallel_map(square_or_fail, list(range(5)), RefusesAfter(2)))
    assert [(o.index, o.value, o.lost) for o in outcomes[:2]] == [(0, 0, False), (1, 1, False)]
    assert all(o.lost and str(o.error) == "cluster gone" for o in outcomes[2:]) and len(outcomes) == 5
    with executor_for(None, workers=1) as pool:
        dead = list(parallel_map(die, [0, 1, 2, 3], pool))
    assert [o.value for o in dead[:2]] == [0, 1]
    assert all(o.lost and "BrokenProcessPool" in type(o.error).__name__ for o in dead[2:])


def test_executor_for_owns_only_the_pool_it_creates() -> None:
    with executor_for(None, workers=1) as pool:
        assert isinstance(pool, ProcessPoolExecutor)
    with pytest.raises(RuntimeError, match="after shutdown"):
        pool.submit(abs, -1)
    with ThreadPoolExecutor(1) as threads:
        with executor_for(threads) as given:
            assert given is threads
        assert threads.submit(abs, -1).result() == 1  # left open
    with executor_for("serial") as here:
        assert here == "serial"


@pytest.mark.parametrize(
    ("call", "message"),
    [
        (lambda: executor_for("threads").__enter__(), r"`executor` must be None, 'serial' or .*'threads'"),
        (lambda: executor_for(None, workers=0).__enter__(), r"`workers` must be a positive integer .* got 0"),
        (lambda: parallel_map(abs, [1], "pool"), r"`executor` must be 'serial' or .*'pool'"),
        (lambda: parallel_map(abs, [1], batch=0), r"`batch` must be a positive integer .* got 0"),
    ],
)
def test_bad_arguments_are_named(call, message: str) -> None:
    with pytest.raises(InputError, match=message):
        call()


def test_the_progress_bar_shows_its_label_or_nothing(capsys: pytest.CaptureFixture) -> None:
    list(parallel_map(abs, [-1, -2], progress="squaring"))
    assert "squaring" in capsys.readouterr().err
    silent = progress_bar(3, "quiet", "item", enabled=False)
    silent.update(2)
    silent.set_postfix(best=1.0)
    silent.close()
    assert capsys.readouterr().err == ""


def fan_out_names(path: Path) -> set[str]:
    """``submit`` calls and ``ProcessPoolExecutor`` names in the code of ``path`` (not its docstrings)."""
    found = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) and node.func.attr == "submit":
            found.add("submit")
        elif isinstance(node, (ast.Name, ast.alias)) and "ProcessPoolExecutor" in (
            getattr(node, "id", None),
            getattr(node, "name", None),
        ):
            found.add("ProcessPoolExecutor")
    return found


def test_fan_out_is_written_once() -> None:
    """No module of bhgrasp but the map submits to an executor or creates a process pool."""
    package = Path(__file__).parents[1] / "bhgrasp"
    assert fan_out_names(package / "parallel.py") == {"submit", "ProcessPoolExecutor"}  # the check sees them
    writers = {str(path.relative_to(package)): fan_out_names(path) for path in package.rglob("*.py")}
    assert {path: names for path, names in writers.items() if names and path != "parallel.py"} == {}


def test_an_outcome_gives_its_value_or_raises_its_error_and_call_applies_a_task() -> None:
    good, bad = parallel_map(call, [(divmod, (7, 2)), (divmod, (1, 0))])
    assert good.result() == (3, 1)
    with pytest.raises(ZeroDivisionError):
        bad.result()
