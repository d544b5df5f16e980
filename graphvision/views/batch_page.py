"""A batch with its report pages: ``report.md`` and ``report.html`` in each item folder, and
``batch.html`` beside ``batch.csv``. :func:`run_batch` is ``graphvision.run_batch``."""

from __future__ import annotations

from collections.abc import Sequence
from functools import partial, update_wrapper
from pathlib import Path

from graphvision.execution import batch
from graphvision.execution.batch_files import BatchItem, BatchPages
from graphvision.views.html import batch_page
from graphvision.views.report import RUN_PAGES

__all__ = ["BATCH_PAGES", "run_batch"]


def _summary_page(items: Sequence[BatchItem], out_dir: Path) -> tuple[str, str]:
    return "batch.html", batch_page(items, out_dir)


BATCH_PAGES = BatchPages(run=RUN_PAGES, summary=_summary_page)
"""Each item's ``report.md`` and ``report.html``, and the batch's ``batch.html``."""

run_batch = update_wrapper(partial(batch.run_batch, pages=BATCH_PAGES), batch.run_batch)
