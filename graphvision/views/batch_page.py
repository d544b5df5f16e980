"""A batch with its report pages: ``report.md`` and ``report.html`` in each item folder, and
``batch.html`` beside ``batch.csv``. :func:`run_batch` is ``graphvision.run_batch``.

``batch.html`` names the pipeline (read from the first item's ``record.json``), and has
one card per file: its first picture, status, time, error and scalar outputs (the
metrics). Cards have a fixed width and wrap their text, so a long file name or error
never overflows them.
"""

from __future__ import annotations

import json
import os
from collections.abc import Sequence
from functools import partial, update_wrapper
from html import escape
from pathlib import Path
from urllib.parse import quote

from graphvision.execution import batch
from graphvision.execution.batch_files import BatchItem, BatchPages
from graphvision.views.report import RUN_PAGES

__all__ = ["BATCH_PAGES", "batch_page", "run_batch"]

_STYLE = (
    "body{font-family:sans-serif;margin:2em} .grid{display:flex;flex-wrap:wrap;gap:1em}"
    ".card{box-sizing:border-box;width:200px;color:inherit;text-decoration:none;"
    "border:1px solid #ddd;padding:.4em;overflow:hidden;overflow-wrap:anywhere}"
    ".card img{width:100%} .card.bad{border-color:#b71c1c}"
    ".failed{color:#b71c1c;font-size:.8em} .none{height:120px;background:#eee}"
    ".metrics{font-size:.8em;width:100%;table-layout:fixed;border-collapse:collapse}"
    ".metrics th{text-align:left;font-weight:normal;color:#555}"
    ".metrics td{text-align:right} .metrics th,.metrics td{overflow-wrap:anywhere}"
)


def _pipeline(items: Sequence[BatchItem]) -> tuple[str, str]:
    """The pipeline's name and file, from the first item folder whose record is readable."""
    for item in items:
        if item.output_dir is None:
            continue
        try:
            record = json.loads((Path(item.output_dir) / "record.json").read_text("utf-8"))
            return str(record.get("pipeline", "")), str(record.get("pipeline_file", ""))
        except (OSError, ValueError, AttributeError):
            continue
    return "", ""


def _metrics(item: BatchItem) -> str:
    """The item's scalar outputs as a two-column table."""
    rows = "".join(
        f"<tr><th>{escape(name)}</th><td>"
        f"{escape(f'{value:.4g}' if isinstance(value, float) else str(value))}</td></tr>"
        for name, value in item.scalars.items()
        if value != "" and value is not None
    )
    return f'<table class="metrics">{rows}</table>' if rows else ""


def _card(item: BatchItem, out_dir: str) -> str:
    """One file's card; ``out_dir`` is the batch's folder as an absolute path."""
    folder = os.path.abspath(item.output_dir) if item.output_dir is not None else ""
    names = _file_names(folder) if folder else set()
    pictures = sorted(name for name in names if name.endswith(".png"))
    image = (
        f'<img loading="lazy" alt="{escape(pictures[0])}" '
        f'src="{escape(_relative(os.path.join(folder, pictures[0]), out_dir))}">'
        if pictures
        else '<div class="none">no picture</div>'
    )
    error = f'<div class="failed">{escape(item.error)}</div>' if item.error else ""
    body = (
        f"{image}<div>{escape(Path(item.file).name)}</div>"
        f"<small>{escape(item.status)}, {item.seconds:.2f} s</small>{_metrics(item)}{error}"
    )
    kind = "ok" if item.status == "ok" else "bad"
    if "report.html" in names:  # a failed or interrupted file has no page to link to
        page = _relative(os.path.join(folder, "report.html"), out_dir)
        return f'<a class="card {kind}" href="{escape(page)}">{body}</a>'
    return f'<div class="card {kind}">{body}</div>'


def _file_names(folder: str) -> set[str]:
    """The names of the files in ``folder`` (links followed; none when it is not a folder),
    read in one listing: a card used to ask of each folder four times."""
    try:
        with os.scandir(folder) as entries:
            return {entry.name for entry in entries if entry.is_file()}
    except OSError:
        return set()


def batch_page(items: Sequence[BatchItem], out_dir: Path) -> str:
    """``batch.html``: the pipeline's name, and one card per file with its first picture,
    status, time, metrics and error, linking its own ``report.html``.

    Pictures are linked from the item folders (a batch of thousands stays a
    small page).
    """
    start = os.path.abspath(out_dir)
    cards = [_card(item, start) for item in items]
    failed = sum(item.status != "ok" for item in items)
    name, source = _pipeline(items)
    title = f"{name}: " if name else ""
    origin = f"<p>pipeline <code>{escape(source)}</code></p>" if source else ""
    return (
        '<!DOCTYPE html>\n<html lang="en"><head><meta charset="utf-8">'
        f"<title>{escape(title)}batch of {len(items)} files</title><style>{_STYLE}</style>"
        f"</head><body><h1>{escape(title)}{len(items) - failed} of {len(items)} files "
        f'succeeded</h1>{origin}<div class="grid">{"".join(cards)}</div></body></html>\n'
    )


def _relative(path: str, start: str) -> str:
    """``path`` as a relative URL from ``start`` (both absolute): percent-encoded, starting
    ``./`` or ``../``, so no file name can become a scheme (``javascript:``), a query or a
    fragment."""
    relative = os.path.relpath(path, start).replace(os.sep, "/")
    url = quote(relative, safe="/")
    return url if url.startswith("../") else f"./{url}"


BATCH_PAGES = BatchPages(run=RUN_PAGES, summary=batch_page)
"""Each item's ``report.md`` and ``report.html``, and the batch's ``batch.html``."""

run_batch = update_wrapper(partial(batch.run_batch, pages=BATCH_PAGES), batch.run_batch)
