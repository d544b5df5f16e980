"""A line per test file as it completes (its tests passed, failed, skipped and its time),
instead of minutes of progress dots; loaded by ``tests/conftest.py``, with or without
pytest-xdist (the lines then come from the controller, as workers report)."""

from __future__ import annotations

import time
from collections import Counter, defaultdict

import pytest


class FileSummary:
    def __init__(self, config: pytest.Config) -> None:
        self.config = config
        self.expected: Counter[str] = Counter()
        self.outcomes: dict[str, Counter[str]] = defaultdict(Counter)
        self.first: dict[str, float] = {}
        self.finished: Counter[str] = Counter()

    @staticmethod
    def file_of(nodeid: str) -> str:
        return nodeid.split("::", 1)[0]

    def pytest_collection_modifyitems(self, items: list[pytest.Item]) -> None:
        if not self.expected:  # without xdist: this process collected them
            self.expected.update(self.file_of(item.nodeid) for item in items)

    @pytest.hookimpl(optionalhook=True)
    def pytest_xdist_node_collection_finished(self, node: object, ids: list[str]) -> None:
        if not self.expected:  # every worker collects the same tests: count them once
            self.expected.update(self.file_of(nodeid) for nodeid in ids)

    def pytest_runtest_logreport(self, report: pytest.TestReport) -> None:
        file = self.file_of(report.nodeid)
        self.first.setdefault(file, time.monotonic())
        if report.failed:
            self.outcomes[file]["failed"] += 1 if report.when != "teardown" else 0
            self.outcomes[file]["errors"] += 1 if report.when == "teardown" else 0
        elif report.skipped and report.when == "setup":
            self.outcomes[file]["skipped"] += 1
        elif report.passed and report.when == "call":
            self.outcomes[file]["passed"] += 1
        if report.when == "teardown":
            self.finished[file] += 1
            if self.finished[file] == self.expected.get(file, -1):
                self.announce(file)

    def announce(self, file: str) -> None:
        counts = self.outcomes[file]
        parts = [f"{counts[k]} {k}" for k in ("passed", "failed", "errors", "skipped") if counts[k]]
        seconds = time.monotonic() - self.first[file]
        reporter = self.config.pluginmanager.get_plugin("terminalreporter")
        if reporter is not None:
            reporter.write_line(f"{file}: {', '.join(parts) or 'nothing ran'} ({seconds:.1f} s)")

    @pytest.hookimpl(hookwrapper=True)
    def pytest_report_teststatus(self, report: pytest.TestReport, config: pytest.Config):  # type: ignore[no-untyped-def]
        outcome = yield
        result = outcome.get_result()
        if result and config.getoption("verbose") <= 0:  # no progress letters: lines per file
            category, _, word = result
            outcome.force_result((category, "", word))
