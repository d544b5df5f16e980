"""What a change repaints in the studio (Debian's Chromium through Playwright): the values a
node streams are drawn once, not fetched and drawn again when its run ends (issue 27 item 4:
the inspector was built again from scratch at every run's end, its pair viewers and formulas
included, which doubled the studio's paint time while the next change was already under way)."""

from __future__ import annotations

import shutil
from collections import Counter
from pathlib import Path

import pytest

pytest.importorskip("starlette")
sync_api = pytest.importorskip("playwright.sync_api", reason="playwright is not installed")

from graphvision.studio.server import studio  # noqa: E402

PIPELINES = Path(__file__).parents[2] / "pipelines"
BROWSER = next(
    (shutil.which(name) for name in ("chromium", "chromium-browser") if shutil.which(name)), None
)
pytestmark = pytest.mark.skipif(BROWSER is None, reason="no Chromium installed (CI installs one)")


def test_a_streamed_inspector_is_kept_and_its_value_asked_for_once() -> None:
    server = studio(PIPELINES / "coins.yaml")
    try:
        with sync_api.sync_playwright() as playwright:
            browser = playwright.chromium.launch(executable_path=BROWSER, args=["--no-sandbox"])
            page = browser.new_page(viewport={"width": 1500, "height": 950})
            errors: list[str] = []
            page.on("pageerror", lambda error: errors.append(str(error)))
            asked: Counter[str] = Counter()
            page.on("request", lambda r: asked.update([r.url.split("/api/", 1)[-1]]))
            page.goto(server.url)
            page.wait_for_selector("body[data-painted-run='1']", timeout=120_000)
            page.click("[data-node=binary]")
            page.wait_for_selector("[data-inspect=binary] [data-port='binary.out'] canvas")
            page.evaluate("document.querySelector('[data-inspect=binary]').dataset.mark = 'kept'")
            box = page.locator("[data-inspect=binary] [data-param=k] input.gv-number")
            box.fill("-0.3")
            box.press("Enter")
            page.wait_for_selector("body[data-painted-run='2']", timeout=120_000)
            # binary computed in run 2: its card was repainted as it finished (streamed)...
            card = "[data-inspect=binary] [data-port='binary.out']"
            assert page.get_attribute(card, "data-streamed") == "2"
            # ...and the run's end updated the panel's status and keys, nothing else
            assert page.get_attribute("[data-inspect=binary]", "data-mark") == "kept"
            assert page.inner_text("[data-inspect=binary] .gv-meta").startswith("status computed")
            keys = server.session.runs[-1].nodes["binary"]["keys"]
            assert page.inner_text("[data-inspect=binary] .gv-key") == "\n".join(
                f"{p}: {k}" for p, k in keys.items()
            )
            assert page.inner_text("[data-inspect=binary] td[data-shape=out]") == "303×384"
            assert asked["value/2/binary/out"] == 1  # binary is no output: its inspector card only
            assert errors == []
            browser.close()
    finally:
        server.stop()
