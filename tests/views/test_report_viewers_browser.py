"""report.html's values drawn by the studio's viewers in Chromium (Debian's, through
Playwright; nothing downloads): a label map tinted over its image (toggle, alpha slider),
a network's training curves with labelled axes and a legend, a classifier's confusion
matrix with its right and wrong samples, a point cloud in 3-D by image colour or depth,
matches over their image pair (inliers and outliers apart, toggled); images and float maps
with the value under the cursor the array's own at that pixel (a map sent reduced names
the full map's pixel), a range box that recolours, and the PNGs kept without script (one
report, stereo.yaml's outputs made by the test, loaded once with script and once without).
Checked from the canvas's pixels and the DOM; each wait has a deadline
(GRAPHVISION_VIEWER_SHOTS=DIR keeps screenshots)."""

from __future__ import annotations

import os
import re
from pathlib import Path
from unittest import mock

import numpy as np
import pytest

from graphvision.views import scripted

from .report_values import (
    GRAY,
    classifier_values,
    cnn_page,
    coins_page,
    homography_page,
    stereo_maps,
    stereo_maps_page,
    stereo_page,
)

DEADLINE = 30_000  # ms


def _open(browser, html: str, folder: Path) -> object:
    path = folder / "report.html"
    path.write_text(html, encoding="utf-8")
    page = browser.new_page(viewport={"width": 1000, "height": 900})
    errors: list[str] = []
    page.on("pageerror", lambda error: errors.append(str(error)))
    page.goto(path.as_uri())
    page.wait_for_selector("html[data-values-shown='1']", state="attached", timeout=DEADLINE)
    page.errors = errors
    return page


def _shot(page, selector: str, name: str, tmp_path: Path) -> None:
    folder = Path(os.environ.get("GRAPHVISION_VIEWER_SHOTS", tmp_path))
    page.locator(selector).screenshot(path=str(folder / f"{name}.png"))


CENTRE = """() => {
  const c = document.querySelector('.gv-view[data-view="coins.labels"] canvas.gv-canvas');
  return Array.from(c.getContext('2d').getImageData(c.width >> 1, c.height >> 1, 1, 1).data);
}"""


def test_a_label_map_is_tinted_over_its_image_toggled_and_faded(browser, tmp_path):
    page = _open(browser, coins_page(), tmp_path)
    box = '.gv-view[data-view="coins.labels"]'
    assert page.get_attribute(box, "data-drawn") == "labels"
    assert page.locator(f"{box} > .gv-fallback").is_hidden()  # the viewer replaced it
    gray = round(255 * GRAY)
    # the tint is drawn at the next frame: wait for it, with a deadline
    page.wait_for_function(f"() => ({CENTRE})()[0] !== {gray} || ({CENTRE})()[1] !== {gray}",
                           timeout=DEADLINE)  # fmt: skip
    half = np.array(page.evaluate(CENTRE)[:3])
    fade = "s => { s.value = 1; s.dispatchEvent(new Event('input')); }"
    page.eval_on_selector(f"{box} input[data-alpha]", fade)
    whole = np.array(page.evaluate(CENTRE)[:3])  # the label's own colour
    assert not np.all(whole == gray)
    assert np.abs(half - (whole + gray) / 2).max() <= 2  # alpha 0.5: half label, half image
    page.uncheck(f"{box} input[data-layer]")
    assert page.evaluate(CENTRE)[:3] == [gray, gray, gray]  # the image alone
    _shot(page, box, "report-labels", tmp_path)
    assert page.errors == []


def test_curves_and_a_confusion_matrix_with_samples_are_drawn(browser, tmp_path):
    page = _open(browser, cnn_page(), tmp_path)
    _, table, _ = classifier_values()
    curves = page.eval_on_selector_all(
        '.gv-view[data-view="cnn.out"] svg.gv-curve',
        """svgs => svgs.map(s => ({name: s.dataset.curve,
            axes: [...s.querySelectorAll('.gv-axis-x, .gv-axis-y')].map(t => t.textContent),
            series: [...s.querySelectorAll('polyline')].map(p => [p.dataset.series,
                      p.getAttribute('points').trim().split(' ').length]),
            legend: [...s.querySelectorAll('.gv-legend')].map(t => t.textContent)}))""",
    )
    assert curves == [
        {"name": "loss", "axes": ["epoch", "loss"], "series": [["loss", 4]], "legend": []},
        {"name": "accuracy", "axes": ["epoch", "accuracy"],
         "series": [["training", 4], ["held out", 4]], "legend": ["training", "held out"]},
    ]  # fmt: skip
    assert page.locator('.gv-view[data-view="cnn.out"] > .gv-fallback').is_visible()  # kept
    box = '.gv-view[data-view="predicted.out"]'
    cells = page.eval_on_selector_all(
        f"{box} table.gv-confusion tr",
        "rows => rows.slice(1).map(r => [...r.querySelectorAll('td')].map(d => +d.textContent))",
    )
    counts = np.zeros((3, 3), int)
    np.add.at(counts, (table["label"], table["predicted"]), 1)
    assert cells == counts.tolist()
    assert page.locator(f"{box} > .gv-fallback").is_hidden()
    captions = {
        side: page.eval_on_selector_all(
            f"{box} .gv-samples[data-samples={side}] figcaption", "f => f.map(c => c.textContent)"
        )
        for side in ("right", "wrong")
    }
    right = np.flatnonzero(table["label"] == table["predicted"])[:8]
    wrong = np.flatnonzero(table["label"] != table["predicted"])[:8]
    assert captions == {
        side: [f"{table['label'][i]} → {table['predicted'][i]}" for i in rows]
        for side, rows in (("right", right), ("wrong", wrong))
    }
    _shot(page, ".outputs >> nth=0", "report-classifier", tmp_path)
    assert page.errors == []


REDS = """() => {
  const c = document.querySelector('.gv-view[data-view="cloud.points"] canvas.gv-cloud');
  const p = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
  let red = 0, other = 0;
  for (let i = 0; i < p.length; i += 4) {
    if (p[i] === 255 && p[i + 1] === 0 && p[i + 2] === 0) red++;
    else if (p[i] + p[i + 1] + p[i + 2] > 3 * 0x11 + 6) other++;
  }
  return [red, other];
}"""


def test_a_cloud_is_drawn_in_3d_by_its_colours_or_by_depth(browser, tmp_path):
    page = _open(browser, stereo_page(), tmp_path)
    box = '.gv-view[data-view="cloud.points"]'
    assert page.get_attribute(box, "data-drawn") == "points3d"
    assert page.locator(f"{box} > .gv-fallback").is_hidden()
    red, other = page.evaluate(REDS)
    assert red > 1000 and other == 0  # every point red, as its colours say
    page.select_option(f"{box} select[data-cloud-colour]", "depth")
    red, other = page.evaluate(REDS)
    assert red == 0 and other > 1000  # viridis over the depth: no pure red
    _shot(page, box, "report-cloud", tmp_path)
    assert page.errors == []


def test_matches_are_drawn_over_their_pair_inliers_and_outliers_apart(browser, tmp_path):
    page = _open(browser, homography_page(), tmp_path)
    box = '.gv-view[data-view="matches.out"]'
    assert page.get_attribute(box, "data-drawn") == "matches"
    assert page.locator(f"{box} > .gv-fallback").is_hidden()  # the page's own SVG pair
    # 3 matches: (0, 2) and (2, 0) the fit's inliers, (1, 1) the outlier
    assert page.get_attribute(f"{box} .gv-pair", "data-matches") == '{"inliers":2,"outliers":1}'
    toggles = page.eval_on_selector_all(
        f"{box} input[data-overlay]", "b => b.map(i => i.dataset.overlay)"
    )
    assert toggles == ["inliers (2)", "outliers (1)"]
    assert page.errors == []


MAX_VALUES = 2_000  # the 30×40 disparity is sent whole, the 60×80 depth reduced (every 2nd)
VIRIDIS_LOW, VIRIDIS_HIGH = [0x44, 0x01, 0x54], [0xFD, 0xE7, 0x25]  # matplotlib's ends


@pytest.fixture(scope="module")
def report(tmp_path_factory) -> Path:
    with mock.patch.object(scripted, "MAX_VALUES", MAX_VALUES):
        html = stereo_maps_page()
    path = tmp_path_factory.mktemp("maps") / "report.html"
    path.write_text(html, encoding="utf-8")
    return path


@pytest.fixture(scope="module")
def maps_page(browser, report):
    page = browser.new_page(viewport={"width": 1000, "height": 900})
    page.errors = []
    page.on("pageerror", lambda error: page.errors.append(str(error)))
    page.goto(report.as_uri())
    page.wait_for_selector("html[data-values-shown='1']", state="attached", timeout=DEADLINE)
    yield page
    page.close()


def _canvas(output: str) -> str:
    return f'.gv-view[data-view="{output}.out"] canvas.gv-canvas'


def _fitted(page, output: str) -> dict:
    """The box of ``output``'s viewer canvas (in the viewport) and its size in pixels;
    the viewer fits the map into it, centred (as a double click fits it)."""
    canvas = page.locator(_canvas(output))
    canvas.scroll_into_view_if_needed()
    page.wait_for_function(
        f"() => document.querySelector('{_canvas(output)}').width > 0", timeout=DEADLINE
    )
    return canvas.evaluate(
        """c => { const r = c.getBoundingClientRect();
                  return {left: r.left, top: r.top, w: c.width, h: c.height}; }"""
    )


def _hover(page, output: str, x: int, y: int, shape: tuple[int, int]) -> str:
    """Move the mouse over pixel (x, y) of a map of ``shape`` drawn by ``output``'s viewer;
    the viewer's status line then."""
    box = _fitted(page, output)
    height, width = shape
    scale = min(box["w"] / width, box["h"] / height)
    tx, ty = (box["w"] - width * scale) / 2, (box["h"] - height * scale) / 2
    page.mouse.move(box["left"] + tx + (x + 0.5) * scale, box["top"] + ty + (y + 0.5) * scale)
    status = page.locator(f'.gv-view[data-view="{output}.out"] .gv-status').first
    return status.text_content()


def _pixel(page, output: str, x: int, y: int, shape: tuple[int, int]) -> list[int]:
    """The canvas's colour at the centre of map pixel (x, y)."""
    box = _fitted(page, output)
    height, width = shape
    scale = min(box["w"] / width, box["h"] / height)
    cx = round((box["w"] - width * scale) / 2 + (x + 0.5) * scale)
    cy = round((box["h"] - height * scale) / 2 + (y + 0.5) * scale)
    return page.eval_on_selector(
        _canvas(output),
        f"c => Array.from(c.getContext('2d').getImageData({cx}, {cy}, 1, 1).data).slice(0, 3)",
    )


STATUS = re.compile(r"x (\d+), y (\d+) · value (.+)")


def test_the_value_under_the_cursor_is_the_disparity_maps_own(maps_page):
    page = maps_page
    disparity = stereo_maps()["disparity"]
    assert page.get_attribute('.gv-view[data-view="disparity.out"]', "data-drawn") == "floatmap"
    for x, y in ((5, 3), (39, 29), (17, 22), (0, 0)):
        found = STATUS.fullmatch(_hover(page, "disparity", x, y, disparity.shape))
        assert found, f"no value under the cursor at {x}, {y}"
        assert (int(found[1]), int(found[2])) == (x, y)
        shown = float(found[3])  # quarter pixels: 4 digits print them exactly; NaN as NaN
        assert shown == disparity[y, x] or (np.isnan(shown) and np.isnan(disparity[y, x]))
    assert page.errors == []


def test_a_map_sent_reduced_names_the_full_maps_pixel_and_says_so(maps_page):
    page = maps_page
    depth = stereo_maps()["depth"]  # 60×80 = 4800 pixels, over 2000: every 2nd pixel sent
    note = page.locator('.gv-view[data-view="depth.out"] [data-reduced]')
    assert note.get_attribute("data-reduced") == "2"
    assert "every 2nd pixel" in note.text_content() and "40×30 of 80×60" in note.text_content()
    found = STATUS.fullmatch(_hover(page, "depth", 7, 11, (30, 40)))
    assert found and (int(found[1]), int(found[2])) == (14, 22)
    assert float(found[3]) == depth[22, 14]
    assert page.errors == []


def test_an_rgb_image_shows_its_three_values(maps_page):
    page = maps_page
    maps = stereo_maps()
    # drawn by nodes `picture` and `view`: float32, and 8-bit levels
    for node, output in (("picture", "disparity_picture"), ("view", "cloud_picture")):
        image = maps[output]
        assert page.get_attribute(f'.gv-view[data-view="{node}.out"]', "data-drawn") == "image"
        found = STATUS.fullmatch(_hover(page, node, 9, 4, image.shape[:2]))
        assert found, output
        shown = [float(v) for v in found[3].strip("()").split(", ")]
        np.testing.assert_allclose(shown, image[4, 9], rtol=5e-4)  # printed to 4 digits
        assert _pixel(page, node, 9, 4, image.shape[:2]) == np.round(255 * image[4, 9]).tolist()
    assert page.errors == []


def test_the_range_box_recolours_the_map(maps_page, tmp_path):
    page = maps_page
    disparity = stereo_maps()["disparity"]
    x, y = 5, 3
    value = float(disparity[y, x])
    view = '.gv-view[data-view="disparity.out"]'
    automatic = _pixel(page, "disparity", x, y, disparity.shape)

    def fix(low: float, high: float) -> list[int]:
        for nth, number in ((0, low), (1, high)):
            page.locator(f"{view} input.gv-range").nth(nth).fill(str(number))
            page.locator(f"{view} input.gv-range").nth(nth).dispatch_event("change")
        return _pixel(page, "disparity", x, y, disparity.shape)

    assert fix(value + 1, value + 2) == VIRIDIS_LOW  # under the range: its low end
    assert fix(value - 2, value - 1) == VIRIDIS_HIGH  # over it: its high end
    middle = fix(value - 1, value + 1)
    assert middle not in (VIRIDIS_LOW, VIRIDIS_HIGH)
    assert fix(value + 1, value - 1) == middle  # the ends typed the wrong way round
    page.locator(f"{view} .gv-rangebox button").click()
    assert _pixel(page, "disparity", x, y, disparity.shape) == automatic
    assert automatic not in (VIRIDIS_LOW, VIRIDIS_HIGH)  # 1.25 … 63.75: inside the range
    folder = Path(os.environ.get("GRAPHVISION_VIEWER_SHOTS", tmp_path))
    page.locator(view).screenshot(path=str(folder / "report-floatmap.png"))
    assert page.errors == []


def test_zooming_in_stops_at_a_pixel_a_sixth_of_the_canvas_wide(maps_page):
    page = maps_page
    box = _fitted(page, "disparity")
    status = page.locator('.gv-view[data-view="disparity.out"] .gv-status').first
    centre_x, centre_y = box["left"] + box["w"] / 2, box["top"] + box["h"] / 2
    page.mouse.move(centre_x, centre_y)
    for _ in range(80):  # unbounded, this made one pixel wider than the whole canvas
        page.mouse.wheel(0, -400)
    page.mouse.move(centre_x, centre_y)
    here = STATUS.fullmatch(status.text_content())
    page.mouse.move(centre_x + box["w"] / 5, centre_y)
    right = STATUS.fullmatch(status.text_content())
    assert here and right and int(right[1]) > int(here[1])
    page.mouse.dblclick(centre_x, centre_y)  # fitted again for the other tests
    assert page.errors == []


def test_without_script_the_page_keeps_its_pngs(browser, report):
    context = browser.new_context(java_script_enabled=False)
    page = context.new_page()
    page.goto(report.as_uri())
    for output in ("disparity", "depth", "picture"):  # picture: disparity_picture
        fallback = page.locator(f'.gv-view[data-view="{output}.out"] > .gv-fallback img')
        assert fallback.is_visible()
        assert fallback.get_attribute("src").startswith("data:image/png;base64,")
    assert page.locator("canvas").count() == 0
    context.close()
