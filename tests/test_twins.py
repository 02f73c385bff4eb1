"""The twin registry (bhgrasp/_twins.py) is complete and true: every bound name, its twin, its lockstep test."""

from __future__ import annotations

import ast
import importlib
from pathlib import Path

import numpy as np
import pytest

from bhgrasp._native import core_loads
from bhgrasp._twins import DATA, KERNELS, REGISTRY

TESTS = Path(__file__).parent


def bound_names() -> set[str]:
    core = importlib.import_module("bhgrasp._core")
    return {name for name in dir(core) if not name.startswith("_")}


@pytest.mark.skipif(not core_loads(), reason="bhgrasp._core is not built (CI requires it)")
def test_every_name_the_core_binds_is_registered_and_nothing_else() -> None:
    assert len(REGISTRY) == len(KERNELS) + len(DATA)  # no name twice
    assert sorted(bound_names() - set(REGISTRY)) == []
    assert sorted(set(REGISTRY) - bound_names()) == []


def resolve(path: str) -> object:
    """The object a dotted path names (a module's attribute, or an attribute of one)."""
    parts = path.split(".")
    for cut in range(len(parts), 0, -1):
        try:
            found = importlib.import_module(".".join(parts[:cut]))
        except ModuleNotFoundError:
            continue
        for name in parts[cut:]:
            found = getattr(found, name)
        return found
    raise ModuleNotFoundError(path)


@pytest.mark.parametrize("entry", REGISTRY.values(), ids=list(REGISTRY))
def test_each_twin_exists_and_its_lockstep_test_too(entry) -> None:
    if entry.twin:
        resolve(entry.twin)
    else:
        assert entry.reason, f"{entry.name} has no twin and no reason"
    file, test = entry.lockstep.split("::")
    tree = ast.parse((TESTS.parent / file).read_text())
    assert test in {node.name for node in tree.body if isinstance(node, ast.FunctionDef)}, entry.lockstep


def is_zero(value: object) -> bool:
    """Zero, false, empty, all-zero arrays, or an option struct whose fields all are."""
    fields = getattr(type(value), "FIELDS", None)
    if fields is not None:
        return all(is_zero(getattr(value, field)) for field in fields)
    if isinstance(value, (bool, int, float)):
        return value == 0
    return not np.any(np.asarray(value))


OPTION_STRUCTS = ("ContactLaw", "Pair", "Query", "Spinning", "Settings", "Drive", "Barrett")


@pytest.mark.skipif(not core_loads(), reason="bhgrasp._core is not built (CI requires it)")
@pytest.mark.parametrize("name", OPTION_STRUCTS)
def test_an_option_struct_holds_no_defaults_of_its_own_and_is_filled_whole(name: str) -> None:
    """The defaults live in Python: a new struct is all zeros, and filling it misses no field (src/options.hpp)."""
    from bhgrasp.sim.native_options import filled

    struct = getattr(importlib.import_module("bhgrasp._core"), name)
    assert is_zero(struct()), name
    first, *rest = struct.FIELDS
    with pytest.raises(TypeError, match=rf"missing here \['{first}'\], unknown there \['spare'\]"):
        filled(struct, spare=1, **dict.fromkeys(rest, 0))


@pytest.mark.skipif(not core_loads(), reason="bhgrasp._core is not built (CI requires it)")
def test_the_engine_settings_carry_pythons_values() -> None:
    """What the compiled engine is given is what the Python side declares (its tolerances included)."""
    from bhgrasp.scenarios.hold import reference_hold
    from bhgrasp.sim.coal_queries import FALLBACK_TOLERANCE, NARROW_TOLERANCE
    from bhgrasp.sim.compiled import engine_settings

    simulator = reference_hold().simulator
    native = engine_settings(simulator.scene, simulator.layout, simulator.law, simulator.settings, 3e-3)
    assert native.dt == simulator.dt and native.limit_damping == simulator.settings.joint_limit_damping
    assert native.law.stiffness == simulator.law.stiffness and native.law.match_radius == 3e-3
    assert (native.query.tolerance, native.query.fallback_tolerance) == (NARROW_TOLERANCE, FALLBACK_TOLERANCE)
