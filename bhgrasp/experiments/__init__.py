"""Reproductions of the thesis' results, one module per chapter."""

from collections.abc import Iterable, Iterator
from typing import TypeVar

from bhgrasp.experiments.chapter2 import THESIS_TABLE_2_2, WorkspaceRow, workspace_table

T = TypeVar("T")


def case_progress(items: Iterable[T], total: int, label: str, progress: bool) -> Iterator[T]:
    """``items`` (a chapter's cases), behind a tqdm bar named ``label`` when ``progress`` (on stderr)."""
    if not progress:
        yield from items
        return
    from tqdm import tqdm

    yield from tqdm(items, total=total, desc=label, unit="case", mininterval=0.5)


__all__ = ["THESIS_TABLE_2_2", "WorkspaceRow", "case_progress", "workspace_table"]
