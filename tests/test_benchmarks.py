"""The benchmark scripts run (``python benchmarks/run.py --quick``), so that they cannot rot."""

from __future__ import annotations

import runpy
import subprocess
import sys
from pathlib import Path

import pytest

RUNNER = Path(__file__).parents[1] / "benchmarks" / "run.py"


@pytest.mark.slow
def test_every_benchmark_script_runs() -> None:
    result = subprocess.run([sys.executable, str(RUNNER), "--quick"], capture_output=True, text=True, check=False)
    assert result.returncode == 0, result.stderr[-2000:]
    scripts = sorted(path.name for path in RUNNER.parent.glob("bench_*.py"))
    quick = runpy.run_path(str(RUNNER))["QUICK"]  # every script has its smoke run's arguments
    assert set(scripts) == set(quick) and all(f"== {name}" in result.stdout for name in scripts)
