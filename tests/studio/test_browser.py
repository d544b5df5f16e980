"""The studio in a real browser (Debian's Chromium driven by Playwright; nothing downloads
a browser): tuning coins.yaml, the graph of every shipped pipeline, the token."""

from __future__ import annotations

import os
from collections.abc import Iterator
from pathlib import Path

import pytest

pytest.importorskip("starlette")

from graphvision.studio.server import StudioServer, studio

PIPELINES = Path(__file__).parents[2] / "pipelines"
# The README's picture, written again when GRAPHVISION_UPDATE_SCREENSHOT=1 (else to a
# temporary folder: a test run leaves the work tree as it was).
SCREENSHOT = Path(__file__).parents[2] / "docs" / "assets" / "studio.png"


@pytest.fixture
def coins() -> Iterator[StudioServer]:
    server = studio(PIPELINES / "coins.yaml")
    yield server
    server.stop()


# true once the inspector's number box of node.param reads the value
_BOX_READS = """([node, param, value]) => document.querySelector(
    `[data-inspect=${node}] [data-param=${param}] input.gv-number`)?.value === value"""


def _painted(page, run: int) -> None:
    page.wait_for_selector(f"body[data-painted-run='{run}']", timeout=120_000)


def _labels_png(page, server: StudioServer) -> bytes:
    source = page.get_attribute("[data-output=labels] canvas", "data-value")
    response = page.request.get(f"http://127.0.0.1:{server.port}/api/png/{source}")
    assert response.ok
    return response.body()


def test_tuning_the_threshold_repaints_the_count_and_labels(browser, coins, tmp_path) -> None:
    page = browser.new_page(viewport={"width": 1500, "height": 950})
    errors: list[str] = []
    page.on("pageerror", lambda error: errors.append(str(error)))
    page.goto(coins.url)
    _painted(page, 1)
    assert page.inner_text("[data-output=count] .gv-scalar") == "24"
    before = _labels_png(page, coins)
    other = browser.new_page()  # a second tab on the same session
    other.goto(coins.url)
    _painted(other, 1)
    other.click("[data-node=binary]")
    page.click("[data-node=binary]")
    box = page.locator("[data-inspect=binary] [data-param=k] input.gv-number")
    box.fill("-0.3")
    box.press("Enter")
    _painted(page, 2)
    assert page.inner_text("[data-output=count] .gv-scalar") == "23"
    assert _labels_png(page, coins) != before
    _painted(other, 2)  # the other tab follows the session, its widgets too
    assert other.inner_text("[data-output=count] .gv-scalar") == "23"
    other.wait_for_function(_BOX_READS, arg=["binary", "k", "-0.3"], timeout=10_000)
    other.close()
    assert page.get_attribute("[data-node=gray]", "data-state") == "cached"
    assert page.get_attribute("[data-node=overlay]", "data-state") == "computed"
    run = coins.session.runs[-1]  # the run record says what ran, not the page
    statuses = {node.name: node.status for node in run.record.nodes}
    assert statuses == {
        "gray": "cached", "disk": "cached", "binary": "computed", "closed": "computed",
        "filled": "computed", "opened": "computed", "labels": "computed",
        "measured": "computed", "coins": "computed", "overlay": "computed",
    }  # fmt: skip
    # an invalid value is refused inline with the validator's message, and nothing runs
    window = page.locator("[data-inspect=binary] [data-param=window] input.gv-number")
    window.fill("2")
    window.press("Enter")
    message = page.locator("[data-inspect=binary] [data-param=window] .gv-invalid")
    message.wait_for(state="visible")
    assert "greater than or equal to 3" in message.inner_text()
    # a number too large for the page: the box keeps what was typed and says why it is refused
    box.fill("1e400")
    box.press("Enter")
    refused = page.locator("[data-inspect=binary] [data-param=k] .gv-invalid")
    refused.wait_for(state="visible")
    assert refused.inner_text().startswith("out of range: 1e400 is beyond ±1.8e+308")
    assert len(coins.session.runs) == 2
    # the runs table writes the change from the file's number (k: 0.0 in coins.yaml)
    page.wait_for_function(
        "document.querySelector('#runs tr[data-run=\"2\"]')?.textContent.includes("
        "'binary.k: 0 → -0.3')",
        timeout=10_000,
    )
    # a tab that goes away in the middle of a run: the run finishes, the server serves on
    leaving = browser.new_page()
    leaving.goto(coins.url)
    _painted(leaving, 2)
    leaving.evaluate(
        "fetch('api/change', {method: 'POST', headers: {'Content-Type': 'application/json'},"
        " body: JSON.stringify({overrides: {'binary.k': -0.2}})})"
    )
    leaving.close()
    for _ in range(300):
        if len(coins.session.runs) == 3:
            break
        page.wait_for_timeout(20)
    coins.session.wait()
    assert coins.session.runs[-1].status == "done"
    _painted(page, 3)
    page.wait_for_function(_BOX_READS, arg=["binary", "k", "-0.2"], timeout=10_000)
    page.evaluate("document.querySelector('#side').scrollTop = 0")
    update = os.environ.get("GRAPHVISION_UPDATE_SCREENSHOT") == "1"
    shot = SCREENSHOT if update else tmp_path / "studio.png"
    page.screenshot(path=str(shot))
    assert shot.stat().st_size > 10_000
    box.press("ArrowDown")  # the arrows step the box, as a number box's did
    _painted(page, 4)
    stepped = coins.session.overrides["binary.k"]
    assert stepped < -0.2 and box.input_value() == repr(stepped)
    assert errors == []


def _overlapping(boxes: list[tuple[str, dict]]) -> list[tuple[str, str]]:
    found = []
    for i, (a, p) in enumerate(boxes):
        for b, q in boxes[i + 1 :]:
            apart_x = p["x"] + p["width"] <= q["x"] + 0.5 or q["x"] + q["width"] <= p["x"] + 0.5
            apart_y = p["y"] + p["height"] <= q["y"] + 0.5 or q["y"] + q["height"] <= p["y"] + 0.5
            if not (apart_x or apart_y):
                found.append((a, b))
    return found


def test_no_two_graph_nodes_or_labels_overlap(browser) -> None:
    """Every shipped pipeline, drawn by the viewers bundle (the one report.html can inline)."""
    import graphvision as gv
    from graphvision.compiler.compile import compile_graph
    from graphvision.studio.describe import describe_graph

    registry = gv.discover()
    server = studio(PIPELINES / "coins.yaml", run=False)
    try:
        page = browser.new_page(viewport={"width": 1400, "height": 900})
        page.goto(server.url)
        page.wait_for_selector("body[data-ready='1']", timeout=60_000)
        page.add_script_tag(url=f"http://127.0.0.1:{server.port}/static/viewers.js")
        checked = 0
        for path in sorted(PIPELINES.glob("*.yaml")):
            graph = gv.load_pipeline(path)
            drawn = describe_graph(graph, compile_graph(graph, registry), {})
            boxes, spill = page.evaluate(_DRAW, drawn)
            assert len(boxes) >= 2, path.name
            assert _overlapping(boxes) == [], path.name
            assert spill == [], path.name  # every node's text stays inside its box
            checked += 1
        assert checked >= 30
    finally:
        server.stop()


_DRAW = """(graph) => {
  document.querySelector('#probe')?.remove();
  const box = document.createElement('div');
  box.id = 'probe';
  box.style.cssText = 'position:fixed;left:0;top:0;width:1400px;height:900px;background:#fff';
  document.body.append(box);
  new GraphvisionViewers.GraphView(box, graph);
  const boxes = [...box.querySelectorAll('.gv-node rect, .gv-edge-label')].map(e => {
    const r = e.getBoundingClientRect();
    const name = e.closest('.gv-node')?.dataset.node || e.dataset.edge;
    return [name, {x: r.x, y: r.y, width: r.width, height: r.height}]; });
  const spill = [...box.querySelectorAll('.gv-node')].filter(g => {
    const r = g.querySelector('rect').getBoundingClientRect();
    return [...g.querySelectorAll('text')].some(t => {
      const b = t.getBoundingClientRect();
      return b.width && (b.left < r.left || b.right > r.right + 0.5); }); })
    .map(g => g.dataset.node);
  return [boxes, spill];
}"""
