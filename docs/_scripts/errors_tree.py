"""The trust page's generated half: the exception hierarchy, read from the package."""

from __future__ import annotations

import docstrings
import mkdocs_gen_files

import graphvision as gv


def _tree(cls: type, depth: int = 0) -> list[str]:
    doc = (cls.__doc__ or "").strip().splitlines()
    first = doc[0] if doc and cls is not gv.GraphvisionError else ""
    lines = [
        f"{'    ' * depth}- `{cls.__name__}`" + (f": {docstrings.inline(first)}" if first else "")
    ]
    subclasses: list[type] = cls.__subclasses__()
    for sub in sorted(subclasses, key=lambda c: c.__name__):
        if sub.__module__.split(".")[0] == "graphvision":
            lines += _tree(sub, depth + 1)
    return lines


def generate() -> None:
    lines = [
        "",
        "## Every error a user can cause",
        "",
        "Each derives from `gv.GraphvisionError` (read from the package when this site",
        "was built; each class's docstring in the [Python API](python-api.md#errors)):",
        "",
        *_tree(gv.GraphvisionError),
        "",
    ]
    with mkdocs_gen_files.open("reference/trust-and-errors.md", "a") as out:
        out.write("\n".join(lines))
