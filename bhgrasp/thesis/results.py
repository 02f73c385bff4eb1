"""Figures of merit of the thesis chapters as JSON, their tolerances, the comparer and the README's table.

``bhgrasp experiments chN --output DIR`` writes ``DIR/chapterN.json`` beside ``chapterN.md``: every number of the
report's tables under a named key (units in the key: ``_pct``, ``_s``, ``_mm``, ``_N`` ...), with sorted keys.
Chapters whose cases carry a ``values`` dict (3 and 5: full-precision floats recorded where the tables are built)
store those; a case without one (chapter 4) has its markdown table read back (:func:`table_values`), and then each
number also records its printed ``resolution`` (one unit of its last digit), because that is all it is known to.

The committed ``docs/results/chapterN.json`` are full-scale runs; :func:`compare_folders` (``bhgrasp experiments
compare NEW_DIR``) checks a new run against them within :data:`DEFAULT_TOLERANCE` or the first matching entry of
:data:`TOLERANCES`.  The README's "Results at a glance" table is rendered from those files
(:func:`render_readme_table`, ``bhgrasp experiments readme-table``); ``tests/test_results.py`` asserts that the
README holds exactly that table.

Regenerating every published number (reports, figures, JSON and the README table) is one command, from the
repository root::

    bhgrasp experiments all --output docs/results --force --readme README.md
"""

from __future__ import annotations

import fnmatch
import json
import math
import re
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from bhgrasp.thesis.readme_rows import README_HEADER, README_ROWS

SCHEMA = 1
REPOSITORY = Path(__file__).resolve().parents[2]


def _reference_folder() -> Path:
    """The committed full-scale results: a checkout's docs/results, else the copy a wheel ships (bhgrasp/results)."""
    checkout = REPOSITORY / "docs" / "results"
    return checkout if checkout.is_dir() else Path(__file__).resolve().parents[1] / "results"


REFERENCE = _reference_folder()


# ---------------------------------------------------------------------------------------------------- tolerances
@dataclass(frozen=True)
class Tolerance:
    """A value passes when ``|new - reference| <= max(abs, rel |reference|, resolution)``."""

    rel: float
    abs: float
    reason: str


DEFAULT_TOLERANCE = Tolerance(
    1e-6, 1e-9, "measured: two runs on one machine agree bit for bit; with other OpenBLAS kernels "
    "(OPENBLAS_CORETYPE=Prescott: ~1e-13 in a dot product) chapter 5's contact runs moved by <= 3e-11 relative, "
    "chapter 3's (but for the override below) by <= 1e-13, chapter 4's printed numbers not at all",
)  # fmt: skip

# pattern (fnmatch on "chapterN/key", "*" also spans "/"; first match wins) -> tolerance, each with its reason
TOLERANCES: dict[str, Tolerance] = {
    "chapter3/*/HOSM*-[AB]/*": Tolerance(2e-3, 1e-4, "HOSM laws A and B switch at e = e_dot = 0, and the adaptive "
                                         "ones integrate the switching: other OpenBLAS kernels moved HOSMA-A's "
                                         "planar final error by 7e-4 relative (3e-5 % of the range)"),
    "chapter4/tuning/*": Tolerance(1e-2, 0.0, "CMA-ES ranks candidates by a contact simulation's fitness, so a "
                                   "near-tie can steer the search: other OpenBLAS kernels moved the found K_I by "
                                   "7e-4 relative (6.2626 -> 6.2582)"),
    "chapter*/*settling*_s": Tolerance(1e-6, 1.5e-3, "the last exit from a band, sampled every 1 ms: a response that "
                                       "grazes the band's edge may leave it one sample earlier or later"),
    "chapter*/*touched_s": Tolerance(1e-6, 1.5e-3, "the first sample with contact: a threshold crossing (1 ms)"),
    "chapter*/*_within_*_s": Tolerance(1e-6, 1.5e-3, "the last exit from the 2 % band: a threshold crossing (1 ms)"),
    "chapter5/robustness/*/success_pct": Tolerance(0.0, 100.0 / 12, "a share of 12 runs, each a threshold test "
                                                   "(0.5 mm, 5 mrad, zero slip): a run that grazes a threshold may "
                                                   "count either way (measured: no change)"),
    "chapter5/*slip_events": Tolerance(0.0, 1.0, "slip events count sliding samples: a contact that grazes the cone "
                                       "may switch one sample earlier or later (measured: no change)"),
    "chapter5/synthesis/*/final_*": Tolerance(1e-6, 1e-5, "a final error of micrometres (and micro-radians) after "
                                              "the synthesised grasp's move: on an AVX-512 machine, with OpenBLAS's "
                                              "kernels held to Haswell's, proxsuite's runtime-dispatched ones moved "
                                              "the box's rx-0.15 final error by 5e-7 mm of 1.5e-3 (1e-5: 10 nm)"),
}  # fmt: skip


def tolerance_for(chapter: int, key: str) -> Tolerance:
    """The tolerance of ``key`` of chapter ``chapter``: the first matching pattern of TOLERANCES, else the default."""
    name = f"chapter{chapter}/{key}"
    for pattern, tolerance in TOLERANCES.items():
        if fnmatch.fnmatchcase(name, pattern):
            return tolerance
    return DEFAULT_TOLERANCE


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


def _decode(value: Any) -> float | int:
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
    document["values"] = {key: _decode(value) for key, value in document["values"].items()}
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
    old_values = {key: _decode(value) for key, value in reference["values"].items()}
    new_values = {key: _decode(value) for key, value in new["values"].items()}
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
    lines = [f"{name}: {kinds.count('outside')} of {count} values outside tolerance, {kinds.count('missing')} "
             f"missing, {kinds.count('extra')} extra"]  # fmt: skip
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


# ---------------------------------------------------------------------------------------------------- README table
_FIELD = re.compile(r"\{(\d+):([^:{}]+):([^{}]*)\}")
README_MARK = "<!-- generated from docs/results/chapterN.json by `bhgrasp experiments readme-table` -->"


def fill(template: str, documents: Mapping[int, Mapping[str, Any]]) -> str:
    """``template`` with each ``{N:key:format}`` replaced by that value of chapter N (KeyError: no such key)."""

    def value(match: re.Match) -> str:
        chapter, key, spec = int(match[1]), match[2], match[3]
        number = _decode(documents[chapter]["values"][key])
        if not (isinstance(number, int) or math.isfinite(number)):
            return str(number)
        return format(number, spec)

    # the literal "%" of the templates survives: fields are replaced one by one, no str.format over the whole
    return _FIELD.sub(value, template)


def load_folder(folder: Path = REFERENCE) -> dict[int, dict[str, Any]]:
    """Every ``chapterN.json`` of ``folder``, by chapter number."""
    return {int(path.stem[7:]): load(path) for path in sorted(Path(folder).glob("chapter*.json"))}


def render_readme_table(folder: Path = REFERENCE) -> str:
    """The README's "Results at a glance" table (marker comment and markdown table) from the JSON in ``folder``."""
    documents = load_folder(folder)
    lines = [README_MARK, "", "| " + " | ".join(README_HEADER) + " |", "|" + "---|" * len(README_HEADER)]
    for chapter, case, ours, thesis in README_ROWS:
        lines.append(f"| {chapter} | {case} | {fill(ours, documents)} | {thesis} |")
    return "\n".join(lines) + "\n"


def readme_table(readme_text: str) -> str:
    """The generated part of a README: from the marker comment to the end of the table after it."""
    start = readme_text.index(README_MARK)
    lines = readme_text[start:].splitlines()
    end = next(i for i in range(3, len(lines) + 1) if i == len(lines) or not lines[i].startswith("|"))
    return "\n".join(lines[:end]) + "\n"


def update_readme(readme: Path, folder: Path = REFERENCE) -> bool:
    """Rewrite the README's generated table from ``folder``; True if the file changed."""
    text = Path(readme).read_text()
    current = readme_table(text)
    fresh = render_readme_table(folder)
    if current == fresh:
        return False
    Path(readme).write_text(text.replace(current, fresh, 1))
    return True


__all__ = [
    "DEFAULT_TOLERANCE", "README_ROWS", "TOLERANCES", "Difference", "Tolerance", "allowed_difference",
    "chapter4_figures", "compare", "compare_folders", "dumps", "figures_of_merit", "fill", "format_differences",
    "load", "load_folder", "readme_table", "render_readme_table", "results_document", "slug",
    "table_values", "tolerance_for", "update_readme", "write_results",
]  # fmt: skip
