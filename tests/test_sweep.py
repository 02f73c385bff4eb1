"""Sweeps: designs, seeded cases, failures recorded, resume, process pool and Dask give the serial results."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

import bhgrasp as bh
from bhgrasp import sweep
from bhgrasp.cli import main
from bhgrasp.scenarios import hold_rollout


def projectile(parameters: dict, seed: int) -> dict:
    """Range of a projectile on flat ground (v^2 sin 2a / g), plus a seeded draw; fails for a negative speed."""
    speed, angle = parameters["speed"], parameters["angle"]
    if speed < 0:
        raise ValueError(f"negative speed {speed}")
    return {"range": speed**2 * math.sin(2 * angle) / 9.81, "draw": float(np.random.default_rng(seed).normal())}


DESIGN = sweep.grid(speed=[-1.0, 2.0, 5.0], angle=[0.3, 0.7])


def test_designs_are_full_factorial_and_seeded():
    assert len(DESIGN) == 6 and DESIGN[1] == {"speed": -1.0, "angle": 0.7}
    first, again = sweep.random_design(5, 3, mass=(0.2, 1.0)), sweep.random_design(5, 3, mass=(0.2, 1.0))
    assert first == again and all(0.2 <= case["mass"] <= 1.0 for case in first)
    assert sweep.case_seeds(4, 0) == sweep.case_seeds(4, 0) != sweep.case_seeds(4, 1)
    with pytest.raises(bh.InputError, match="axis 'mass'"):
        sweep.grid(mass=[])
    with pytest.raises(bh.InputError, match="low <= high"):
        sweep.random_design(3, 0, mass=(1.0, 0.2))


def test_serial_sweep_records_results_and_failures():
    table = sweep.run_sweep(projectile, DESIGN, seed=7, executor="serial")
    assert list(table["case"]) == list(range(6))
    ok = table[table["status"] == "ok"]
    np.testing.assert_allclose(ok["range"], ok["speed"] ** 2 * np.sin(2 * ok["angle"]) / 9.81)
    failed = table[table["status"] == "failed"]
    assert len(failed) == 2 and all("negative speed -1.0" in error for error in failed["error"])
    draws = [np.random.default_rng(s).normal() for s in sweep.case_seeds(6, 7)]
    np.testing.assert_allclose(ok["draw"], np.array(draws)[ok["case"]])


def test_process_pool_and_dask_give_the_serial_table():
    from distributed import Client, LocalCluster

    serial = sweep.run_sweep(projectile, DESIGN, seed=1, executor="serial").drop(columns="wall_time")
    pooled = sweep.run_sweep(projectile, DESIGN, seed=1, workers=2).drop(columns="wall_time")
    assert serial.equals(pooled)
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
        with Client(cluster) as client:
            dask = sweep.run_sweep(projectile, DESIGN, seed=1, executor=client.get_executor())
    assert serial.equals(dask.drop(columns="wall_time"))


def test_sweep_resumes_from_its_log(tmp_path: Path):
    log = tmp_path / "log.jsonl"
    sweep.run_sweep(projectile, DESIGN[:4], seed=2, log=log, executor="serial")  # an interrupted sweep's 4 cases
    lines = log.read_text().splitlines()
    lines = [json.dumps({**json.loads(line), "case": int(json.loads(line)["case"])}) for line in lines]
    log.write_text("\n".join(lines[:3]) + "\n")  # ... of which 3 reached the log
    calls = []

    def counting(parameters, seed):
        calls.append(parameters)
        return projectile(parameters, seed)

    finished = []
    table = sweep.run_sweep(counting, DESIGN, seed=2, log=log, executor="serial", on_row=finished.append)
    assert len(table) == 6 and len(calls) == 3  # only the missing cases ran
    # on_row saw each case that ran, as it finished, with the row the table holds (resumed rows are not re-announced)
    assert [row["case"] for row in finished] == [3, 4, 5]
    assert all(row == table.iloc[row["case"]].to_dict() for row in finished)
    assert len(log.read_text().splitlines()) == 6
    with pytest.raises(bh.InputError, match="another sweep"):
        sweep.run_sweep(projectile, DESIGN, seed=3, log=log, executor="serial")


def test_cli_sweeps_the_grasp_demo(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    config, csv = tmp_path / "sweep.toml", tmp_path / "grasp.csv"
    config.write_text(f"""
[sweep]
output = "{csv}"
workers = 2
seed = 4
progress = false

[grid]
mass = [0.3, 0.8]

[fixed]
estimate = 0.5
duration = 3.0
""")
    assert main(["sweep", str(config)]) == 0
    assert "2 cases, 0 failed" in capsys.readouterr().out
    import pandas as pd

    table = pd.read_csv(csv)
    np.testing.assert_allclose(table["mass_estimate"], table["mass"], rtol=0.02)  # each case learnt its own mass
    assert (table["slip_events"] == 0).all() and (table["force_error"] < 0.05).all()
    config.write_text("[sweep]\n[grid]\nmass = [0.3]\n[random]\nn = 2\n")
    assert main(["sweep", str(config)]) == 2
    assert "give exactly one of [grid] or [random] (got both)" in capsys.readouterr().err


BAD_CONFIGS = {
    '[sweep]\nworkers = "two"\n[grid]\nmass = [0.3]': "[sweep] workers: give an integer >= 0, got 'two'",
    "[sweep]\nworkrs = 2\n[grid]\nmass = [0.3]": "[sweep] workrs: unknown key; the keys are output, log, workers",
    "[grid]\nmasss = [0.3]": "[grid] masss: the grasp demo has no parameter 'masss'; it takes mass, estimate",
    "[grid]\nmass = [-0.3]": "[grid] mass: `mass` must be",
    "[grid]\nmass = [0.3, -0.3]": "case 1 (mass=-0.3): `mass` must be",
    '[grid]\nmass = [0.3]\n[fixed]\ncontroller = "pid"': "[fixed] controller: `controller` must be one of",
    "[grid]\nmass = [0.3]\n[fixed]\nseed = 3": "[fixed] seed: the case seed comes from the sweep",
    "[grid]\nmass = [0.3]\n[fixed]\nmass = 0.5": "[fixed] mass: also varied in the design",
    "[random]\nmass = [0.2, 1.0]": "[random] n: give the number of cases, a positive integer, got None",
    "[random]\nn = 3\nmass = 0.2": "[random] mass: give [low, high], got 0.2",
    "[grid]\nmass = [0.3]\n[grids]\nx = 1": "unknown table [grids]",
    "[fixed]\nmass = 0.3": "give exactly one of [grid] or [random] (got neither)",
}


@pytest.mark.parametrize("text", list(BAD_CONFIGS))
def test_a_sweep_file_mistake_is_named_before_anything_runs(text: str, tmp_path: Path, capsys) -> None:
    config = tmp_path / "sweep.toml"
    config.write_text(f'[sweep]\noutput = "{tmp_path / "out.csv"}"\n' + text.replace("[sweep]\n", "", 1))
    assert main(["sweep", str(config)]) == 2
    captured = capsys.readouterr()
    assert BAD_CONFIGS[text] in captured.err and str(config) in captured.err
    assert captured.out == "" and not (tmp_path / "out.csv").exists() and not (tmp_path / "out.jsonl").exists()


def test_the_example_sweep_file_is_valid_and_documents_every_key() -> None:
    from bhgrasp.scenarios.grasp_demo import SWEEPABLE
    from bhgrasp.sweep_config import SETTINGS, load_config

    path = Path(__file__).resolve().parents[1] / "docs" / "sweep.toml"
    config = load_config(path)
    assert len(config.cases) == 6 and config.workers == 2 and config.seed == 7
    text = path.read_text()
    for key in (*SETTINGS, *SWEEPABLE, "[random]", "n ="):
        assert key in text, f"docs/sweep.toml does not mention {key}"


def test_a_changed_fixed_parameter_never_reuses_logged_rows(tmp_path: Path) -> None:
    log = tmp_path / "log.jsonl"
    design = sweep.grid(speed=[1.0, 2.0])
    sweep.run_sweep(projectile, [{**case, "angle": 0.3} for case in design], seed=2, log=log, executor="serial")
    with pytest.raises(bh.InputError, match=r"its case 0 has angle=0.3, this sweep's has angle=0.5; use a new log"):
        sweep.run_sweep(projectile, [{**case, "angle": 0.5} for case in design], seed=2, log=log, executor="serial")
    again = sweep.run_sweep(projectile, [{**case, "angle": 0.3} for case in design], seed=2, log=log, executor="serial")
    assert len(again) == 2 and len(log.read_text().splitlines()) == 2  # the same sweep resumes from its log


def test_failed_cases_exit_non_zero_with_a_summary(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    """A case that cannot be checked beforehand (too short for the fingers to close) fails at run time."""
    config = tmp_path / "sweep.toml"
    config.write_text(
        f'[sweep]\noutput = "{tmp_path / "out.csv"}"\nworkers = 1\nprogress = false\n'
        "[grid]\nmass = [0.3, 0.5]\n[fixed]\nduration = 0.05\n"
    )
    assert main(["sweep", str(config)]) == 1
    captured = capsys.readouterr()
    assert "2 cases, 2 failed" in captured.out
    assert "2 case(s) [0, 1] failed: InputError: the fingers did not close on the object within 0.05 s" in captured.err


def test_batched_hold_sweep_agrees_with_serial_runs_and_a_weak_squeeze_drops_the_box():
    """hold_rollout runs its cases in BatchSimulators: the same table from one batch, from batches of 2 on a process
    pool, and (for the reference gains) from the reference hold run alone; with 2 % of the squeeze the friction
    (0.8 x 0.16 N) cannot carry the 1.96 N box and it slides out, with the full squeeze it stays (< 1 mm)."""
    from bhgrasp.scenarios.hold import reference_hold

    design = sweep.grid(squeeze=[0.02, 1.0], posture_gain=[2.0, 4.0], duration=[0.3])
    one = sweep.run_sweep(hold_rollout, design, executor="serial").drop(columns="wall_time")
    pairs = sweep.BatchedRollout(hold_rollout.function, size=2)
    pooled = sweep.run_sweep(pairs, design, workers=2).drop(columns="wall_time")
    assert one.equals(pooled) and (one["status"] == "ok").all()
    drops = one.set_index(["squeeze", "posture_gain"])["drop"]
    assert drops[(0.02, 2.0)] > 0.01 and drops[(0.02, 4.0)] > 0.01
    assert abs(drops[(1.0, 2.0)]) < 1e-3 and abs(drops[(1.0, 4.0)]) < 1e-3
    hold = reference_hold()
    alone = hold.simulator.run(hold.controller, 0.3, state=hold.state, progress=False)
    assert drops[(1.0, 2.0)] == pytest.approx(hold.box_height - alone.object_position[-1, 0, 2], abs=1e-9)
    with pytest.raises(bh.InputError, match="`size` must be a positive integer"):
        sweep.BatchedRollout(hold_rollout.function, size=0)
    failed = sweep.run_sweep(hold_rollout, [{"mass": 0.3}], executor="serial")
    assert failed["status"][0] == "failed" and "hold_rollout has no parameters ['mass']" in failed["error"][0]
