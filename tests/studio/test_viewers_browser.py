"""The viewers in Chromium (Debian's, through Playwright), fed values built here through
the page's own bundle: matches over an image pair with inliers and outliers toggled, epipolar
lines, a mask tinted with an alpha slider, a cloud switched between image colour and depth,
a confusion matrix with right and wrong samples, training curves with labelled axes, and a
float map's colour bar with its units. Each is checked from the canvas's pixels or the DOM,
and screenshotted (to a temporary folder; GRAPHVISION_VIEWER_SHOTS=DIR keeps them)."""

from __future__ import annotations

import os
from collections.abc import Iterator
from pathlib import Path

import pytest

pytest.importorskip("starlette")

from graphvision.studio.server import StudioServer, studio

PIPELINES = Path(__file__).parents[2] / "pipelines"


@pytest.fixture(scope="module")
def page(browser, tmp_path_factory) -> Iterator[object]:
    server: StudioServer = studio(PIPELINES / "coins.yaml", run=False)
    try:
        opened = browser.new_page(viewport={"width": 900, "height": 900})
        errors: list[str] = []
        opened.on("pageerror", lambda error: errors.append(str(error)))
        opened.goto(server.url)
        opened.wait_for_selector("body[data-ready='1']", timeout=60_000)
        opened.add_script_tag(url=f"http://127.0.0.1:{server.port}/static/viewers.js")
        opened.add_script_tag(content=_SETUP)
        yield opened
        assert errors == []
    finally:
        server.stop()


def _shot(page, selector: str, name: str, tmp_path: Path) -> None:
    folder = Path(os.environ.get("GRAPHVISION_VIEWER_SHOTS", tmp_path))
    page.locator(selector).screenshot(path=str(folder / f"{name}.png"))


# Helpers in the page: a probe box, canvases of one colour, a fake run `source`.
_SETUP = """
window.probe = () => {
  document.querySelector('#probe')?.remove();
  const box = document.createElement('div');
  box.id = 'probe';
  box.style.cssText = 'position:fixed;left:0;top:0;width:800px;background:#fff;z-index:9';
  document.body.append(box);
  return box;
};
window.plain = (w, h, rgb) => {
  const c = document.createElement('canvas'); c.width = w; c.height = h;
  const ctx = c.getContext('2d'); ctx.fillStyle = `rgb(${rgb})`; ctx.fillRect(0, 0, w, h);
  return c;
};
window.pixel = (canvas, x, y) => [...canvas.getContext('2d').getImageData(x, y, 1, 1).data];
// the canvas pixel showing image pixel (x, y) of an ImageViewer
window.at = (viewer, x, y) => pixel(viewer.canvas, Math.floor(viewer.tx + (x + 0.5) * viewer.scale),
                                    Math.floor(viewer.ty + (y + 0.5) * viewer.scale));
// the canvas pixel at image point (x, y) exactly (a line through it covers it)
window.on = (viewer, x, y) => pixel(viewer.canvas, Math.round(viewer.tx + x * viewer.scale),
                                    Math.round(viewer.ty + y * viewer.scale));
"""

_MATCHES = """async () => {
  const box = probe();
  const d = {node: 'm', port: 'out', columns: {a: [0, 1], b: [0, 1]},
    pair: {all: ['m', 'out'], inliers: ['fit', 'inliers'],
           a: {keypoints: ['fa', 'keypoints'], image: ['ia', 'out']},
           b: {keypoints: ['fb', 'keypoints'], image: ['ib', 'out']}}};
  const values = {'fit/inliers': {columns: {a: [0], b: [0]}},
    'fa/keypoints': {columns: {x: [10, 10], y: [20, 80]}},
    'fb/keypoints': {columns: {x: [90, 90], y: [20, 80]}}};
  const source = {value: async (n, p) => values[`${n}/${p}`] ?? null, raw: async () => null,
    picture: async (n) => plain(100, 100, n === 'ia' ? '0,0,80' : '80,0,0')};
  const v = await GraphvisionViewers.matchesPanel(box, d, source);
  v.root.style.width = '800px'; v.resize(); v.fit();
  const gap = GraphvisionViewers.PAIR_GAP;
  const mid = (y) => on(v, (10 + 90 + 100 + gap) / 2, y);  // halfway along a match: in the gap
  const before = [mid(20), mid(80)];
  box.querySelector('[data-overlay^="outliers"]').click();
  const after = [mid(20), mid(80)];
  return {before, after, counts: v.root.dataset.matches,
          sides: [at(v, 50, 50), at(v, 100 + gap + 50, 50)]};
}"""


def test_matches_are_drawn_over_the_pair_inliers_and_outliers_toggled(page, tmp_path):
    found = page.evaluate(_MATCHES)
    assert found["counts"] == '{"inliers":1,"outliers":1}'
    assert found["sides"][0][:3] == [0, 0, 80] and found["sides"][1][:3] == [80, 0, 0]
    inlier, outlier = found["before"]
    assert inlier[1] > 150 > inlier[0]  # green (#22c55e) along the inlier at y = 20
    assert outlier[0] > 150 > outlier[1]  # red (#ef4444) along the outlier at y = 80
    assert found["after"][0] == inlier and found["after"][1][:3] == [34, 34, 34]  # hidden: the gap
    _shot(page, "#probe", "matches", tmp_path)


_EPIPOLAR = """async () => {
  const box = probe();
  // F of a pure x translation: the epipolar line of (x, y) is the row y in the other view
  const d = {value: [0, 0, 0, 0, 0, -1, 0, 1, 0],
    pair: {a: {points: ['fit', 'inliers_a'], image: ['ia', 'out']},
           b: {points: ['fit', 'inliers_b'], image: ['ib', 'out']}}};
  const raws = {inliers_a: [30, 25], inliers_b: [60, 70]};
  const source = {value: async () => null,
    raw: async (n, p) => ({values: new Float32Array(raws[p]), shape: [1, 2]}),
    picture: async (n) => plain(100, 100, '0,0,0')};
  const v = await GraphvisionViewers.epipolarPanel(box, d, source);
  v.root.style.width = '800px'; v.resize(); v.fit();
  const gap = GraphvisionViewers.PAIR_GAP;
  return {inB: on(v, 100 + gap + 50, 25), offB: at(v, 100 + gap + 50, 45), inA: on(v, 50, 70),
          count: v.root.dataset.epipolar};
}"""


def test_epipolar_lines_cross_the_other_view_at_the_points_row(page, tmp_path):
    found = page.evaluate(_EPIPOLAR)
    assert found["count"] == "2"
    assert found["inB"][0] > 150 and found["inB"][1] > 150  # #facc15, yellow, on row 25
    assert found["offB"][:3] == [0, 0, 0]
    assert found["inA"][0] > 150 and found["inA"][2] < 100  # #fb923c, orange, on row 70
    _shot(page, "#probe", "epipolar", tmp_path)


_MASK = """async () => {
  const box = probe();
  const v = new GraphvisionViewers.ImageViewer(box, {width: 40, height: 40});
  const values = new Float32Array(40 * 40);
  for (let i = 0; i < 20 * 40; i++) values[i] = 1;  // the top half is the mask
  const d = {view: 'mask', node: 'mask', port: 'out', shape: [40, 40], over: ['gray', 'out']};
  const source = {raw: async () => ({values, shape: [40, 40]}),
                  picture: async () => plain(40, 40, '0,0,255')};
  await GraphvisionViewers.maskLayer(v, d, source);
  v.root.style.width = '400px'; v.resize(); v.fit();
  const half = [at(v, 20, 5), at(v, 20, 35)];
  const slider = box.querySelector('[data-alpha]');
  slider.value = '1'; slider.dispatchEvent(new Event('input'));
  const full = at(v, 20, 5);
  box.querySelector('[data-layer]').click();
  return {half, full, off: at(v, 20, 5)};
}"""


def test_a_mask_is_tinted_over_its_image_with_an_alpha_slider_and_a_toggle(page, tmp_path):
    found = page.evaluate(_MASK)
    assert found["half"][0][:3] == [128, 0, 128] or abs(found["half"][0][0] - 128) <= 1
    assert found["half"][1][:3] == [0, 0, 255]  # outside the mask: the image
    assert found["full"][:3] == [255, 0, 0]  # alpha 1: the mask's red alone
    assert found["off"][:3] == [0, 0, 255]  # toggled off: the image
    _shot(page, "#probe", "mask", tmp_path)


_CLOUD = """() => {
  const box = probe();
  const points = [], colours = [];
  for (let i = 0; i < 400; i++) {
    points.push([i % 20, Math.floor(i / 20), 5]);
    colours.push([1, 0, 0]);
  }
  const root = GraphvisionViewers.pointCloudViewer(box, points, colours);
  const canvas = root.querySelector('canvas');
  const seen = () => {  // every colour drawn but the background
    const d = canvas.getContext('2d').getImageData(0, 0, canvas.width, canvas.height).data;
    const found = new Set();
    for (let i = 0; i < d.length; i += 4) found.add(`${d[i]},${d[i+1]},${d[i+2]}`);
    found.delete('17,17,17');
    return [...found];
  };
  const byImage = seen();
  const menu = root.querySelector('[data-cloud-colour]');
  menu.value = 'depth'; menu.dispatchEvent(new Event('change'));
  return {byImage, byDepth: seen(), mode: root.dataset.colour};
}"""


def test_a_cloud_switches_between_image_colour_and_depth(page, tmp_path):
    found = page.evaluate(_CLOUD)
    assert found["byImage"] == ["255,0,0"]
    assert found["byDepth"] == ["68,1,84"]  # one depth: viridis's low end
    assert found["mode"] == "depth"
    _shot(page, "#probe", "cloud", tmp_path)


_CLASSIFIER = """async () => {
  const box = probe();
  const pixels = [];
  for (let i = 0; i < 4; i++) for (let k = 0; k < 64; k++) pixels.push(i / 4);
  const d = {confusion: {classes: [0, 1], counts: [[2, 1], [0, 1]]},
    right: [[0, 0, 0], [2, 0, 0], [3, 1, 1]], wrong: [[1, 0, 1]], samples: ['split', 'test']};
  const source = {value: async () => ({side: [8, 8], pixels})};
  await GraphvisionViewers.classifierPanel(box, d, source);
  const curves = {loss: [2.3, 1.1, 0.6, 0.4], accuracy: [0.3, 0.6, 0.8, 0.9]};
  GraphvisionViewers.curvesViewer(box, curves);
  const cells = [...box.querySelectorAll('.gv-confusion td')].map((td) => td.textContent);
  return {caption: box.querySelector('.gv-confusion caption').textContent, cells,
    right: box.querySelectorAll('[data-samples=right] canvas').length,
    wrong: [...box.querySelectorAll('[data-samples=wrong] figcaption')].map((f) => f.textContent),
    axes: [...box.querySelectorAll('.gv-axis-x, .gv-axis-y')].map((t) => t.textContent),
    points: box.querySelectorAll('[data-curve=loss] circle').length};
}"""


def test_a_classifier_shows_its_confusion_matrix_samples_and_curves(page, tmp_path):
    found = page.evaluate(_CLASSIFIER)
    assert found["caption"].startswith("confusion matrix: 3 of 4 right (75.0 %)")
    assert found["cells"] == ["2", "1", "0", "1"]
    assert found["right"] == 3 and found["wrong"] == ["0 → 1"]
    assert found["axes"] == ["epoch", "loss", "epoch", "accuracy"]
    assert found["points"] == 4
    _shot(page, "#probe", "classifier", tmp_path)


def test_a_float_maps_colour_bar_names_its_units(page, tmp_path):
    title = page.evaluate("""() => {
      const box = probe();
      const values = new Float32Array(32 * 32).map((_, i) => i);
      GraphvisionViewers.floatMapViewer(box, {shape: [32, 32], type: 'Disparity', summary: '',
        units: 'disparity, pixels'}, values);
      return box.querySelector('.gv-bartitle').textContent;
    }""")
    assert title == "Disparity (disparity, pixels)"
    _shot(page, "#probe", "colourbar", tmp_path)


_REPORT_GRAPH = """() => {
  const svg = document.querySelector('.graph svg');
  const boxes = [...svg.querySelectorAll('.node rect, .edge-label rect')].map((e) => {
    const r = e.getBoundingClientRect();
    return [r.x, r.y, r.width, r.height]; });
  const clash = [];
  boxes.forEach((a, i) => boxes.slice(i + 1).forEach((b) => {
    const apart = a[0] >= b[0] + b[2] || b[0] >= a[0] + a[2] ||
      a[1] >= b[1] + b[3] || b[1] >= a[1] + a[3];
    if (!apart) clash.push([a, b]);
  }));
  const home = svg.getAttribute('viewBox');
  const [plus, , fit] = document.querySelectorAll('.graph .zoom button');
  plus.click();
  const zoomed = svg.getAttribute('viewBox');
  fit.click();
  return {layout: svg.dataset.layout, nodes: svg.querySelectorAll('.node').length, clash, home,
          zoomed, fitted: svg.getAttribute('viewBox'),
          status: svg.querySelector('[data-node=binary]').dataset.status};
}"""


def test_report_html_lays_its_graph_out_like_the_studio_and_keeps_zoom_and_fit(page, tmp_path):
    import graphvision as gv
    from graphvision.views.html import write_html_report

    result = gv.run(gv.load_pipeline(PIPELINES / "coins.yaml"), cache=None)
    page_path = write_html_report(result.compiled, result.outputs, result.record, tmp_path)
    report = page.context.browser.new_page(viewport={"width": 1200, "height": 900})
    errors: list[str] = []
    report.on("pageerror", lambda error: errors.append(str(error)))
    report.on("request", lambda r: errors.append(r.url) if r.url.startswith("http") else None)
    report.goto(page_path.as_uri())
    found = report.evaluate(_REPORT_GRAPH)
    _shot(report, ".graph", "report-graph", tmp_path)
    report.close()
    assert errors == []  # no script error, nothing fetched from the network
    assert found["layout"] == "dagre" and found["nodes"] == 11  # 1 input and 10 nodes
    assert found["clash"] == []
    assert found["zoomed"] != found["home"] and found["fitted"] == found["home"]
    assert found["status"] == "computed"
