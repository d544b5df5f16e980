"""Results shown inline in a notebook: the run's report page as HTML.

:func:`register` tells the execution layer's display hook
(:mod:`graphvision.execution.display`) how to draw a run's result; the
top-level package calls it once, when a public name is first used inside a
running IPython kernel.
"""

from __future__ import annotations

from graphvision.execution.display import register_html
from graphvision.execution.record import RunResult
from graphvision.views.html import html_report

__all__ = ["register", "result_html"]


def result_html(result: RunResult) -> str:
    """The report's page of ``result`` (without its output folder's files)."""
    failures = {name: str(error) for name, error in result.failures.items()}
    return html_report(result.compiled, result.outputs, result.record, failures=failures)


def register() -> None:
    """Show run results in notebooks as their report page."""
    register_html(RunResult, result_html)
