"""Published numbers: the chapters' JSON figures of merit, the comparer and its tolerances, the README's table."""

from __future__ import annotations

import json
import math
import re
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from bhgrasp.cli import main
from bhgrasp.thesis import chapter3, chapter5, readme_rows, results, tolerances

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"
COMMITTED = ROOT / "docs" / "results"


def document(values: dict, scale: float = 1.0, chapter: int = 5, resolution: dict | None = None) -> dict:
    out = {"schema": 1, "chapter": chapter, "scale": scale, "values": values}
    if resolution:
        out["resolution"] = resolution
    return out


# ---------------------------------------------------------------------------------------------------- committed files
@pytest.mark.parametrize("chapter", [3, 4, 5])
def test_committed_results_are_full_runs_written_deterministically(chapter: int) -> None:
    path = COMMITTED / f"chapter{chapter}.json"
    text = path.read_text()
    raw = json.loads(text)
    assert raw["chapter"] == chapter and raw["scale"] == 1.0 and raw["schema"] == results.SCHEMA
    assert results.dumps(raw) == text  # sorted keys, fixed layout: a rerun of the same numbers is byte-identical
    assert len(raw["values"]) > 20
    assert all(isinstance(value, (int, float)) or value in ("inf", "-inf", "nan") for value in raw["values"].values())
    assert not results.compare(results.load(path), results.load(path))


def test_readme_table_is_the_one_rendered_from_the_committed_json() -> None:
    assert readme_rows.readme_table(README.read_text()) == readme_rows.render_readme_table(COMMITTED)


def test_every_number_of_the_readme_table_comes_from_the_json() -> None:
    documents = readme_rows.load_folder(COMMITTED)
    for _, _, ours, _ in readme_rows.README_ROWS:
        assert not re.search(r"\d", readme_rows._FIELD.sub("", ours)), ours  # the words around the fields: no digits
        for match in readme_rows._FIELD.finditer(ours):
            assert match[2] in documents[int(match[1])]["values"], match[0]
    # and read back from the README itself: each number of the "ours" column is a formatted JSON value
    rows = [line.split(" | ") for line in readme_rows.readme_table(README.read_text()).splitlines()[4:]]
    assert len(rows) == len(readme_rows.README_ROWS)
    for row, (_, _, ours, _) in zip(rows, readme_rows.README_ROWS):
        shown = re.findall(r"-?\d+(?:\.\d+)?", row[2])
        fields = [readme_rows.fill(field[0], documents) for field in readme_rows._FIELD.finditer(ours)]
        assert shown == fields


def test_readme_table_is_rewritten_in_place(tmp_path: Path) -> None:
    readme = tmp_path / "README.md"
    text = README.read_text()
    stale = text.replace(readme_rows.readme_table(text), readme_rows.README_MARK + "\n\n| x |\n")
    readme.write_text(stale)
    assert readme_rows.update_readme(readme, COMMITTED)
    assert readme.read_text() == README.read_text()
    assert not readme_rows.update_readme(readme, COMMITTED)


# ---------------------------------------------------------------------------------------------------- comparer
def test_compare_passes_within_tolerance_and_lists_what_is_outside_missing_or_extra() -> None:
    reference = document({"a_mm": 1.0, "b_pct": 0.0, "gone_s": 2.0, "laws/ctc/settling_z_s": 0.19, "inf_s": "inf"})
    close = {"a_mm": 1.0 + 5e-7, "b_pct": 5e-10, "laws/ctc/settling_z_s": 0.191, "inf_s": math.inf, "new_N": 3.0}
    differences = results.compare(document(close), reference)
    assert [(d.key, d.kind) for d in differences] == [("gone_s", "missing"), ("new_N", "extra")]
    far = {**close, "a_mm": 1.01, "b_pct": 1e-3, "laws/ctc/settling_z_s": 0.25, "inf_s": 3.0, "gone_s": 2.0}
    far.pop("new_N")
    outside = results.compare(document(far), reference)
    assert [d.key for d in outside] == ["a_mm", "b_pct", "inf_s", "laws/ctc/settling_z_s"]
    assert all(d.kind == "outside" for d in outside)
    table = results.format_differences("chapter5.json", outside, 5)
    assert table.splitlines()[0] == "chapter5.json: 4 of 5 values outside tolerance, 0 missing, 0 extra"
    assert "a_mm" in table and "0.01" in table  # key and |difference| on its line


def test_compare_refuses_runs_of_another_scale() -> None:
    differences = results.compare(document({"a": 1.0}, scale=0.5), document({"a": 1.0}))
    assert [d.key for d in differences] == ["(scale)"]


def test_tolerances_default_tight_overrides_by_pattern_with_reasons() -> None:
    assert tolerances.DEFAULT_TOLERANCE.rel <= 1e-6 and tolerances.DEFAULT_TOLERANCE.abs <= 1e-9
    assert all(tolerance.reason for tolerance in tolerances.TOLERANCES.values())
    assert tolerances.tolerance_for(5, "smc/mass_estimate_kg") is tolerances.DEFAULT_TOLERANCE
    assert tolerances.tolerance_for(3, "ctc/joint_steps/F1_distal/settling_s").abs >= 1e-3
    assert tolerances.tolerance_for(5, "mass/1.0kg/pinv/slip_events").abs >= 1
    assert results.allowed_difference(4, "x", 10.0, resolution=0.01) == pytest.approx(0.01)  # printed digits


def test_table_values_reads_a_report_table() -> None:
    header = ["start", "found [M_I, K_I]", "F_d [N]", "error [N] untuned -> tuned", "overshoot %", "note"]
    table = [
        ["[0.5, 0.5]", "[0.0048, 6.2626]", "4", "0.080 -> 0.035", "-", "text"],
        ["[0.5, 0.5]", "[0.0048, 6.2626]", "6", "0.113 -> 0.048", "1.0e+00", "inf"],
    ]
    case = SimpleNamespace(key="tuning", header=header, table=table)
    values, resolution = results.table_values(case)
    assert values == {
        "tuning/0.5_0.5/F_d_N=4/found_M_I_K_I#1": 0.0048,
        "tuning/0.5_0.5/F_d_N=4/found_M_I_K_I#2": 6.2626,
        "tuning/0.5_0.5/F_d_N=4/F_d_N": 4.0,
        "tuning/0.5_0.5/F_d_N=4/error_N_untuned_to_tuned#1": 0.080,
        "tuning/0.5_0.5/F_d_N=4/error_N_untuned_to_tuned#2": 0.035,
        "tuning/0.5_0.5/F_d_N=6/found_M_I_K_I#1": 0.0048,
        "tuning/0.5_0.5/F_d_N=6/found_M_I_K_I#2": 6.2626,
        "tuning/0.5_0.5/F_d_N=6/F_d_N": 6.0,
        "tuning/0.5_0.5/F_d_N=6/error_N_untuned_to_tuned#1": 0.113,
        "tuning/0.5_0.5/F_d_N=6/error_N_untuned_to_tuned#2": 0.048,
        "tuning/0.5_0.5/F_d_N=6/overshoot_pct": 1.0,
        "tuning/0.5_0.5/F_d_N=6/note": math.inf,
    }
    assert resolution["tuning/0.5_0.5/F_d_N=4/found_M_I_K_I#1"] == pytest.approx(1e-4)
    assert resolution["tuning/0.5_0.5/F_d_N=6/overshoot_pct"] == pytest.approx(0.1)
    assert resolution["tuning/0.5_0.5/F_d_N=4/F_d_N"] == 1.0 and "tuning/0.5_0.5/F_d_N=6/note" not in resolution
    assert results.chapter4_figures([case]) == values


def test_written_json_round_trips_and_the_cli_compares_folders(tmp_path: Path, capsys) -> None:
    case = SimpleNamespace(
        key="smc",
        values={
            "mass_kg": np.float64(1.0008),
            "slip_events": np.int64(0),
            "settling_s": np.inf,
            "none_kg": float("nan"),
        },
    )
    new, reference = tmp_path / "new", tmp_path / "reference"
    path = results.write_results(new, 5, [case], scale=1.0)
    results.write_results(reference, 5, [case], scale=1.0)
    text = path.read_text()
    assert json.loads(text)["values"] == {
        "smc/mass_kg": 1.0008,
        "smc/none_kg": "nan",
        "smc/settling_s": "inf",
        "smc/slip_events": 0,
    }
    assert main(["experiments", "compare", str(new), "--reference", str(reference)]) == 0
    assert "0 of 4 values outside tolerance, 0 missing, 0 extra" in capsys.readouterr().out
    case.values["mass_kg"] = 1.2
    results.write_results(new, 5, [case], scale=1.0)
    assert main(["experiments", "compare", str(new), "--reference", str(reference)]) == 1
    out = capsys.readouterr().out
    assert "1 of 4 values outside tolerance" in out and "smc/mass_kg" in out and "1.0008" in out
    assert main(["experiments", "compare", str(tmp_path / "empty"), "--reference", str(reference)]) == 1
    assert main(["experiments", "compare"]) == 2  # the folder is required


def test_readme_table_command_prints_the_rendered_table(capsys) -> None:
    assert main(["experiments", "readme-table", "--reference", str(COMMITTED)]) == 0
    assert capsys.readouterr().out == readme_rows.render_readme_table(COMMITTED)


# ---------------------------------------------------------------------------------------------------- producers
def test_chapter3_values_are_the_table_unrounded() -> None:
    case = chapter3.planar_sinusoid(scale=0.1)
    assert len(case.values) == 4 * len(case.table)
    columns = {"max_error_pct": ".3f", "rms_error_pct": ".3f", "final_error_pct": ".4f", "chattering_Nm_per_s": ".3g"}
    for row in case.table:
        key = f"{'noise' if row[1] == 'yes' else 'clean'}/{row[0]}/{row[2]}"
        assert row[3:] == [format(case.values[f"{key}/{column}"], spec) for column, spec in columns.items()]


def test_chapter5_values_are_the_table_unrounded() -> None:
    case = chapter5.smc_adaptive(scale=0.6)  # through the grasp and into the move
    rows = dict(case.table)
    v = case.values
    assert rows["mass estimate (true 1.0 kg, start 0.5 kg) [kg]"] == f"{v['mass_estimate_kg']:.4f}"
    assert rows["slip events"] == str(v["slip_events"])
    assert rows["object final error [mm] / [mrad]"] == f"{v['final_error_z_mm']:.3f} / {v['final_error_rotx_mrad']:.3f}"
    assert rows["contact force error after settling [% of commanded]"] == f"{v['contact_force_error_pct']:.2f}"
