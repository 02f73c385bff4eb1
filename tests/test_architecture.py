"""The house's rules (DESIGN.md), checked on the code: layers import nothing above them.

Controllers, grasp analysis, the Barrett driver, drive models and the data vocabulary know ``State`` and the model,
never the simulator, so that the same controller drives a real hand.  Checked twice: statically on every import
statement (function-local ones too), and at run time on what importing them loads.
"""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import pytest

import bhgrasp

PACKAGE = Path(bhgrasp.__file__).parent
BELOW_THE_SIMULATOR = ("controllers", "grasp", "barrett", "data", "transmission.py")


def imported_modules(path: Path) -> list[str]:
    """Every module an import statement of ``path`` names (relative imports resolved within bhgrasp)."""
    names = []
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom):
            names.append(node.module or "")
        elif isinstance(node, ast.Import):
            names += [alias.name for alias in node.names]
    return names


def sources(place: str) -> list[Path]:
    path = PACKAGE / place
    return sorted(path.rglob("*.py")) if path.is_dir() else [path]


@pytest.mark.parametrize("place", BELOW_THE_SIMULATOR)
def test_layers_below_the_simulator_import_nothing_of_it(place: str) -> None:
    files = sources(place)
    assert files
    offending = [
        f"{path.relative_to(PACKAGE)}: {name}"
        for path in files
        for name in imported_modules(path)
        if name == "bhgrasp.sim" or name.startswith("bhgrasp.sim.")
    ]
    assert offending == []


def test_the_data_vocabulary_imports_only_errors_and_orientation_maths() -> None:
    for path in sources("data"):
        inside = [name for name in imported_modules(path) if name.startswith("bhgrasp")]
        assert set(inside) <= {
            "bhgrasp.errors",
            "bhgrasp.orientation",
            "bhgrasp.data.contacts",
            "bhgrasp.data.state",
            "bhgrasp.data.trajectory",
        }


def loaded_after(statement: str) -> set[str]:
    code = f"import sys; {statement}; print(' '.join(sorted(sys.modules)))"
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    return set(result.stdout.split())


def test_importing_controllers_grasp_and_the_driver_loads_no_simulator() -> None:
    modules = [
        ".".join(("bhgrasp", *path.relative_to(PACKAGE).with_suffix("").parts)).removesuffix(".__init__")
        for place in BELOW_THE_SIMULATOR
        for path in sources(place)
    ]
    every = "; ".join(f"import {module}" for module in modules)
    loaded = loaded_after(every)
    assert "bhgrasp.controllers.adaptive_grasp" in loaded and "bhgrasp.barrett.sensors" in loaded
    assert sorted(name for name in loaded if name.startswith("bhgrasp.sim")) == []


def test_the_public_face_imports_on_demand() -> None:
    assert not any(name.startswith("bhgrasp.sim") for name in loaded_after("import bhgrasp"))
    assert "bhgrasp.sim.simulator" in loaded_after("import bhgrasp; bhgrasp.Simulator")
    for name in bhgrasp.__all__:
        assert getattr(bhgrasp, name) is not None, name
    assert sorted(bhgrasp.__all__) == bhgrasp.__all__ == sorted(dir(bhgrasp))
    with pytest.raises(AttributeError, match="module 'bhgrasp' has no attribute 'Simulater'"):
        bhgrasp.Simulater  # noqa: B018
