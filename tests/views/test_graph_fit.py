"""The graph in a report fits the page, zooms, and no edge label overlaps another or a box:
measured from the drawing for every shipped pipeline, and from element boxes in a real
browser (Debian's Chromium; skipped where none is installed)."""

from __future__ import annotations

import html
import json
import re
import subprocess
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

import graphvision as gv
from graphvision.execution.batch_files import BatchItem
from graphvision.graph.svg import graph_svg
from graphvision.views.batch_page import batch_page
from graphvision.views.graph_view import GRAPH_SCRIPT, GRAPH_STYLE, graph_html

from .test_html import _browser

PIPELINES = sorted((Path(__file__).parents[2] / "pipelines").glob("*.yaml"))
SVG = "{http://www.w3.org/2000/svg}"
LABEL_CHAR = 6.2  # as the layout assumes for its 10 px labels


def _overlap(a: tuple[float, ...], b: tuple[float, ...]) -> bool:
    return a[0] < b[2] and b[0] < a[2] and a[1] < b[3] and b[1] < a[3]


@pytest.mark.parametrize("path", PIPELINES, ids=[p.stem for p in PIPELINES])
def test_no_edge_label_overlaps_another_or_a_box(path):
    root = ET.fromstring(graph_svg(gv.load_pipeline(path)))
    boxes = [
        (x := float(r.get("x")), y := float(r.get("y")), x + float(r.get("width")),
         y + float(r.get("height")))
        for g in root.findall(f"{SVG}g") if g.get("class") != "edge"
        for r in g.findall(f"{SVG}rect")
    ]  # fmt: skip
    labels = [
        (x := float(t.get("x"))) - LABEL_CHAR * len(t.text or "") and (
            x - LABEL_CHAR * len(t.text or ""), float(t.get("y")) - 9, x, float(t.get("y")) + 2
        )
        for g in root.findall(f"{SVG}g[@class='edge']") for t in g.findall(f"{SVG}text")
    ]  # fmt: skip
    for i, label in enumerate(labels):
        assert not any(_overlap(label, other) for other in labels[i + 1 :]), path.stem
        assert not any(_overlap(label, box) for box in boxes), path.stem


CHECK = """<script>
window.addEventListener("load", () => {
  const inside = (a, b) => a.left < b.right - 0.5 && b.left < a.right - 0.5
                        && a.top < b.bottom - 0.5 && b.top < a.bottom - 0.5;
  const graphs = [...document.querySelectorAll(".graph svg")].map(svg => {
    const r = svg.getBoundingClientRect();
    const labels = [...svg.querySelectorAll("g.edge text")].map(t => t.getBoundingClientRect());
    const boxes = [...svg.querySelectorAll("g:not(.edge) > rect")]
      .map(b => b.getBoundingClientRect());
    let clashes = 0;
    labels.forEach((a, i) => {
      clashes += labels.slice(i + 1).filter(b => inside(a, b)).length;
      clashes += boxes.filter(b => inside(a, b)).length;
    });
    return {name: svg.querySelector("title").textContent, left: r.left, right: r.right,
            height: r.height, clashes};
  });
  const first = document.querySelector(".graph svg");
  const before = first.getAttribute("viewBox");
  document.querySelector(".graph .zoom button").click();
  const zoomed = first.getAttribute("viewBox");
  [...document.querySelectorAll(".graph .zoom button")][2].click();
  const cards = [...document.querySelectorAll(".card")].map(c => c.scrollWidth - c.clientWidth);
  document.documentElement.setAttribute("data-check", JSON.stringify({
    width: window.innerWidth, height: window.innerHeight, graphs, cards,
    zoomed: zoomed !== before, fitted: first.getAttribute("viewBox") === before}));
});
</script>"""


@pytest.mark.skipif(_browser() is None, reason="no Chromium installed (CI installs one)")
def test_in_a_browser_every_graph_fits_the_viewport_and_zooms(tmp_path):
    graphs = "".join(graph_html(graph_svg(gv.load_pipeline(p))) for p in PIPELINES)
    long = "a_very_long_file_name_without_any_break_" * 4 + ".png"
    items = [
        BatchItem(tmp_path / long, tmp_path / "x", "failed", 1.0, "ValueError: " + "e" * 300),
        BatchItem(tmp_path / "b.png", tmp_path / "y", scalars={"m" * 80: 1.5, "psnr": 31.25}),
    ]
    batch = batch_page(items, tmp_path)  # its cards, as its own style draws them
    cards = batch.split("<body>")[1].split("</body>")[0]
    style = batch.split("<style>")[1].split("</style>")[0]
    page = tmp_path / "page.html"
    page.write_text(
        f'<!DOCTYPE html><html><head><meta charset="utf-8"><style>{GRAPH_STYLE}{style}'
        f"body{{margin:2em auto;max-width:1100px}}</style>{CHECK}</head><body>{graphs}"
        f"{cards}{GRAPH_SCRIPT}</body></html>"
    )
    command = [
        str(_browser()), "--headless", "--no-sandbox", "--disable-gpu",
        "--disable-background-networking", "--disable-component-update", "--disable-sync",
        "--no-first-run", f"--user-data-dir={tmp_path / 'profile'}", "--window-size=900,700",
        "--virtual-time-budget=5000", "--dump-dom", page.as_uri(),
    ]  # fmt: skip
    dom = subprocess.run(command, capture_output=True, text=True, timeout=120).stdout
    found = re.search(r'data-check="([^"]*)"', dom)
    assert found, "the page's load handler did not run"
    check = json.loads(html.unescape(found.group(1)))
    assert len(check["graphs"]) == len(PIPELINES)
    for graph in check["graphs"]:
        assert graph["left"] >= 0 and graph["right"] <= check["width"], graph["name"]
        assert graph["height"] <= 0.75 * check["height"] + 1, graph["name"]
        assert graph["clashes"] == 0, graph["name"]
    assert check["zoomed"] and check["fitted"]
    assert check["cards"] == [0, 0]  # nothing sticks out of a card
