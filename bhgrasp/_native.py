"""The compiled extension ``bhgrasp._core``: one loader, and the kernels built once per model they copy.

A module of its own, outside :mod:`bhgrasp.sim`, so that the model, grasp and controller modules use the compiled
kernels without importing the simulator (DESIGN.md: controllers never import the simulator).
"""

from __future__ import annotations

import sys
import weakref
from collections.abc import Callable
from importlib import metadata
from pathlib import Path
from types import ModuleType
from typing import Any

from bhgrasp.errors import CompiledEngineUnavailable

_KERNELS: weakref.WeakKeyDictionary[Any, dict[str, Any]] = weakref.WeakKeyDictionary()
_MISSING = object()


def optional_core() -> ModuleType | None:
    """``bhgrasp._core``, or ``None`` when it does not load (the callers then run their Python twins)."""
    loaded = sys.modules.get("bhgrasp._core")  # the per-step callers' fast path: imported before
    if loaded is not None:
        return loaded
    try:
        from bhgrasp import _core
    except ImportError:
        return None
    return _core


def required_core(what: str) -> ModuleType:
    """``bhgrasp._core`` for ``what`` (e.g. "the compiled engine").

    Raises:
        CompiledEngineUnavailable: It does not load; the message says why, how to rebuild, and the Python fallback.
    """
    try:
        from bhgrasp import _core
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
            "compiler, e.g. Debian's g++), or pass engine='python' to use the Python reference"
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
    """The compiled kernel ``name`` of ``owner`` (e.g. a Hand), ``build(core)`` on first use; ``None`` without the core.

    Kept beside ``owner``, not in it (copies and pickles of the owner build their own); a kernel holds a copy of
    the owner's model, which must not change in place afterwards.
    """
    kernels = _KERNELS.get(owner)  # (a get is cheaper than setdefault, which makes a weak reference every call)
    if kernels is None:
        kernels = _KERNELS[owner] = {}
    found = kernels.get(name, _MISSING)
    if found is _MISSING:
        core = optional_core()
        found = kernels[name] = None if core is None else build(core)
    return found


__all__ = ["kernel", "optional_core", "required_core"]
