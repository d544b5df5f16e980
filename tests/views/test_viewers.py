"""The report's viewers: float maps with a colour bar giving range and units, label maps in
distinct colours, point clouds coloured by depth, a classifier's confusion matrix, links to
every output file, and pages that name what they show."""

from __future__ import annotations

import base64
import io
import re
from pathlib import Path

import imageio.v3 as iio
import numpy as np
import pytest

import graphvision as gv
from graphvision.values.geometry import Points3DPort
from graphvision.values.images import FloatImagePort, LabelImagePort
from graphvision.values.scalars import TablePort
from graphvision.views.viewers import pictures_at_most, value_html
from graphvision_plugins.stereo._ports import DisparityPort

PIPELINES = Path(__file__).parents[2] / "pipelines"
VIOLET, YELLOW = (0x44, 0x01, 0x54), (0xFD, 0xE7, 0x25)  # viridis's ends


def _pictures(page: str) -> list[np.ndarray]:
    found = re.findall(r'src="data:image/png;base64,([^"]+)"', page)
    return [iio.imread(io.BytesIO(base64.b64decode(data))) for data in found]


def test_a_disparity_map_gets_a_colour_bar_with_its_range_and_units():
    disparity = np.tile(np.linspace(10.0, 60.0, 101, dtype=np.float32), (20, 1))
    disparity[0, 0] = np.nan
    shown = value_html(DisparityPort, disparity, "disparity")
    (picture,) = _pictures(shown)
    low, high = np.percentile(disparity[np.isfinite(disparity)], [1, 99])
    assert f">{low:.4g}</text>" in shown and f">{high:.4g}</text>" in shown
    assert "<figcaption>disparity, pixels</figcaption>" in shown
    assert "1 invalid pixels (NaN) drawn black" in shown
    factor = picture.shape[0] // 20  # enlarged to at least 64 pixels
    assert tuple(picture[factor, 0]) == VIOLET and tuple(picture[0, -1]) == YELLOW
    assert tuple(picture[0, 0]) == (0, 0, 0)  # the NaN


def test_a_capped_float_map_picture_is_coloured_from_a_sample_of_the_right_size():
    """Within a cap of 50 pixels, a 400×300 map is coloured from every 8th pixel
    (50×38, drawn doubled as small pictures are), not block-averaged from all of it (50×37);
    its ends keep their colours, and the range printed is still the whole map's."""
    disparity = np.tile(np.linspace(10.0, 60.0, 300, dtype=np.float32), (400, 1))
    disparity[:, -8:] = np.nan  # the last sampled column (296) falls in the NaN band
    with pictures_at_most(50):
        shown = value_html(DisparityPort, disparity, "disparity")
    (picture,) = _pictures(shown)
    assert picture.shape[:2] == (2 * 50, 2 * 38)
    assert tuple(picture[0, 0]) == VIOLET and tuple(picture[0, -1]) == (0, 0, 0)
    assert "3200 invalid pixels (NaN) drawn black" in shown


def test_a_filter_response_says_it_has_no_unit_and_an_image_has_no_bar():
    response = np.linspace(-1, 1, 64 * 64, dtype=np.float32).reshape(64, 64)
    assert "no unit (a filter response)" in value_html(FloatImagePort, response, "r")
    assert "colourbar" not in value_html(gv.GrayImagePort, (response + 1) / 2, "image")


def test_label_maps_are_counted_and_coloured_apart():
    labels = np.zeros((64, 64), np.int32)
    labels[:, 16:32], labels[:, 32:48], labels[:, 48:] = 1, 2, 3
    shown = value_html(LabelImagePort, labels, "labels")
    (picture,) = _pictures(shown)
    assert "3 labels, each its own colour; background (0) black" in shown
    colours = {tuple(picture[0, column]) for column in (0, 20, 40, 60)}
    assert len(colours) == 4 and (0, 0, 0) in colours


def test_a_point_cloud_is_drawn_coloured_by_depth_not_black():
    xy = np.random.default_rng(0).uniform(0, 1, (4000, 2))
    depth = np.where(xy[:, 0] < 0.5, 1.0, 10.0)  # the left half near, the right far
    shown = value_html(Points3DPort, np.column_stack([xy, depth]), "cloud")
    (picture,) = _pictures(shown)
    drawn = (picture[..., :3] != 255).any(axis=-1)
    half = picture.shape[1] // 2
    left, right = (
        picture[:, : half - 8][drawn[:, : half - 8]],
        picture[:, half + 8 :][drawn[:, half + 8 :]],
    )
    assert len(left) > 1000 and len(right) > 1000
    assert {tuple(c) for c in left} == {VIOLET} and {tuple(c) for c in right} == {YELLOW}
    assert "depth Z" in shown and "colourbar" in shown


def test_a_classifiers_results_show_as_a_confusion_matrix():
    table = {
        "label": np.array([0, 0, 1, 1, 1, 2]),
        "predicted": np.array([0, 1, 1, 1, 0, 2]),
    }
    shown = value_html(TablePort, table, "results")
    matrix = shown.split('<table class="confusion">')[1].split("</table>")[0]
    cells = [int(c) for c in re.findall(r'<td class="(?:right|wrong)"[^>]*>(\d+)</td>', matrix)]
    assert cells == [1, 1, 0, 1, 2, 0, 0, 0, 1]  # rows true 0, 1, 2; columns predicted
    assert "4 of 6 right (66.7%)" in matrix


@pytest.fixture(scope="module")
def line_fit_folder(tmp_path_factory) -> Path:
    from graphvision.cli import main

    folder = tmp_path_factory.mktemp("line_fit")
    command = ["run", str(PIPELINES / "line_fit.yaml"), "-d", str(folder), "--no-cache"]
    assert main(command) == 0
    return folder


def test_the_report_links_every_output_file(line_fit_folder):
    import json
    from urllib.parse import unquote

    page = (line_fit_folder / "report.html").read_text()
    files = json.loads((line_fit_folder / "record.json").read_text())["files"]
    links = {unquote(h[2:]) for h in re.findall(r'href="(\./[^"]+)"', page)}
    expected = {name for names in files.values() for name in names}
    assert expected | {"record.json", "report.md"} <= links
    assert all((line_fit_folder / link).is_file() for link in links)


def test_the_graph_scales_to_the_page_with_zoom_buttons(line_fit_folder):
    page = (line_fit_folder / "report.html").read_text()
    svg = re.search(r"<svg [^>]*>", page.split('<div class="graph">')[1]).group(0)
    assert "viewBox=" in svg and "width=" not in svg and "height=" not in svg
    drawn = re.search(r'viewBox="0 0 ([\d.]+) ', svg).group(1)
    assert f'style="max-width: {drawn}px"' in svg  # shrinks to fit, never enlarged
    assert re.findall(r'<button type="button">([^<]+)</button>', page) == ["+", "\u2212", "fit"]


def test_shrunk_pictures_are_the_block_averages_of_thumbnail():
    from graphvision.values.pictures import thumbnail
    from graphvision.views.viewers import shrunk

    rng = np.random.default_rng(11)
    for shape, longest in (((303, 384, 3), 200), ((61, 47), 20), ((1, 4000), 500),
                           ((7, 9), 200), ((50, 3, 2), 10)):  # fmt: skip
        picture = rng.random(shape).astype(np.float32)
        mine, theirs = shrunk(picture, longest), thumbnail(picture, longest)
        assert mine.dtype == theirs.dtype and mine.shape == theirs.shape, shape
        np.testing.assert_allclose(mine, theirs, rtol=0, atol=2e-7)  # a float32 rounding
        # the exactly rounded average of each block (float64 sums)
        step = int(np.ceil(max(shape[:2]) / longest))
        if step > 1:
            across = [min(step, side) for side in shape[:2]]
            block = picture[: across[0], : across[1]].astype(np.float64).mean(axis=(0, 1))
            np.testing.assert_array_equal(mine[0, 0], block.astype(np.float32))
