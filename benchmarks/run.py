"""Run every ``benchmarks/bench_*.py`` of this checkout, one process each; ``--quick``: a few repetitions (a smoke run).

Usage: ``python benchmarks/run.py [--quick]``.  Each script prints ratios against a baseline measured in the same
run (BENCHMARKS.md).  The scripts measure a checkout, so they are not part of the installed package; CI runs this
with ``--quick`` in the slow tests' step (``tests/test_benchmarks.py``) so that they cannot rot.
"""

from __future__ import annotations

import argparse
import subprocess
import sys
from pathlib import Path

FOLDER = Path(__file__).resolve().parent
QUICK = {  # script -> its arguments for a smoke run
    "bench_batch.py": ["--steps", "10", "--sizes", "8", "--repeat", "1"],
    "bench_hand.py": ["--repeat", "200"],
    "bench_sim.py": ["--duration", "0.05"],
    "bench_control.py": ["--repeat", "50"],
    "bench_qp.py": ["--cycles", "50"],
    "bench_sweep.py": ["--cases", "2", "--duration", "0.8"],
    "bench_scaling.py": ["--steps", "20"],
    "bench_instructions.py": ["--cases", "free", "--engine", "compiled", "--short", "2", "--long", "12"],
    "bench_meshes.py": ["--steps", "20", "--repeat", "1"],
    "bench_clutter.py": ["--sizes", "4", "--steps", "20"],
    "bench_build.py": ["--sizes", "16", "--steps", "2"],
    "bench_linear_solver.py": ["--small", "2", "8", "--large", "3", "10", "--steps", "3"],
    "bench_trial.py": ["--duration", "0.2"],
    "bench_demo.py": ["--repeat", "1", "--duration", "1.0"],
}


def main(argv: list[str] | None = None) -> int:
    """Run the scripts in name order; stop at the first that fails, with its status."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true", help="a few repetitions only (a smoke run)")
    args = parser.parse_args(argv)
    for script in sorted(FOLDER.glob("bench_*.py")):
        print(f"== {script.name}", flush=True)
        extra = QUICK.get(script.name, []) if args.quick else []
        status = subprocess.run([sys.executable, str(script), *extra], check=False).returncode
        if status:
            print(f"benchmarks/run.py: {script.name} exited with {status}", file=sys.stderr)
            return status
    return 0


if __name__ == "__main__":
    sys.exit(main())
