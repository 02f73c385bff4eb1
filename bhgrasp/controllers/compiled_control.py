"""A controller's next cycles as a compiled loop controller, which :meth:`Simulator.run` runs in C++.

A controller that can offers them through ``compiled_control(t, state)`` (``None``: not from this state); the run
loop hands them to :meth:`Simulator.run_compiled <bhgrasp.sim.simulator.Simulator.run_compiled>` when its sensors are
exact, it takes one control cycle and one sample a step, nothing else acts on the scene (no disturbance, object
forces or ``until``) and the simulator can (the compiled engine, a ``FullyActuated`` drive).  The steps are those the
Python loop would take, bit for bit; the controller gives the log of every cycle and takes back its state after them.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from bhgrasp.errors import InputError


@dataclass(frozen=True)
class CompiledControl:
    """The cycles a compiled loop controller takes for a controller (:class:`bhgrasp.sim.run_loop.LoopOffer`).

    Attributes:
        loop: The loop controller (a ``bhgrasp._core.LoopController``, ``src/closed_loop.hpp``).
        until: The controller's next switch [s]: the loop stops before a step at t >= until (``inf``: none).
        log_rows: ``(rows, q_hand) -> entries``: from the loop's log rows (n, log_size) and the hand's joint
            positions the n cycles read (n, nq) [rad], every entry of the controller's log as it is after each
            cycle, ``(n, *shape)`` each.
        settle: ``(run, q_hand) -> None`` after the loop's run (``bhgrasp._core.LoopRun``): the controller's clock
            and log as the last of the cycles it completed (``q_hand``: one row each) left them.
        fail: ``(run, state) -> None``: raises what the cycle that stopped the run (its ``status`` > 0) raises at
            ``state``, leaving what it would leave; nothing otherwise.
    """

    loop: Any
    until: float
    log_rows: Callable[[np.ndarray, np.ndarray], dict[str, np.ndarray]]
    settle: Callable[[Any, np.ndarray], None]
    fail: Callable[[Any, Any], None]


def held_rows(log: dict[str, Any], n: int) -> dict[str, np.ndarray]:
    """Each entry of ``log`` held for ``n`` cycles: ``(n, *shape)`` read-only rows of its value as floats.

    Raises:
        InputError: An entry that is not numbers (named).
    """
    rows = {}
    for name, value in log.items():
        try:
            value = np.asarray(value, dtype=float)
        except (TypeError, ValueError, OverflowError) as error:
            raise InputError(f"log entry {name!r} must be numbers, got {value!r}") from error
        rows[name] = np.broadcast_to(value, (n, *value.shape))
    return rows


__all__ = ["CompiledControl", "held_rows"]
