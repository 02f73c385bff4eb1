"""One engine switch: ``BHGRASP_ENGINE=python`` runs every Python twin; nothing falls back silently."""

from __future__ import annotations

import os
import subprocess
import sys

import numpy as np

from bhgrasp.scenarios.hold import reference_hold

RUN = """
import numpy as np
from bhgrasp.grasp import ContactForceQP
from bhgrasp.grasp.kinematics import grasp_kinematics_kernel
from bhgrasp.scenarios.hold import reference_hold
hold = reference_hold()
trajectory = hold.simulator.run(hold.controller, 0.05, state=hold.state, progress=False)
print(hold.simulator.engine_name, ContactForceQP(3, 0.5).engine, grasp_kinematics_kernel(hold.simulator.scene.hand))
print(trajectory.q[-1].tobytes().hex())
"""


def run_with(engine: str) -> list[str]:
    environment = {**os.environ, "BHGRASP_ENGINE": engine}
    result = subprocess.run([sys.executable, "-c", RUN], capture_output=True, text=True, env=environment, check=False)
    return result.stdout.splitlines() if result.returncode == 0 else [result.stderr.strip().splitlines()[-1]]


def test_the_python_switch_runs_every_twin_with_the_bits_of_the_python_engine() -> None:
    hold = reference_hold()
    python = hold.simulator.with_settings(engine="python")
    expected = python.run(hold.controller, 0.05, state=hold.state, progress=False).q[-1]
    names, bits = run_with("python")
    assert names == "python python None"
    assert np.array_equal(np.frombuffer(bytes.fromhex(bits)), expected)
    assert run_with("compiled")[0].startswith("compiled compiled <bhgrasp._core.GraspKinematics")


def test_a_bad_switch_value_is_named() -> None:
    (message,) = run_with("fortran")
    expected = "InputError: BHGRASP_ENGINE='fortran': expected one of ('compiled', 'python') (unset: compiled)"
    assert message.endswith(expected)
