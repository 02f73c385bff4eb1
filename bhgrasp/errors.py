"""The bhgrasp exception hierarchy.

Every error raised on purpose by bhgrasp derives from :class:`BhgraspError`; each subclass also derives from
the builtin a caller would naturally catch (``ValueError`` for bad input, ...), so ``except ValueError`` keeps
working.  Messages name the argument, the value received and what was expected.
"""

from __future__ import annotations

from typing import Any


class BhgraspError(Exception):
    """Root of every error bhgrasp raises on purpose."""


class InputError(BhgraspError, ValueError):
    """An argument has the wrong shape, type, range, or contains NaN/inf, or names an unknown joint/frame."""


class ModelError(BhgraspError, ValueError):
    """A robot description cannot be used: missing or malformed URDF, forbidden XML, inconsistent model."""


class UnreachableError(BhgraspError, ValueError):
    """A target lies outside the reachable set (joint limits or link lengths).

    Attributes:
        result: Optional diagnostic payload (e.g. the best :class:`~bhgrasp.model.hand_ik.IKResult` found).
    """

    def __init__(self, message: str, result: Any = None) -> None:
        super().__init__(message)
        self.result = result


class FrozenSettingError(BhgraspError, AttributeError):
    """A setting that is fixed once its object is built was assigned (e.g. ``Simulator.dt``): build a new one."""


class CompiledEngineUnavailable(BhgraspError, ImportError):
    """The compiled core ``bhgrasp._core`` does not load (the package was installed without building it)."""


class SimulationDiverged(BhgraspError, RuntimeError):
    """A simulation produced NaN/inf, runaway speed or runaway penetration.

    Attributes:
        time: Simulated time [s] at which it was detected.
        quantity: What diverged (e.g. ``"object speed"``, ``"contact depth"``).
        value: The offending value.
    """

    def __init__(self, time: float, quantity: str, value: object, hint: str = "") -> None:
        message = f"simulation diverged at t = {time:.6g} s: {quantity} = {value}"
        super().__init__(message + (f"; {hint}" if hint else ""))
        self.time = time
        self.quantity = quantity
        self.value = value


class NotSettled(BhgraspError, RuntimeError):
    """Objects left to settle were still moving when the time allowed ran out.

    Attributes:
        time: Simulated time [s] when it stopped.
        speeds: Each object's fastest surface speed [m/s] then, by name.
    """

    def __init__(self, time: float, speeds: dict[str, float], rest_speed: float) -> None:
        moving = {name: speed for name, speed in speeds.items() if speed >= rest_speed}
        listed = ", ".join(f"{name} {speed:.3g} m/s" for name, speed in sorted(moving.items(), key=lambda i: -i[1]))
        now = f"still moving faster than {rest_speed:.3g} m/s: {listed}" if moving else "all slower just now"
        super().__init__(
            f"the objects did not settle in {time:.3g} s (at rest: every one slower than {rest_speed:.3g} m/s for "
            f"`rest_time`): {now}; allow more time (`max_time`) or drop them lower"
        )
        self.time = time
        self.speeds = speeds


class SolverFailed(BhgraspError, RuntimeError):
    """A numerical solver stopped without an answer (an iteration limit, numerical trouble), naming why."""
