"""Figures of merit of the thesis chapters as JSON, and the comparer.

``bhgrasp experiments chN --output DIR`` writes ``DIR/chapterN.json`` beside ``chapterN.md``: every number of the
report's tables under a named key (units in the key: ``_pct``, ``_s``, ``_mm``, ``_N`` ...), with sorted keys.
Chapters whose cases carry a ``values`` dict (3 and 5: full-precision floats recorded where the tables are built)
store those; a case without one (chapter 4) has its markdown table read back (:func:`table_values`), and then each
number also records its printed ``resolution`` (one unit of its last digit), because that is all it is known to.

The committed ``docs/results/chapterN.json`` are full-scale runs; :func:`compare_folders` (``bhgrasp experiments
compare NEW_DIR``) checks a new run against them within the tolerances of :mod:`bhgrasp.thesis.tolerances`.  The
README's "Results at a glance" table is rendered from those files (:mod:`bhgrasp.thesis.readme_rows`, ``bhgrasp
experiments readme-table``); ``tests/test_results.py`` asserts that the README holds exactly that table.

Regenerating every published number (reports, figures, JSON and the README table) is one command, from the
repository root::

    bhgrasp experiments all --output docs/results --force --readme README.md
"""

from __future__ import annotations

import json
import math
import re
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from bhgrasp.thesis.tolerances import tolerance_for

SCHEMA = 1
REPOSITORY = Path(__file__).resolve().parents[2]


def _reference_folder() -> Path:
    """The committed full-scale results: a checkout's docs/results, else the copy a wheel ships (bhgrasp/results)."""
    checkout = REPOSITORY / "docs" / "results"
    return checkout if checkout.is_dir() else Path(__file__).resolve().parents[1] / "results"


REFERENCE = _reference_folder()


# ---------------------------------------------------------------------------------------------------- extraction
_NUMBER = re.compile(r"(?<![A-Za-z_.\d])[-+]?(?:inf|nan|(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)(?![A-Za-z_])")


def slug(text: str) -> str:
    """A key segment: "->" is "to", "%" "pct", others than letters, digits, ``.``, ``-`` in a word (HOSMA-A): ``_``."""
    text = re.sub(r"(?<![A-Za-z0-9])-|-(?![A-Za-z0-9])", " ", text.replace("->", " to ").replace("%", " pct "))
    return re.sub(r"[^A-Za-z0-9.\-]+", "_", text).strip("_")


def _resolution(token: str) -> float:
    mantissa, _, exponent = token.lower().partition("e")
    decimals = len(mantissa.partition(".")[2])
    return 10.0 ** (int(exponent or 0) - decimals)


def table_values(case: Any) -> tuple[dict[str, float], dict[str, float]]:
    """Every number of a case's markdown table: ``{row/column: value}`` and each one's printed resolution.

    The first column names the row; rows that share it add the first column that tells them apart (as
    ``header=value``; failing one, every column that differs, then ``rowN``).  A cell with several numbers
    ("0.152 -> 0.124", "999.3 (999.0)") gives ``key#1``, ``key#2`` ...; cells without a number ("-") give nothing.
    """
    header, rows = list(case.header), [list(row) for row in case.table]
    labels = [slug(row[0]) for row in rows]
    for label in sorted({label for label in labels if labels.count(label) > 1}):
        group = [i for i, other in enumerate(labels) if other == label]
        columns = [c for c in range(1, len(header)) if len({rows[i][c] for i in group}) == len(group)][:1]
        if not columns:  # no single column tells them apart: every column that differs, then the occurrence
            columns = [c for c in range(1, len(header)) if len({rows[i][c] for i in group}) > 1]
        for i in group:
            labels[i] = "/".join([label, *(f"{slug(header[c])}={slug(rows[i][c])}" for c in columns)])
        if len({labels[i] for i in group}) < len(group):
            for n, i in enumerate(group, start=1):
                labels[i] += f"/row{n}"
    values: dict[str, float] = {}
    resolution: dict[str, float] = {}
    for label, row in zip(labels, rows):
        for name, cell in zip(header[1:], row[1:]):
            tokens = _NUMBER.findall(cell)
            for index, token in enumerate(tokens, start=1):
                key = f"{case.key}/{label}/{slug(name)}" + (f"#{index}" if len(tokens) > 1 else "")
                values[key] = float(token)
                if math.isfinite(values[key]):
                    resolution[key] = _resolution(token)
    return values, resolution


def figures_of_merit(cases: Iterable[Any]) -> tuple[dict[str, float], dict[str, float]]:
    """The named numbers of a chapter's cases (``case.values`` where given, else its table) and resolutions."""
    values: dict[str, float] = {}
    resolution: dict[str, float] = {}
    for case in cases:
        own = getattr(case, "values", None)
        if own:
            values.update({f"{case.key}/{key}": _plain(value) for key, value in own.items()})
        else:
            parsed, printed = table_values(case)
            values.update(parsed)
            resolution.update(printed)
    return values, resolution


def chapter4_figures(cases: Iterable[Any]) -> dict[str, float]:
    """Chapter 4's figures of merit, read from its report tables (:func:`table_values`)."""
    return figures_of_merit(cases)[0]


def _plain(value: Any) -> float | int:
    if isinstance(value, (bool, int)) or (hasattr(value, "dtype") and value.dtype.kind in "biu"):
        return int(value)
    return float(value)


def _encode(value: float | int) -> float | int | str:
    return value if isinstance(value, int) or math.isfinite(value) else str(value)  # "inf", "-inf", "nan"


def decode(value: Any) -> float | int:
    """A stored value back as a number (non-finite floats are stored as text)."""
    return float(value) if isinstance(value, str) else value


# ---------------------------------------------------------------------------------------------------- files
def results_document(chapter: int, cases: Iterable[Any], scale: float) -> dict[str, Any]:
    """The JSON document of a chapter's run (see the module docstring)."""
    values, resolution = figures_of_merit(cases)
    document: dict[str, Any] = {
        "schema": SCHEMA,
        "chapter": int(chapter),
        "command": f"bhgrasp experiments ch{chapter}",
        "scale": float(scale),
        "values": {key: _encode(value) for key, value in values.items()},
    }
    if resolution:
        document["resolution"] = resolution
    return document


def dumps(document: Mapping[str, Any]) -> str:
    """Deterministic JSON text: sorted keys, one value per line, no NaN/Infinity literals."""
    return json.dumps(document, sort_keys=True, indent=1, allow_nan=False) + "\n"


def write_results(output: Path, chapter: int, cases: Iterable[Any], scale: float = 1.0) -> Path:
    """Write ``output/chapterN.json`` for the cases that ``run_chapterN`` returned; return its path."""
    path = Path(output) / f"chapter{int(chapter)}.json"
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(dumps(results_document(chapter, cases, scale)))
    return path


def load(path: Path) -> dict[str, Any]:
    """A chapter's JSON document with its values decoded (non-finite values back to floats)."""
    document = json.loads(Path(path).read_text())
    document["values"] = {key: decode(value) for key, value in document["values"].items()}
    return document


# ---------------------------------------------------------------------------------------------------- comparing
@dataclass(frozen=True)
class Difference:
    """One key outside tolerance, missing from the new run, or extra in it (``None`` for an absent side)."""

    key: str
    reference: float | None
    new: float | None
    allowed: float | None

    @property
    def kind(self) -> str:
        """The difference's kind: "missing", "extra" or "outside"."""
        return "missing" if self.new is None else "extra" if self.reference is None else "outside"


def allowed_difference(chapter: int, key: str, reference: float, resolution: float = 0.0) -> float:
    """The largest |new - reference| that passes for ``key``."""
    tolerance = tolerance_for(chapter, key)
    return max(tolerance.abs, tolerance.rel * abs(reference), resolution * (1.0 + 1e-9))


def compare(new: Mapping[str, Any], reference: Mapping[str, Any]) -> list[Difference]:
    """Every difference between two chapter documents (:func:`load` or :func:`results_document`), keys sorted.

    A differing ``scale`` is reported as the key ``(scale)``: runs of different durations are not comparable.
    """
    chapter = int(reference.get("chapter", new.get("chapter", 0)))
    differences = []
    if float(new.get("scale", 1.0)) != float(reference.get("scale", 1.0)):
        differences.append(Difference("(scale)", float(reference["scale"]), float(new["scale"]), 0.0))
    old_values = {key: decode(value) for key, value in reference["values"].items()}
    new_values = {key: decode(value) for key, value in new["values"].items()}
    printed = {**new.get("resolution", {}), **reference.get("resolution", {})}
    for key in sorted(old_values.keys() | new_values.keys()):
        if key not in new_values or key not in old_values:
            differences.append(Difference(key, old_values.get(key), new_values.get(key), None))
            continue
        old, value = old_values[key], new_values[key]
        if not (math.isfinite(old) and math.isfinite(value)):
            if not (old == value or (math.isnan(old) and math.isnan(value))):
                differences.append(Difference(key, old, value, 0.0))
            continue
        allowed = allowed_difference(chapter, key, old, printed.get(key, 0.0))
        if abs(value - old) > allowed:
            differences.append(Difference(key, old, value, allowed))
    return differences


def format_differences(name: str, differences: Sequence[Difference], count: int) -> str:
    """A readable table of ``differences`` of ``name`` (``count`` values compared)."""
    kinds = [difference.kind for difference in differences]
    lines = [
        f"{name}: {kinds.count('outside')} of {count} values outside tolerance, {kinds.count('missing')} "
        f"missing, {kinds.count('extra')} extra"
    ]
    if not differences:
        return lines[0]
    width = max(len("key"), *(len(difference.key) for difference in differences))
    lines.append(f"  {'key':<{width}}  {'reference':>14}  {'new':>14}  {'|difference|':>12}  {'allowed':>9}")
    for d in differences:
        old = "(missing)" if d.reference is None else f"{d.reference:.8g}"
        new = "(missing)" if d.new is None else f"{d.new:.8g}"
        gap = f"{abs(d.new - d.reference):.3g}" if d.kind == "outside" else "-"
        allowed = "-" if d.allowed is None else f"{d.allowed:.2g}"
        lines.append(f"  {d.key:<{width}}  {old:>14}  {new:>14}  {gap:>12}  {allowed:>9}")
    return "\n".join(lines)


def compare_folders(new: Path, reference: Path = REFERENCE) -> tuple[bool, str]:
    """Compare every ``chapterN.json`` of folder ``new`` with the one in ``reference``: (all within, report)."""
    files = sorted(Path(new).glob("chapter*.json"))
    if not files:
        return False, f"no chapterN.json in {new}: run `bhgrasp experiments chN --output {new}` first"
    ok, parts = True, []
    for path in files:
        committed = Path(reference) / path.name
        if not committed.exists():
            ok = False
            parts.append(f"{path.name}: no reference {committed}")
            continue
        old, fresh = load(committed), load(path)
        differences = compare(fresh, old)
        ok = ok and not differences
        parts.append(format_differences(path.name, differences, len(old["values"].keys() | fresh["values"].keys())))
    return ok, "\n".join(parts)


__all__ = [
    "Difference",
    "allowed_difference",
    "chapter4_figures",
    "compare",
    "compare_folders",
    "decode",
    "dumps",
    "figures_of_merit",
    "format_differences",
    "load",
    "results_document",
    "slug",
    "table_values",
    "write_results",
]
