"""The README's Python examples run as written, each block on its own, and print what their comments say.

Each block ends with a ``# Prints:`` comment (a first line may add an explanation in parentheses): its remaining
comment lines are the printed lines, in order, where ``...`` stands for any text (a port number, a long tuple).
Beyond the prints, a few results are checked against independent truths (closed forms, the coupling ratio).
"""

from __future__ import annotations

import contextlib
import io
import re
from pathlib import Path

import numpy as np
import pytest

README = Path(__file__).resolve().parents[1] / "README.md"
BLOCKS = re.findall(r"```python\n(.*?)```", README.read_text(), flags=re.DOTALL)


def expected_lines(block: str) -> list[str]:
    """The printed lines a block's trailing ``# Prints`` comment gives."""
    comment = block[block.index("# Prints") :].splitlines()
    lines = [line[2:] if line.startswith("# ") else line[1:] for line in comment]
    start = next(i for i, line in enumerate(lines) if line.rstrip().endswith(":")) + 1  # after "Prints ...:"
    return lines[start:]


def run_alone(block: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> tuple[dict, list[str]]:
    monkeypatch.chdir(tmp_path)  # the examples write files
    namespace: dict = {"__name__": "__main__"}
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        exec(compile(block, str(README), "exec"), namespace)  # our own README, a fresh namespace per block
    return namespace, out.getvalue().splitlines()


def test_every_block_says_what_it_prints() -> None:
    assert len(BLOCKS) >= 10
    assert all("# Prints" in block for block in BLOCKS)


@pytest.mark.parametrize("index", range(len(BLOCKS)), ids=[f"block{i + 1}" for i in range(len(BLOCKS))])
def test_block_runs_alone_and_prints_its_comment(index: int, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    block = BLOCKS[index]
    namespace, printed = run_alone(block, tmp_path, monkeypatch)
    expected = expected_lines(block)
    assert len(printed) == len(expected), f"printed {printed}, the README says {expected}"
    for line, pattern in zip(printed, expected):
        regex = ".*".join(re.escape(part) for part in pattern.split("..."))
        assert re.fullmatch(regex, line.rstrip()), f"printed {line!r}, the README says {pattern!r}"
    check_truths(namespace, tmp_path)


def check_truths(namespace: dict, tmp_path: Path) -> None:
    """Independent truths for the blocks that compute them (found by the names they define)."""
    if "traj" in namespace and "mug" in namespace:  # a box from a mesh file falls as the primitive box does
        z = namespace["traj"].object_position[-1, 0, 2]
        assert z == pytest.approx(0.025 - 0.2 * 9.81 / 1e4, rel=1e-6)
    if "traj" in namespace and "closing" in namespace:  # falling box and Barrett closing
        z = namespace["traj"].object_position[-1, 0, 2]
        assert z == pytest.approx(0.025 - 0.2 * 9.81 / 1e4, rel=1e-6)  # resting on k = 1e4 N/m: m g / k deep
        closing = namespace["closing"].q
        np.testing.assert_allclose(closing[:, 2] - closing[:, 1] / 3, 0.0, atol=1e-12)  # distal = proximal / 3
    if "law" in namespace and "traj_force" in namespace:  # adaptive impedance: force reached, k_e identified
        setup = namespace["setup"]
        force = namespace["normal_force"](setup, namespace["traj_force"])
        assert abs(force[-1] - 30.0) < 0.6 and abs(namespace["law"].environment_stiffness / setup.k_e - 1) < 0.05
    if "forces" in namespace and "G" in namespace:  # the forces exert the weight exactly
        forces = namespace["forces"]
        np.testing.assert_allclose(namespace["G"] @ forces.forces.ravel(), namespace["weight"], atol=1e-6)
    if "pile" in namespace:  # the settled pile: the bin carries its weight (object-object forces cancel in pairs)
        weight = sum(item.mass for item in namespace["pile"].objects) * 9.81
        assert namespace["pile"].support_force() == pytest.approx([0.0, 0.0, weight], rel=1e-4, abs=1e-2)
    if "viewer" in namespace:  # the MeshCat example's offline page
        assert (tmp_path / "replay.html").stat().st_size > 200_000


def test_readme_gives_exactly_two_setup_commands() -> None:
    commands = re.findall(r"```bash\n(.*?)```", README.read_text(), flags=re.DOTALL)
    assert len(commands) == 2
    assert "pip install . && bhgrasp demo" in commands[0]
    assert 'pip install -e ".[test]" && pytest -n auto -m "not slow"' in commands[1]
    ci = (README.parent / ".ci" / "run").read_text()  # CI runs both, the test command timed against its budget
    assert 'pip install --quiet -e ".[test,docs]"' in ci and "\nbhgrasp demo --output" in ci
    assert re.search(r'\n(BHGRASP_REQUIRE_CORE=1 )?(BHGRASP_REQUIRE_BROWSER=1 )?pytest -n auto -m "not slow"\n', ci)
    # the rest, in CI's own step (the chapters in full there)
    assert re.search(
        r"\n(BHGRASP_REQUIRE_CORE=1 )?(BHGRASP_FULL_CHAPTERS=1 )?pytest -n auto (--dist worksteal )?-m slow"
        r"( --durations=\d+)?( \|\| slow_status=\$\?)?\n",
        ci,
    )
    budget = int(re.search(r"\nbudget=(\d+)\n", ci).group(1))
    stated = re.search(
        r"the tests take about (\d+) min on 2 cores.*?fails above (\d+) min", README.read_text(), re.DOTALL
    )
    assert stated and int(stated.group(2)) * 60 == budget and int(stated.group(1)) * 60 < budget
