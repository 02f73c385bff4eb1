"""Thesis chapter 4 reproduced: uncontrolled contact, PIM, FIM, adaptive FIM and CMA-ES-tuned impedance.

Environments are the thesis' compliant objects (4.3)-(4.7): a box of mass m_o = 0.25 kg on a spring K_s (plus a
light damper, 0.3 of critical, our choice: the thesis' undamped object rings forever) that can only move along the
pushing direction, touched through the simulator's spring-damper contact (k_c = 1e6 N/m, c = 200 N s/m).  The
fingertip therefore sees the static stiffness k_e = (1/K_s + 1/k_c)^-1, which is what FIM needs and what the
adaptive law must find.  The three-finger case presses a box that can only move vertically, so each finger sees the
contact stiffness itself.  Fully actuated fingers, dt = 1 ms, control at the same rate, fingertip computed torque
as the inner loop.

Choices where the thesis is silent or its values belong to its own model are listed in the report
(:func:`write_report`); the BH8-280's light links (fingertip effective mass ~0.05 kg) call for impedance masses
of tens of grams, not the thesis' 15 kg.

Our FIM and adaptive FIM add the feed-forward J^T f_d n to the inner loop (see
:mod:`bhgrasp.controllers.impedance`); the planar and F3 force cases also run the laws *as the thesis prints them*
(:func:`~bhgrasp.thesis.chapter4_closed_form.as_printed`: no feed-forward, the filter's acceleration passed
on, the gradient law (4.41) with a constant f_d), and set the steady force of every run beside the closed form of
:func:`~bhgrasp.thesis.chapter4_closed_form.steady_force`, the balance of impedance, environment and
inner-loop stiffness (:func:`~bhgrasp.thesis.chapter4_closed_form.inner_loop_stiffness`) that explains the
printed law's steady-state force error.

The chapter's code, one concept per module: :mod:`~bhgrasp.scenarios.finger_press` (the finger-and-object
benches, running them, the normal force and its metrics), :mod:`~bhgrasp.thesis.chapter4_metrics` (their report
rows), :mod:`~bhgrasp.thesis.chapter4_closed_form` (the laws as printed, the closed-form steady force),
:mod:`~bhgrasp.thesis.chapter4_contact` (contact without control, PIM), :mod:`~bhgrasp.thesis.chapter4_fim` (FIM,
adaptive FIM, three fingers), :mod:`~bhgrasp.scenarios.press_fitness` (the tuning's fitness) and
:mod:`~bhgrasp.thesis.chapter4_tuning` (the CMA-ES tuning).  This module holds the :data:`CASES` registry,
:func:`run_chapter4` and :func:`write_report`, and re-exports the cases and the closed forms.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path
from typing import Any

from bhgrasp.parallel import executor_for, parallel_map, progress_bar
from bhgrasp.scenarios.finger_press import (
    CONTACT,
    IMPACT_WINDOW,
    OBJECT_MASS,
)
from bhgrasp.thesis.case import Case
from bhgrasp.thesis.chapter4_closed_form import as_printed, friction_offset, inner_loop_stiffness, steady_force
from bhgrasp.thesis.chapter4_contact import f3_push, one_link_contact
from bhgrasp.thesis.chapter4_fim import f3_force, planar_impedance, three_fingers
from bhgrasp.thesis.chapter4_tuning import fingertip_mass_range, tuning, tuning_plan

CASES: dict[str, Callable[..., Case]] = {
    "one_link": one_link_contact,
    "f3_push": f3_push,
    "planar": planar_impedance,
    "f3_force": f3_force,
    "three": three_fingers,
    "tuning": tuning,
}


def run_chapter4(
    output: Path, scale: float = 1.0, figures: bool = True, executor: Any = None, progress: bool = False
) -> list[Case]:
    """Run every case (durations x ``scale``), write ``chapter4.md`` and figures into ``output``.

    ``progress``: a bar over the cases on stderr.
    """
    output = Path(output)
    output.mkdir(parents=True, exist_ok=True)
    cases = _run_cases(scale, executor, progress)
    names: dict[str, str] = {}
    if figures:
        from bhgrasp import plots

        for case in cases:
            names[case.key] = plots.save_force_figure(case, output / f"chapter4_{case.key}.png").name
    write_report(cases, output / "chapter4.md", names, scale)
    return cases


def _run_cases(scale: float, executor: Any, progress: bool = False) -> list[Case]:
    """Every case of :data:`CASES`, in order, the others evaluated on the tuning's executor while it tunes.

    ``executor``: ``None`` for one process pool of ``min(6, cpu_count)`` workers, ``"serial"`` for all here, one after
    another, or any Executor (as :func:`tuning`'s).  Results do not depend on it.  ``progress``: a bar over the
    cases (the tuning, the longest, counted first).
    """
    bar = progress_bar(len(CASES), "ch4", "case", enabled=progress)
    others = [key for key in CASES if key != "tuning"]
    done = {}
    try:
        with executor_for(executor, min(6, os.cpu_count() or 1)) as runner:
            if runner == "serial":
                for key, make in CASES.items():
                    done[key] = make(scale, runner) if key == "tuning" else make(scale)
                    bar.update()
                return [done[key] for key in CASES]
            running = parallel_map(_make_case, [(key, scale) for key in others], runner)  # submitted now
            done["tuning"] = tuning(scale, runner)  # tune while the others run
            bar.update()
            for outcome in running:
                done[others[outcome.index]] = outcome.result()
                bar.update()
    finally:
        bar.close()
    return [done[key] for key in CASES]


def _make_case(item: tuple[str, float]) -> Case:
    """Case ``key`` of :data:`CASES` at ``scale`` (runs in a worker, or here)."""
    key, scale = item
    return CASES[key](scale)


def _markdown_table(header: list[str], rows: list[list[str]]) -> list[str]:
    """Markdown table lines; a "|" inside a cell (as in "mean |error|") is escaped so it does not split the cell."""

    def line(cells: list[str]) -> str:
        return "| " + " | ".join(cell.replace("|", "\\|") for cell in cells) + " |"

    return [line(header), "|" + "---|" * len(header), *[line(row) for row in rows]]


def write_report(cases: list[Case], path: Path, figures: dict[str, str], scale: float) -> Path:
    """Markdown: per case our table beside the thesis' numbers, notes and the figure."""
    lines = [
        "# Thesis chapter 4 reproduced with bhgrasp",
        "",
        "Generated by `bhgrasp experiments ch4` (module `bhgrasp.thesis.chapter4`)"
        + (f", durations x {scale}" if scale != 1.0 else "")
        + ".  dt = control period = 1 ms; fully actuated fingers; fingertip computed torque inner loop; contact"
        f" law k_c = {CONTACT.stiffness:g} N/m, c = {CONTACT.damping:g} N s/m, mu = {CONTACT.friction:g};"
        f" objects m_o = {OBJECT_MASS} kg on a spring K_s with 0.3 of critical damping.",
        "Force metrics are measured from the first contact: 'impact' is the largest force in the first"
        f" {1e3 * IMPACT_WINDOW:g} ms (a stiff-contact collision spike that no controller can react to within its first"
        " samples), 'peak' the largest force after it and 'overshoot' that peak above f_d; 2 % settling is against"
        " f_d (against the final force where no force is desired); 'ss error' is |final - f_d| / f_d.",
        "",
    ]
    for case in cases:
        lines += [f"## {case.title}", "", *_markdown_table(case.header, case.table)]
        for caption, header, rows in case.tables:
            lines += ["", f"{caption}:", "", *_markdown_table(header, rows)]
        lines += ["", *[f"- {note}" for note in case.notes], ""]
        if case.key in figures:
            lines += [f"![{case.key}]({figures[case.key]})", ""]
    path.write_text("\n".join(lines) + "\n")
    return path


__all__ = [
    "CASES",
    "as_printed",
    "f3_force",
    "f3_push",
    "fingertip_mass_range",
    "friction_offset",
    "inner_loop_stiffness",
    "one_link_contact",
    "planar_impedance",
    "run_chapter4",
    "steady_force",
    "three_fingers",
    "tuning",
    "tuning_plan",
    "write_report",
]
