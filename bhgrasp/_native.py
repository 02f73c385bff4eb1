"""The compiled extension ``bhgrasp._core``: one loader, one engine switch, and the kernels built once per model.

Every computation that has a compiled kernel and a Python twin runs the compiled one, unless asked otherwise: per
object with ``engine="python"`` (``Simulator``, ``ContactForceQP``, ``SMCAdaptiveGrasp``), or everywhere with the
environment variable ``BHGRASP_ENGINE=python`` (read when bhgrasp is imported: a machine without a C++ compiler, or
a check of the twins).  ``engine=None`` means that default.  Nothing falls back silently: where the default is the
compiled engine and ``bhgrasp._core`` does not load, the call raises
:class:`~bhgrasp.errors.CompiledEngineUnavailable` saying how to rebuild, or how to switch.

A module of its own, outside :mod:`bhgrasp.sim`, so that the model, grasp and controller modules use the compiled
kernels without importing the simulator (DESIGN.md: controllers never import the simulator).
"""

from __future__ import annotations

import os
import sys
import weakref
from collections.abc import Callable
from importlib import metadata
from pathlib import Path
from types import ModuleType
from typing import Any

from bhgrasp.errors import CompiledEngineUnavailable, InputError

ENGINES = ("compiled", "python")
ENGINE_VARIABLE = "BHGRASP_ENGINE"
DEFAULT_ENGINE = os.environ.get(ENGINE_VARIABLE, "compiled")  # checked where it is used: importing never fails
_KERNELS: weakref.WeakKeyDictionary[Any, dict[str, Any]] = weakref.WeakKeyDictionary()
_MISSING = object()


def default_engine() -> str:
    """The engine of ``engine=None``: ``"compiled"``, or ``"python"`` with ``BHGRASP_ENGINE=python``.

    Raises:
        InputError: ``BHGRASP_ENGINE`` holds another value.
    """
    if DEFAULT_ENGINE not in ENGINES:
        raise InputError(f"{ENGINE_VARIABLE}={DEFAULT_ENGINE!r}: expected one of {ENGINES} (unset: compiled)")
    return DEFAULT_ENGINE


def engine_name(engine: str | None) -> str:
    """``engine`` checked, ``None`` resolved to :func:`default_engine`.

    Raises:
        InputError: ``engine`` is not None, ``"compiled"`` or ``"python"``.
    """
    if engine is None:
        return default_engine()
    if engine not in ENGINES:
        raise InputError(f"`engine` must be one of {ENGINES} or None (the default engine), got {engine!r}")
    return engine


def default_core() -> ModuleType | None:
    """``bhgrasp._core`` for a computation on the default engine; ``None`` when the default is Python.

    Raises:
        CompiledEngineUnavailable: The default is the compiled engine and the core does not load.
    """
    loaded = sys.modules.get("bhgrasp._core")  # the per-step callers' fast path: imported before
    if loaded is not None and DEFAULT_ENGINE == "compiled":
        return loaded
    if default_engine() == "python":
        return None
    return required_core("the compiled core")


def core_loads() -> bool:
    """True if ``bhgrasp._core`` loads (whatever the default engine)."""
    try:
        import bhgrasp._core  # noqa: F401
    except ImportError:
        return False
    return True


def required_core(what: str) -> ModuleType:
    """``bhgrasp._core`` for ``what`` (e.g. "the compiled engine").

    Raises:
        CompiledEngineUnavailable: It does not load; the message says why, how to rebuild, and how to run Python.
    """
    try:
        import bhgrasp._core as _core
    except ImportError as error:
        shadowed = _shadowed_install()
        if shadowed is not None:
            raise CompiledEngineUnavailable(
                f"{what} (bhgrasp._core) does not load: Python imported bhgrasp from the source folder "
                f"{Path(__file__).parent} (the current directory comes first on sys.path), which holds no compiled "
                f"core, not the bhgrasp installed in {shadowed}; run from another folder, or install this checkout "
                "in place with `pip install -e .`"
            ) from error
        raise CompiledEngineUnavailable(
            f"{what} (bhgrasp._core) does not load ({error}); reinstall with `pip install -e .` (it needs a C++17 "
            f"compiler, e.g. Debian's g++), or run the Python reference: engine='python' for one object, "
            f"{ENGINE_VARIABLE}=python for everything"
        ) from error
    return _core


def _shadowed_install(package: Path | None = None, distribution: metadata.Distribution | None = None) -> Path | None:
    """The installed bhgrasp that ``package`` (the bhgrasp folder imported) shadows, if it is a source checkout.

    An installed copy is a folder with the package's ``__init__.py`` and its ``_core`` extension (an editable
    install's site-packages folder holds only the extension: then nothing is shadowed).
    """
    package = (Path(__file__).parent if package is None else package).resolve()
    if not (package.parent / "pyproject.toml").is_file():
        return None  # an installed package, not a checkout
    try:
        distribution = metadata.distribution("bhgrasp") if distribution is None else distribution
    except metadata.PackageNotFoundError:
        return None
    for file in distribution.files or ():
        if file.name.startswith("_core.") and file.parent.name == "bhgrasp":
            installed = Path(str(distribution.locate_file(file))).resolve().parent
            if installed != package and (installed / "__init__.py").is_file():
                return installed
    return None


def kernel(owner: Any, name: str, build: Callable[[ModuleType], Any]) -> Any:
    """The compiled kernel ``name`` of ``owner`` (e.g. a Hand), ``build(core)`` on first use (:func:`default_core`).

    ``None`` when the default engine is Python; :class:`~bhgrasp.errors.CompiledEngineUnavailable` when it is the
    compiled one and the core does not load.

    Kept beside ``owner``, not in it (copies and pickles of the owner build their own); a kernel holds a copy of
    the owner's model, which must not change in place afterwards.
    """
    kernels = _KERNELS.get(owner)  # (a get is cheaper than setdefault, which makes a weak reference every call)
    if kernels is None:
        kernels = _KERNELS[owner] = {}
    found = kernels.get(name, _MISSING)
    if found is _MISSING:
        core = default_core()
        found = kernels[name] = None if core is None else build(core)
    return found


__all__ = [
    "DEFAULT_ENGINE",
    "ENGINES",
    "ENGINE_VARIABLE",
    "core_loads",
    "default_core",
    "default_engine",
    "engine_name",
    "kernel",
    "required_core",
]
