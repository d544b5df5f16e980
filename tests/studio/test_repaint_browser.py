"""What a change repaints in the studio (Debian's Chromium through Playwright): the values a
node streams are drawn once, not fetched and drawn again when its run ends (issue 27 item 4:
the inspector was built again from scratch at every run's end, its pair viewers and formulas
included, which doubled the studio's paint time while the next change was already under way);
a picture shown twice is fetched once, on the canvas it was drawn on before."""

from __future__ import annotations

from collections import Counter
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("starlette")

import graphvision as gv
from graphvision.studio.server import studio

PIPELINES = Path(__file__).parents[2] / "pipelines"
TOY = Path(__file__).parents[1] / "fixtures" / "toy.py"


_CHANGE = """fetch("api/change", {method: "POST", headers: {"Content-Type": "application/json"},
  body: JSON.stringify({overrides: {"binary.k": -0.3}})})"""


def test_a_streamed_inspector_is_kept_and_its_value_asked_for_once(browser) -> None:
    server = studio(PIPELINES / "coins.yaml")
    try:
        page = browser.new_page(viewport={"width": 1500, "height": 950})
        errors: list[str] = []
        page.on("pageerror", lambda error: errors.append(str(error)))
        asked: Counter[str] = Counter()
        page.on("request", lambda r: asked.update([r.url.split("/api/", 1)[-1]]))
        page.goto(server.url)
        page.wait_for_selector("body[data-painted-run='1']", timeout=120_000)
        page.click("[data-node=overlay]")  # an output too: shown twice
        panel = "[data-inspect=overlay]"
        page.wait_for_selector(f"{panel} [data-port='overlay.out'] canvas")
        page.evaluate(f"document.querySelector('{panel}').dataset.mark = 'kept'")
        output = "[data-output=overlay] canvas"
        page.evaluate(f"document.querySelector('{output}').dataset.mark = 'same'")
        page.evaluate(_CHANGE)
        page.wait_for_selector("body[data-painted-run='2']", timeout=120_000)
        # coins computed in run 2: its cards were repainted as it finished (streamed)...
        for card in (f"{panel} [data-port='overlay.out']", "[data-output=overlay]"):
            assert page.get_attribute(card, "data-streamed") == "2"
        # ...and the run's end updated the panel's status and keys, nothing else
        assert page.get_attribute(panel, "data-mark") == "kept"
        assert page.inner_text(f"{panel} .gv-meta").startswith("status computed")
        keys = server.session.runs[-1].nodes["overlay"]["keys"]
        assert page.inner_text(f"{panel} .gv-key") == "\n".join(
            f"{p}: {k}" for p, k in keys.items()
        )
        assert page.inner_text(f"{panel} td[data-shape=out]") == "303×384×3"
        # the overlay's description, asked for in run 1, rode its node's event in run 2;
        # its picture was asked for once per step, shared by the output and the inspector
        assert asked["value/2/overlay/out"] == 0
        steps = [k for k in asked if k.startswith("rgba/2/overlay/out?")]
        assert steps and all(asked[k] == 1 for k in steps), asked
        # the same picture's new value was drawn on the same canvas (no card made again)
        assert page.get_attribute(output, "data-mark") == "same"
        assert page.get_attribute(output, "data-value") == "2/overlay/out"
        assert errors == []
    finally:
        server.stop()


def test_a_picture_shown_smaller_travels_as_a_preview_until_the_viewer_zooms_in(browser) -> None:
    graph = gv.Graph("wide")
    wide = np.linspace(0, 1, 32 * 4096, dtype=np.float32).reshape(32, 4096)  # shown smaller
    graph.input("image", "GrayImage", default=wide)
    graph.add("dark", "toy.darken", image="image", params={"factor": 0.5})
    graph.output("dark", "dark")
    server = studio(graph, registry=gv.discover([TOY]))
    try:
        page = browser.new_page(viewport={"width": 1500, "height": 950})
        asked: Counter[str] = Counter()
        page.on("request", lambda r: asked.update([r.url.split("/api/", 1)[-1]]))
        page.goto(server.url)
        page.wait_for_selector("body[data-painted-run='1']", timeout=120_000)
        page.evaluate(_CHANGE.replace('"binary.k": -0.3', '"dark.factor": 0.25'))
        page.wait_for_selector("body[data-painted-run='2']", timeout=120_000)
        canvas = "[data-output=dark] canvas"
        step = int(page.get_attribute(canvas, "data-preview") or 1)
        assert step > 1  # 4096 pixels across a card narrower than 2048
        assert asked[f"rgba/2/dark/out?step={step}"] == 1 and "rgba/2/dark/out?step=1" not in asked
        box = page.locator(canvas).bounding_box()
        assert box is not None
        page.mouse.move(box["x"] + box["width"] / 2, box["y"] + box["height"] / 2)
        page.mouse.wheel(0, -400 * step)  # zoomed in past the preview's pixels: the full one
        page.wait_for_selector(f"{canvas}:not([data-preview])", timeout=30_000)
        assert asked["rgba/2/dark/out?step=1"] == 1
    finally:
        server.stop()
