"""Filling the compiled core's option structs (``src/options.hpp``): every field, from the Python side's values.

Each struct is declared once in C++ by its field list, with no defaults of its own; its binding lists the fields as
``FIELDS``.  :func:`filled` sets every one of them, so a field added in C++ and not filled here is an error that
names it, never a silent zero, and the defaults stay where Python declares them (``SimulatorSettings``,
``SpringDamper``, the scene's collision requests, the actuation models).
"""

from __future__ import annotations

from typing import Any


def filled(struct: type, **values: Any) -> Any:
    """A new ``struct`` (an option struct of ``bhgrasp._core``) with each of its ``FIELDS`` set from ``values``.

    Raises:
        TypeError: ``values`` misses a field of the struct, or names one it lacks (the two sides disagree: a build
            of the core older or newer than this Python code).
    """
    fields = tuple(struct.FIELDS)
    missing, unknown = [name for name in fields if name not in values], sorted(set(values) - set(fields))
    if missing or unknown:
        raise TypeError(
            f"bhgrasp._core.{struct.__name__} has the fields {fields}; missing here {missing}, unknown there "
            f"{unknown} (rebuild the core: pip install -e .)"
        )
    native = struct()
    for name in fields:
        setattr(native, name, values[name])
    return native


__all__ = ["filled"]
