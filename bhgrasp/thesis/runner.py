"""One thesis chapter reproduced into a folder: its report, figures and figures of merit (``chapterN.json``)."""

from __future__ import annotations

import importlib
import time
from pathlib import Path

from bhgrasp.errors import InputError
from bhgrasp.thesis.results import write_results

CHAPTERS = ("ch3", "ch4", "ch5")


def run_chapter(chapter: str, output: Path, scale: float = 1.0, figures: bool = True, progress: bool = False) -> str:
    """Run chapter ``chapter`` (one of :data:`CHAPTERS`) into ``output``; returns what it made, for a reader.

    ``scale`` multiplies every case's duration; ``figures``: also draw them; ``progress``: a bar on stderr.
    """
    if chapter not in CHAPTERS:
        raise InputError(f"`chapter` must be one of {CHAPTERS}, got {chapter!r}")
    number = chapter[2:]
    module = importlib.import_module(f"bhgrasp.thesis.chapter{number}")
    start = time.perf_counter()
    cases = getattr(module, f"run_chapter{number}")(output, scale=scale, figures=figures, progress=progress)
    runs = sum(len(getattr(case, "runs", ())) for case in cases)
    counted = f", {runs} runs" if runs else ""
    return "\n".join(
        [
            f"{chapter}: {len(cases)} cases{counted} in {time.perf_counter() - start:.1f} s",
            f"report: {output / f'chapter{number}.md'}",
            f"figures of merit: {write_results(output, int(number), cases, scale)}",
        ]
    )


__all__ = ["CHAPTERS", "run_chapter"]
