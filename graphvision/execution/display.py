"""How results show themselves in a notebook, without this layer knowing HTML.

A result's ``_repr_html_`` asks :func:`html_of`, which uses the renderer
registered for the result's type. The views layer registers its report page
(:mod:`graphvision.views.notebook`); the top-level package does that when
the first public name is used in a running IPython kernel. Without a
renderer, a result shows its record as a plain table.
"""

from __future__ import annotations

from collections.abc import Callable
from html import escape
from typing import Any

__all__ = ["html_of", "register_html"]

_RENDERERS: dict[type, Callable[[Any], str]] = {}


def register_html(kind: type, render: Callable[[Any], str]) -> None:
    """Show values of ``kind`` in a notebook as ``render(value)`` (an HTML fragment)."""
    _RENDERERS[kind] = render


def html_of(value: Any) -> str:
    """``value`` as HTML: its registered renderer's, or its text in a ``<pre>`` block."""
    for kind in type(value).__mro__:
        if kind in _RENDERERS:
            return _RENDERERS[kind](value)
    record = getattr(value, "record", value)
    text = record.table() if hasattr(record, "table") else repr(value)
    return f"<pre>{escape(text)}</pre>"
