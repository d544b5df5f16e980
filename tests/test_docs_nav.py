"""Every page written under docs/ is in the site's navigation.

``make docs`` (strict) refuses a page left out of ``nav:``, but it runs every pipeline
and is not part of ``make test``; this catches the same omission in a second.
"""

from __future__ import annotations

from pathlib import Path

import yaml

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"


def _nav_pages(entry: object) -> list[str]:
    if isinstance(entry, str):
        return [entry]
    if isinstance(entry, list):
        return [page for item in entry for page in _nav_pages(item)]
    if isinstance(entry, dict):
        return [page for value in entry.values() for page in _nav_pages(value)]
    return []


def test_every_written_page_is_in_the_nav():
    config = yaml.load((ROOT / "mkdocs.yml").read_text(), Loader=yaml.BaseLoader)
    excluded = {line.strip().strip("/") for line in config["exclude_docs"].splitlines()}
    in_nav = set(_nav_pages(config["nav"]))
    written = {
        path.relative_to(DOCS).as_posix()
        for path in DOCS.rglob("*.md")
        if not any(path.relative_to(DOCS).as_posix().startswith(e) for e in excluded if e)
    }
    missing = sorted(written - in_nav)
    assert not missing, f"pages missing from mkdocs.yml's nav: {', '.join(missing)}"
