"""One experiment of a thesis chapter (:class:`Case`), and the progress bar over a chapter's cases."""

from __future__ import annotations

from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass, field
from typing import Any, TypeVar

import numpy as np

from bhgrasp.parallel import progress_bar

T = TypeVar("T")


@dataclass
class Case:
    """One experiment: its table beside the thesis' numbers, notes, the table's numbers, its runs and figures.

    ``thesis`` is the thesis' own value(s) the case is compared with, where the table has one column for them.
    ``values`` maps names such as ``"laws/ctc/final_error_z_mm"`` (unit last) to the table's unrounded numbers;
    :mod:`bhgrasp.thesis.results` writes them to ``chapterN.json``.  ``runs`` holds the case's runs by name (a
    chapter-3 :class:`~bhgrasp.thesis.chapter3.Run`, a chapter-5
    :class:`~bhgrasp.scenarios.demo_result.GraspDemoResult`).  The figures: ``figures`` (file name -> a builder
    returning the figure), ``traces`` (chapter 4: name -> (t [s], force [N], desired force [N] or None)) and, for
    chapter 3's tracking figures, ``figure_title`` (default: ``title``) and ``figure_groups`` (run names split into
    blocks of rows, :func:`bhgrasp.plots.case_figures`).  ``tables``: more tables, as (caption, header, rows).
    """

    key: str
    title: str
    thesis: str = ""
    header: list[str] = field(default_factory=list)
    table: list[list[str]] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    values: dict[str, float] = field(default_factory=dict)
    runs: dict[str, Any] = field(default_factory=dict)
    figures: dict[str, Callable] = field(default_factory=dict)
    traces: dict[str, tuple[np.ndarray, np.ndarray, float | None]] = field(default_factory=dict)
    tables: list[tuple[str, list[str], list[list[str]]]] = field(default_factory=list)
    figure_title: str = ""
    figure_groups: tuple[tuple[str, ...], ...] | None = None


def case_progress(items: Iterable[T], total: int, label: str, progress: bool) -> Iterator[T]:
    """``items`` (a chapter's cases), behind a bar named ``label`` when ``progress`` (on stderr)."""
    bar = progress_bar(total, label, "case", enabled=progress)
    try:
        for item in items:
            yield item
            bar.update()
    finally:
        bar.close()


__all__ = ["Case", "case_progress"]
