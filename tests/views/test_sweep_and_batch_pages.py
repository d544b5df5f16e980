"""sweep.html: a chart with axis labels and a legend, each row linking the page of its run;
batch.html: names its pipeline and shows each file's metrics."""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET
from pathlib import Path

import imageio.v3 as iio
import numpy as np
import pytest

import graphvision as gv
from graphvision.execution.sweep import sweep
from graphvision.views.sweep_page import nice_ticks, sweep_html, sweep_plot_svg, write_sweep

PIPELINES = Path(__file__).parents[2] / "pipelines"
SVG = "{http://www.w3.org/2000/svg}"
GRID = {"robust.threshold": [1.0, 3.0, 9.0], "robust.confidence": [0.9, 0.99]}


@pytest.fixture(scope="module")
def line_sweep() -> gv.SweepResult:
    return sweep(gv.load_pipeline(PIPELINES / "line_fit.yaml"), GRID, executor="sync")


def test_each_chart_labels_its_axes_and_names_its_lines(line_sweep):
    root = ET.fromstring(sweep_plot_svg(line_sweep, "error_ransac"))
    charts = root.findall(f"{SVG}g")
    for chart, key, other in zip(charts, GRID, reversed(list(GRID)), strict=True):
        labels = {t.get("class"): t.text for t in chart.iter(f"{SVG}text") if t.get("class")}
        assert labels == {"x-label": key, "y-label": "error_ransac"}
        legend = [g.find(f"{SVG}text").text for g in chart.findall(f"{SVG}g[@class='legend']")]
        assert legend == [f"{other}={value}" for value in GRID[other]]
        colours = [g.find(f"{SVG}line").get("stroke") for g in chart.findall(f"{SVG}g")]
        assert colours == [p.get("stroke") for p in chart.findall(f"{SVG}polyline")]


def test_a_count_is_labelled_with_whole_numbers_only():
    counts = gv.SweepResult(
        keys=["smooth.sigma"],
        outputs=["count"],
        rows=[{"smooth.sigma": s, "count": c} for s, c in ((1.0, 20), (2.0, 21), (3.0, 22))],
    )
    root = ET.fromstring(sweep_plot_svg(counts, "count"))
    labels = [t.text for t in root.iter(f"{SVG}text") if t.get("text-anchor") == "end"]
    assert labels == ["20", "21", "22"]


@pytest.mark.parametrize("seed", range(20))
def test_ticks_are_round_steps_inside_the_range(seed):
    rng = np.random.default_rng(seed)
    low = float(rng.uniform(-1e3, 1e3)) * 10.0 ** int(rng.integers(-6, 4))
    high = low + float(rng.uniform(1e-3, 1e3)) * 10.0 ** int(rng.integers(-6, 4))
    ticks = nice_ticks(low, high)
    assert 3 <= len(ticks) <= 11
    assert low - 1e-9 * abs(high - low) <= ticks[0] and ticks[-1] <= high + 1e-9 * abs(high - low)
    step = ticks[1] - ticks[0]
    mantissa = step / 10.0 ** np.floor(np.log10(step))
    assert min(abs(mantissa - m) for m in (1, 2, 5, 10)) < 1e-6
    assert np.allclose(np.diff(ticks), step, rtol=1e-6)


def test_each_row_links_the_page_of_its_run(line_sweep, tmp_path):
    write_sweep(line_sweep, tmp_path, "line_fit", ["error_ransac"])
    page = (tmp_path / "sweep.html").read_text()
    links = re.findall(r'<td><a href="\./(sweep_run_\d+\.html)">(\d+)</a></td>', page)
    assert [int(n) for _, n in links] == list(range(1, 7))
    for (name, number), row in zip(links, line_sweep.rows, strict=True):
        run = (tmp_path / name).read_text()
        assert f"run {number} of 6" in run
        assert f"<th>robust.threshold</th><td>{row['robust.threshold']:.6g}</td>" in run
        assert f"<th>error_ransac</th><td>{row['error_ransac']:.6g}</td>" in run
    write_sweep(line_sweep, tmp_path, "line_fit", [])  # the next sweep there replaces them
    assert len(list(tmp_path.glob("sweep_run_*.html"))) == 6


def test_the_batch_page_names_its_pipeline_and_shows_each_files_metrics(tmp_path):
    folder = tmp_path / "in"
    folder.mkdir()
    rng = np.random.default_rng(0)
    for index in range(2):
        iio.imwrite(folder / f"img{index}.png", (rng.random((16, 16)) * 255).astype(np.uint8))
    graph = gv.load_pipeline(PIPELINES / "denoise.yaml")
    batch = gv.run_batch(graph, str(folder / "*.png"), input="image", output_dir=tmp_path / "out")
    text = (tmp_path / "out" / "batch.html").read_text()
    assert text.count("<h1>denoise: 2 of 2 files succeeded</h1>") == 1
    assert f"pipeline <code>{PIPELINES / 'denoise.yaml'}</code>" in text
    for item, card in zip(batch.items, text.split('class="card ')[1:], strict=True):
        shown = dict(re.findall(r"<tr><th>([^<]+)</th><td>([^<]+)</td></tr>", card))
        assert shown == {name: f"{value:.4g}" for name, value in item.scalars.items()}
        assert len(shown) >= 5  # the PSNRs


@pytest.mark.parametrize(("count", "heading"), [(1, "1 combination<"), (2, "2 combinations<")])
def test_the_heading_counts_its_combinations_in_words(count, heading):
    result = gv.SweepResult(
        keys=["smooth.sigma"],
        outputs=["count"],
        rows=[{"smooth.sigma": float(s), "count": 20} for s in range(count)],
    )
    assert f"<h1>p: {heading}/h1>" in sweep_html(result, "p")
