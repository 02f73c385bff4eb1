"""The README's Python examples run as written (documentation is tested like code)."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

README = Path(__file__).resolve().parents[1] / "README.md"


def test_readme_python_blocks_run(capsys, tmp_path, monkeypatch) -> None:
    monkeypatch.chdir(tmp_path)  # the examples write files
    blocks = re.findall(r"```python\n(.*?)```", README.read_text(), flags=re.DOTALL)
    assert len(blocks) >= 4
    namespace: dict = {}
    for block in blocks:
        exec(compile(block, str(README), "exec"), namespace)  # our own README
    out = capsys.readouterr().out
    assert "unknown joint 'F3_spread'; valid joints: F1_spread, F1_proximal" in out
    assert "CTC: RMS error" in out and "ASMC: RMS error" in out and "super-twisting: RMS error" in out
    assert namespace["name"] == "super-twisting" and np.all(namespace["tracking"].rms_percent < 10.0)  # tracks
    force_example = namespace["normal_force"](namespace["setup"], namespace["traj_force"])
    assert (
        abs(force_example[-1] - 30.0) < 0.6
        and abs(namespace["law"].environment_stiffness / namespace["setup"].k_e - 1) < 0.05
    )
    assert namespace["quality"].force_closure and namespace["forces"].feasible
    assert namespace["result"].converged
    assert namespace["traj"].object_position[-1, 0, 2] == pytest.approx(0.025 - 0.2 * 9.81 / 1e4, rel=1e-6)
    assert (tmp_path / "replay.html").stat().st_size > 200_000  # the MeshCat example's offline page
    closing = namespace["closing"].q
    np.testing.assert_allclose(closing[:, 2] - closing[:, 1] / 3, 0.0, atol=1e-12)  # distal = proximal / 3


def test_readme_gives_exactly_two_setup_commands() -> None:
    commands = re.findall(r"```bash\n(.*?)```", README.read_text(), flags=re.DOTALL)
    assert len(commands) == 2
    assert "bhgrasp demo" in commands[0] and "pytest" in commands[1]
    ci = (README.parent / ".ci" / "run").read_text()
    assert 'pip install --quiet -e ".[test]"' in ci and re.search(r"\n(BHGRASP_REQUIRE_BROWSER=1 )?pytest\n", ci)
