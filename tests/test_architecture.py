"""The house's rules (DESIGN.md), checked on the code: no import circle, and layers import nothing above them.

The model, motion references, controllers, grasp analysis, the Barrett driver and the data vocabulary know ``State``
and the model, never the simulator, so that the same controller drives a real hand.  Checked twice: statically on
every import statement (function-local ones too), and at run time on what importing them loads.  Above the library:
the scenarios (reusable scenes), then the grasp benchmark and the thesis reproductions side by side, then the command
line.
"""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import pytest

import bhgrasp

PACKAGE = Path(bhgrasp.__file__).parent
BELOW_THE_SIMULATOR = ("model", "motion", "data", "grasp", "controllers", "barrett")
# Every room of bhgrasp on its floor, bottom to top.  A module imports only from its own room and from lower floors
# (so rooms on one floor, e.g. the benchmark and the thesis, never import each other).  The simulator sits above
# the Barrett drive it simulates and above the controllers it never needs; the public face (``bhgrasp``) above
# everything it re-exports.
FLOORS = (
    ("bhgrasp.errors",),
    ("bhgrasp._validation", "bhgrasp._native", "bhgrasp._twins"),
    ("bhgrasp.parallel",),
    ("bhgrasp.metrics", "bhgrasp.sweep", "bhgrasp.tuning"),
    ("bhgrasp.model",),
    ("bhgrasp.motion", "bhgrasp.data"),
    ("bhgrasp.grasp",),
    ("bhgrasp.controllers",),
    ("bhgrasp.barrett",),
    ("bhgrasp.sim",),
    ("bhgrasp", "bhgrasp.plots", "bhgrasp.viz"),
    ("bhgrasp.scenarios",),
    ("bhgrasp.bench", "bhgrasp.thesis"),
    ("bhgrasp.sweep_config",),
    ("bhgrasp.cli",),
    ("bhgrasp.__main__",),
)


def imported_modules(path: Path) -> list[str]:
    """Every module an import statement of ``path`` names (relative imports resolved within bhgrasp)."""
    names = []
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom):
            names.append(node.module or "")
        elif isinstance(node, ast.Import):
            names += [alias.name for alias in node.names]
    return names


def module_name(path: Path) -> str:
    return ".".join(("bhgrasp", *path.relative_to(PACKAGE).with_suffix("").parts)).removesuffix(".__init__")


MODULES = {module_name(path): path for path in PACKAGE.rglob("*.py")}
COMPILED_CORE = "bhgrasp._core"  # an extension module, no source here


def run_time_imports(name: str, types: bool = False) -> set[str]:
    """The bhgrasp modules that module ``name`` imports when it runs (function-local imports included; those under
    ``if TYPE_CHECKING:`` left out unless ``types``).  ``from package import name`` names the submodule when ``name``
    is one."""
    tree = ast.parse(MODULES[name].read_text())
    typing_only = {
        id(inner)
        for node in ast.walk(tree)
        if not types and isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test)
        for inner in ast.walk(node)
    }
    found = set()
    for node in ast.walk(tree):
        if id(node) in typing_only:
            continue
        if isinstance(node, ast.Import):
            found |= {alias.name for alias in node.names}
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            for alias in node.names:
                submodule = f"{node.module}.{alias.name}"
                found.add(submodule if submodule in MODULES or submodule == COMPILED_CORE else node.module)
    return {module for module in found if module in MODULES and module != name}


def room(name: str) -> str:
    """The package (or root module) of bhgrasp that holds module ``name``."""
    return ".".join(name.split(".")[:2])


def floor_of(name: str) -> int:
    """The floor (index into :data:`FLOORS`) of module ``name``'s room."""
    return next(floor for floor, rooms in enumerate(FLOORS) if room(name) in rooms)


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
            "bhgrasp.model.orientation",
            "bhgrasp.data.contacts",
            "bhgrasp.data.state",
            "bhgrasp.data.trajectory",
        }


def loaded_after(statement: str) -> set[str]:
    code = f"import sys; {statement}; print(' '.join(sorted(sys.modules)))"
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    return set(result.stdout.split())


def test_importing_controllers_grasp_and_the_driver_loads_no_simulator() -> None:
    modules = [module_name(path) for place in BELOW_THE_SIMULATOR for path in sources(place)]
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


@pytest.mark.parametrize("types", [False, True], ids=["run time", "with type-only imports"])
def test_no_module_of_bhgrasp_imports_itself_back_through_others(types: bool) -> None:
    """No circle, not even through ``if TYPE_CHECKING:`` imports (a reader, and farm-studio, sees those too)."""
    graph = {name: run_time_imports(name, types) for name in MODULES}
    assert "bhgrasp.bench.trial" in graph["bhgrasp.bench.runs"]  # the graph is read
    circles = [circle for circle in strongly_connected(graph) if len(circle) > 1]
    assert circles == []


def test_every_module_imports_only_its_own_room_and_the_floors_below() -> None:
    assert sorted(room(name) for name in MODULES if not any(room(name) in rooms for rooms in FLOORS)) == []
    upward = [
        f"{name} -> {other}"
        for name in MODULES
        for other in run_time_imports(name)
        if room(other) != room(name) and floor_of(other) >= floor_of(name)
    ]
    assert upward == []
    assert floor_of("bhgrasp.thesis.chapter5") == floor_of("bhgrasp.bench.trial") > floor_of("bhgrasp.scenarios.hold")


def strongly_connected(graph: dict[str, set[str]]) -> list[list[str]]:
    """Tarjan's strongly connected components of ``graph`` (iterative)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    components = []
    for root in graph:
        if root in index:
            continue
        work = [(root, iter(sorted(graph[root])))]
        index[root] = low[root] = len(index)
        stack.append(root)
        while work:
            node, children = work[-1]
            child = next(children, None)
            if child is not None:
                if child not in index:
                    index[child] = low[child] = len(index)
                    stack.append(child)
                    work.append((child, iter(sorted(graph[child]))))
                elif child in stack:
                    low[node] = min(low[node], index[child])
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[node])
            if low[node] == index[node]:
                component = []
                while True:
                    member = stack.pop()
                    component.append(member)
                    if member == node:
                        break
                components.append(sorted(component))
    return components


def test_no_module_imports_a_private_name_of_another() -> None:
    """A name another module needs has a public home (a private module, ``_core`` and ``_native``'s names aside)."""
    borrowed = []
    for name, path in MODULES.items():
        for node in ast.walk(ast.parse(path.read_text())):
            if not (isinstance(node, ast.ImportFrom) and node.level == 0 and (node.module or "").startswith("bhgrasp")):
                continue
            for alias in node.names:
                target = f"{node.module}.{alias.name}"
                private = alias.name.startswith("_") and not alias.name.startswith("__")
                if private and target not in MODULES and target != COMPILED_CORE:
                    borrowed.append(f"{name}: {target}")
    assert borrowed == []
