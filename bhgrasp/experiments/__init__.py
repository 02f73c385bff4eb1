"""Reproductions of the thesis' results, one module per chapter."""

from bhgrasp.experiments.chapter2 import THESIS_TABLE_2_2, WorkspaceRow, workspace_table

__all__ = ["THESIS_TABLE_2_2", "WorkspaceRow", "workspace_table"]
