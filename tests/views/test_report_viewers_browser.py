"""report.html's values drawn by the studio's viewers in Chromium (Debian's, through
Playwright; nothing downloads): a label map tinted over its image (toggle, alpha slider),
a network's training curves with labelled axes and a legend, a classifier's confusion
matrix with its right and wrong samples, a point cloud in 3-D by image colour or depth,
matches over their image pair (inliers and outliers apart, toggled).
Checked from the canvas's pixels and the DOM; each wait has a deadline
(GRAPHVISION_VIEWER_SHOTS=DIR keeps screenshots)."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from .report_values import (
    GRAY,
    classifier_values,
    cnn_page,
    coins_page,
    homography_page,
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
