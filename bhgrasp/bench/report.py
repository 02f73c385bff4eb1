"""The grasp benchmark's report: its JSON and markdown files, its summary, its comparison with committed trials.

The trials run in :mod:`~bhgrasp.bench.runs`; ``grasp_benchmark.json`` (``{"protocol": ..., "trials": [...]}``, SI
units) and ``grasp_benchmark.md`` (the success tables) report them.
A trial's ``set`` names the object set it came from (:data:`~bhgrasp.bench.objects.SETS`: ``development``, on
which the protocol's constants were chosen, or ``held-out``; ``""`` for an object given on the command line): the
report counts each set apart, so a held-out rate is never mixed with the rate the constants were chosen on.

``python -m bhgrasp grasp-bench`` is the command line.
"""

from __future__ import annotations

import functools
import json
import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from bhgrasp.bench.protocol import ACTUATIONS, DIRECTIONS, DISTURBED, FORCE_LIMIT, LOOSE, PRESHAPE, STRICT

OUTCOMES = ("success", "strict_success", "placed", "inside_envelope", "gripped", "approach")
METRICS = (
    "lifted",
    "max_displacement",
    "max_rotation",
    "slip_samples",
    "peak_contact_force",
    "peak_stand_force",
    "peak_joint_torque",
    "torque_to_rating",
    "need_to_rating",
    "held_force_F1",
    "held_force_F2",
    "held_force_F3",
)


STOP = ("approach_stopped", "approach_met")  # when the guarded approach stopped [s] and what the hand met there


def write_json(trials: list[dict[str, Any]], path: Path) -> None:
    """``{"protocol": ..., "trials": [...]}`` with sorted keys."""
    protocol = {
        "push_directions": list(DIRECTIONS),
        "push_force": "10 m [N]",
        "push_start": "each from the held grasp",
        "loose": {"displacement_m": LOOSE[0], "rotation_rad": LOOSE[1]},
        "strict": {"displacement_m": STRICT[0], "rotation_rad": STRICT[1]},
        "envelope": {"contact_force_n": FORCE_LIMIT, "joint_torque": "the hand's effort limit"},
    }
    path.write_text(json.dumps({"protocol": protocol, "trials": trials}, indent=1, sort_keys=True) + "\n")


def success_rates(trials: list[dict[str, Any]], group: str | None = None) -> dict[str, tuple[int, int, int]]:
    """Per actuation: (successes, strict successes, trials); of the trials of set ``group`` only if given."""
    if group is not None:
        trials = [t for t in trials if t.get("set", "") == group]
    rates = {}
    for actuation in ACTUATIONS:
        rows = [t for t in trials if t["actuation"] == actuation]
        if rows:
            rates[actuation] = (sum(t["success"] for t in rows), sum(t["strict_success"] for t in rows), len(rows))
    return rates


def distinct(trials: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """The trials without copies, the first of each kept.

    A copy: a grasp whose record equals another grasp's of the same object, actuation and spread in every outcome
    and, to ``compare``'s tolerance, every metric (the height rule put both at one height: one simulation, run
    twice; the two heights may differ by a rounding of the height search).
    """
    kept: list[dict[str, Any]] = []
    for t in trials:
        if not any(_copy(t, other) for other in kept):
            kept.append(t)
    return kept


def _copy(a: dict[str, Any], b: dict[str, Any]) -> bool:
    """Whether two trials' records agree but for the grasp (``distinct``)."""
    names = ("set", "spec", "actuation", "spread", *OUTCOMES, "failure")
    return all(a.get(n) == b.get(n) for n in names) and not _metric_problems(a, b, "", 1e-6)


def groups(trials: list[dict[str, Any]]) -> list[str]:
    """The object sets of ``trials`` in the order they first appear."""
    return list(dict.fromkeys(t.get("set", "") for t in trials))


def summary_lines(trials: list[dict[str, Any]], walls: Sequence[float] = (), spreads: bool = False) -> list[str]:
    """What ``bhgrasp grasp-bench`` prints: the success per set and actuation, each failure's reason, wall times.

    ``spreads``: a spread study (each failure names its spread).
    """
    lines = []
    for group in groups(trials):
        for actuation, (ok, strict, total) in success_rates(trials, group).items():
            lines.append(f"{f'{group} set, ' if group else ''}{actuation}: {ok}/{total} succeed ({strict} strict)")
    for trial in trials:
        if not trial["success"]:
            at = f" at spread {trial['spread']:g} rad" if spreads else ""
            lines.append(f"  {trial['object']} {trial['grasp']} {trial['actuation']}{at}: {trial['failure']}")
    among = [t for t in trials if t.get("neighbours")]
    if among:
        disturbed = int(sum(t["neighbours_disturbed"] or 0 for t in among))
        moved = f"moved over {1e3 * DISTURBED:.0f} mm"
        lines.append(f"among {among[0]['neighbours']} neighbours each: {disturbed} disturbed ({moved}) in all")
    if walls:
        lines.append(f"wall time per trial: {min(walls):.1f}-{max(walls):.1f} s")
    return lines


COMMAND = (
    "bhgrasp grasp-bench --set development --set held-out --json docs/results/grasp_benchmark.json "
    "--report docs/results/grasp_benchmark.md"
)  # the committed report's


def markdown(trials: list[dict[str, Any]], command: str = COMMAND) -> str:
    """The report: success per actuation, then one table row per trial (mm, deg, N, N m); ``command`` made it."""
    lines = [
        "# Grasp benchmark",
        "",
        f"Regenerate: `{command}`. "
        "Protocol: approach (guarded: the wrist stops where the hand meets anything with half its weight, and the "
        "trial goes on from there), close, lift 10 cm, push 10 m N on the object along +x, -x, +y, -y, +z, -z (2 s "
        "each, each from the held grasp, as DexGraspBench applies each afresh), place from it until the stand "
        "pushes up (on the object or a finger) with half the object's weight, "
        "open (`bhgrasp/bench/protocol.py`). Success: lifted; gripped once lifted (each finger pressing the "
        "object with at least m g / (n mu), n the fingers that close, no distal joint on its stop); within 5 cm "
        "and 15 deg of the closed grasp's pose in the palm frame from before the lift through the pushes; inside "
        "the real "
        f"hand's envelope all along (no contact force above {FORCE_LIMIT:.0f} N, twice Barrett's stalled "
        "fingertip force; no finger joint torque above its rating, the pucks' MT through ideal gears); and "
        "placed back on its stand (within 2 mm of its resting height, the stand carrying half its weight). "
        "Strict: 1 cm and 5 deg. Held F1/F2/F3: each finger's normal force on the object once lifted. Need x "
        "rating: a lower bound of the least fraction of the inner and outer joints' ratings with which forces at the "
        "hand's contact points on the object, inside the friction cones, carry its weight and each push at rest, in "
        "the grasp held before the pushes (pyramids circumscribing the cones, `bhgrasp/bench/need.py`; - where the "
        "hand did not touch it, no such forces carry a load, or the solver failed). A grasp marked (side) is a side "
        "pinch: where no top-down grasp height qualifies, the palm turns sideways and F1 and F2, spread to face "
        "each other, close in one horizontal plane while F3 stays open (`bhgrasp/bench/side.py`)."
        + (
            " A grasp marked (opened X rad) came down with its fingers opened wider than the pre-shape, where the "
            "open hand would meet the object on its way down (`bhgrasp/bench/opening.py`)."
            if any(_opened(t) for t in trials)
            else ""
        ),
        "",
        *(
            [
                "The development set is the one the protocol's constants were chosen on (`bhgrasp/bench/protocol.py` "
                "says which); each held-out set was fixed in the repository before anything was tuned against it "
                "(held-out-2 to held-out-5 before any of their trials ran; the README says how each was used).",
                "",
            ]
            if any(groups(trials))
            else []
        ),
        "Distinct trials: where a power and a precision grasp of an object stand at one height (the height or side "
        "rule puts both there), they are one simulation, run and listed twice; the last column counts it once.",
        "",
        "| object set | actuation | success | strict | trials | distinct trials: success / trials |",
        "|---|---|---:|---:|---:|---:|",
    ]
    for group in groups(trials):
        unique = success_rates(distinct(trials), group)
        for actuation, (ok, strict, total) in success_rates(trials, group).items():
            lines.append(
                f"| {group or 'given'} | {actuation} | {ok} ({100 * ok / total:.0f} %) | "
                f"{strict} ({100 * strict / total:.0f} %) | {total} | {unique[actuation][0]} / {unique[actuation][2]} |"
            )
    lines += [
        "",
        "| object | set | grasp | spread [deg] | actuation | success | strict | placed | max disp. [mm] | "
        "max rot. [deg] | slip samples | held F1/F2/F3 [N] | peak contact [N] | peak on stand [N] | "
        "peak joint torque [N m] | x rating | need x rating | envelope | failure |",
        "|---|---|---|---:|---|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|---|",
    ]
    for t in trials:
        number = functools.partial(_number, t)
        lines.append(
            f"| {t['object']} (`{t['spec']}`) | {t.get('set', '') or 'given'} | {t['grasp']}{_mark_grasp(t)} | "
            f"{number('spread', 180 / math.pi, '.0f')} | "
            f"{t['actuation']} | {_mark(t['success'])} | "
            f"{_mark(t['strict_success'])} | {_mark(t['placed'])} | {number('max_displacement', 1e3)} | "
            f"{number('max_rotation', 180 / math.pi)} | {number('slip_samples', fmt='.0f')} | "
            f"{'/'.join(number(f'held_force_{f}') for f in ('F1', 'F2', 'F3'))} | "
            f"{number('peak_contact_force')} | {number('peak_stand_force')} | "
            f"{number('peak_joint_torque', fmt='.2f')} | {number('torque_to_rating', fmt='.2f')} | "
            f"{number('need_to_rating', fmt='.2f')} | {_mark(t['inside_envelope'])} | {t['failure'] or ''} |"
        )
    return "\n".join(lines + _neighbour_lines(trials)) + "\n"


def _neighbour_lines(trials: list[dict[str, Any]]) -> list[str]:
    """The table of the neighbours each trial disturbed (moved over 5 mm), if the trials ran among neighbours."""
    among = [t for t in trials if t.get("neighbours")]
    if not among:
        return []
    lines = [
        "",
        f"Among neighbours: each trial ran among {among[0]['neighbours']} mixed household-sized objects (seed "
        f"{among[0]['neighbour_seed']}) dropped and settled on a table flush with its stand "
        f"(`bhgrasp/bench/neighbours.py`); a neighbour moved over {1e3 * DISTURBED:.0f} mm was disturbed. The stand's "
        "columns, and the stand's share of the object's weight once placed, count the table around it too. The hand "
        "turns about the object's axis to the first heading (0, +-15 deg, ... for a round object; 0 or 180 deg for a "
        "box) at which it passes every neighbour by 1 cm on its way down and while its fingers close, or else to the "
        "clearest (`bhgrasp/bench/heading.py`); the open hand starts high enough to clear every neighbour and comes "
        "down in the protocol's 1 s.",
        "",
        "| object | grasp | actuation | success | heading [deg] | neighbours disturbed | farthest moved [mm] | "
        "hand's peak on them [N] |",
        "|---|---|---|---|---:|---:|---:|---:|",
    ]
    for t in among:
        moved, force = _number(t, "max_neighbour_moved", 1e3), _number(t, "peak_neighbour_force")
        disturbed = "-" if t["neighbours_disturbed"] is None else t["neighbours_disturbed"]
        heading = _number(t, "heading", 180.0 / math.pi, ".0f")
        lines.append(
            f"| {t['object']} | {t['grasp']} | {t['actuation']} | {_mark(t['success'])} | {heading} | {disturbed} | "
            f"{moved} | {force} |"
        )
    return lines


def compare(trials: list[dict[str, Any]], reference: list[dict[str, Any]], rel: float = 1e-6) -> list[str]:
    """Differences of a run from the committed trials, matched by object spec, grasp and actuation.

    A difference: a trial missing from the reference, another outcome or failure, or a metric off by more than
    ``rel`` (relative; 1e-9 absolute).
    """
    index = {(t["spec"], t["grasp"], t["actuation"], t.get("spread")): t for t in reference}
    problems = []
    for trial in trials:
        key = (trial["spec"], trial["grasp"], trial["actuation"], trial.get("spread"))
        known = index.get(key)
        if known is None:
            problems.append(f"{key}: not in the reference")
            continue
        among = ("neighbours", "neighbour_seed", "neighbours_disturbed") if _among(trial, known) else ()
        for name in (*OUTCOMES, "most_loaded_joint", *STOP, "failure", *among):
            if trial.get(name) != known.get(name):
                problems.append(f"{key} {name}: {trial.get(name)!r}, reference {known.get(name)!r}")
        problems += _metric_problems(trial, known, str(key), rel)
    return problems


def _metric_problems(trial: dict[str, Any], known: dict[str, Any], key: str, rel: float) -> list[str]:
    """The metrics of ``trial`` off those of ``known`` by more than ``rel`` (relative; 1e-9 absolute)."""
    problems = []
    among = ("heading", "max_neighbour_moved", "peak_neighbour_force") if _among(trial, known) else ()
    for name in (*METRICS, *among):
        new, old = trial.get(name), known.get(name)
        if (new is None) != (old is None) or (new is not None and abs(new - old) > max(rel * abs(old), 1e-9)):
            problems.append(f"{key} {name}: {new!r}, reference {old!r}")
    return problems


def _among(*trials: dict[str, Any]) -> bool:
    """Whether any of ``trials`` ran among neighbours (then their neighbour fields are compared too)."""
    return any(t.get("neighbours") for t in trials)


def _number(trial: dict[str, Any], key: str, scale: float = 1.0, fmt: str = ".1f") -> str:
    """``trial[key]`` scaled and formatted; "-" where it is None or absent (a report written before it existed)."""
    value = trial.get(key)
    return "-" if value is None else format(scale * value, fmt)


def _mark_grasp(trial: dict[str, Any]) -> str:
    """The mark of a side pinch's grasp (:mod:`~bhgrasp.bench.side`) or of a wider opening, else nothing."""
    if trial.get("approach") == "side":
        return " (side)"
    return f" (opened {trial['opening']:.2f} rad)" if _opened(trial) else ""


def _opened(trial: dict[str, Any]) -> bool:
    """Whether a trial came down with its fingers opened wider than the pre-shape (:mod:`~bhgrasp.bench.opening`)."""
    opening = trial.get("opening")
    return opening is not None and opening < PRESHAPE


def _mark(value: bool) -> str:
    return "yes" if value else "no"


__all__ = ["METRICS", "OUTCOMES", "STOP", "compare", "distinct", "groups", "markdown", "success_rates", "write_json"]
