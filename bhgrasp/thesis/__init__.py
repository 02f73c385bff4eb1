"""Reproductions of the thesis' results, chapters 2-5: one module per chapter, one ``Case`` per experiment.

``bhgrasp experiments chN`` runs a chapter (:func:`~bhgrasp.thesis.runner.run_chapter`);
:mod:`~bhgrasp.thesis.results` writes and compares its figures of merit (``docs/results``).
"""

from bhgrasp.thesis.case import Case, case_progress
from bhgrasp.thesis.chapter2 import THESIS_TABLE_2_2, WorkspaceRow, workspace_table
from bhgrasp.thesis.runner import CHAPTERS, run_chapter

__all__ = [
    "CHAPTERS",
    "THESIS_TABLE_2_2",
    "Case",
    "WorkspaceRow",
    "case_progress",
    "run_chapter",
    "workspace_table",
]
