"""The twin registry (bhgrasp/_twins.py) is complete and true: every bound name, its twin, its lockstep test."""

from __future__ import annotations

import ast
import importlib
from pathlib import Path

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
