"""A controller's next cycles as a compiled loop controller, which :meth:`Simulator.run` runs in C++.

A controller that can offers them through ``compiled_control(t, state)`` (``None``: not from this state); the run
loop hands them to :meth:`Simulator.run_compiled <bhgrasp.sim.simulator.Simulator.run_compiled>` when its sensors are
exact, it takes one control cycle and one sample a step, and nothing else acts on the scene.  The steps are those the
Python loop would take, bit for bit; the controller gives the log of every cycle and takes back its state after them.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np


@dataclass(frozen=True)
class CompiledControl:
    """The cycles a compiled loop controller takes for a controller.

    Attributes:
        loop: The loop controller (a ``bhgrasp._core.LoopController``, ``src/closed_loop.hpp``).
        until: The controller's next switch [s]: the loop stops before a step at t >= until (``inf``: none).
        log_rows: ``(rows, q_hand) -> entries``: from the loop's log rows (n, log_size) and the hand's joint
            positions of the n cycles (n, nq) [rad], every entry of the controller's log as it would be after each
            cycle, (n, *shape) each.
        finish: ``(run, state) -> None`` after the loop's run (``bhgrasp._core.LoopRun``) ended at ``state``: the
            controller's clock and log as its last cycle left them; raises what a cycle that failed would raise.
    """

    loop: Any
    until: float
    log_rows: Callable[[np.ndarray, np.ndarray], dict[str, np.ndarray]]
    finish: Callable[[Any, Any], None]


def held_rows(log: dict[str, Any], n: int) -> dict[str, np.ndarray]:
    """Each entry of ``log`` held for ``n`` cycles: (n, *shape) read-only rows of its value as floats."""
    rows = {}
    for name, value in log.items():
        value = np.asarray(value, dtype=float)
        rows[name] = np.broadcast_to(value, (n, *value.shape))
    return rows


__all__ = ["CompiledControl", "held_rows"]
