"""report.html draws values with others of the run: matches over their image pair (inliers
and outliers apart, each toggled), a cloud by image colour or depth, epipolar lines; and
what goes with what is read from the graph (views/pairing.py)."""

from __future__ import annotations

import base64
import io
import re
from pathlib import Path

import imageio.v3 as iio
import numpy as np
import pytest

import graphvision as gv
from graphvision.compiler.compile import compile_graph
from graphvision.values.geometry import Points3DPort
from graphvision.values.records import KeypointSet, MatchesPort, MatchSet
from graphvision.views import pairing
from graphvision.views.linked import GAP, linked_html, shown_html

PIPELINES = Path(__file__).parents[2] / "pipelines"


def _compiled(name: str):
    graph = gv.load_pipeline(PIPELINES / name)
    return compile_graph(graph, gv.discover(graph.plugins))


def _keypoints(xy: list[list[float]]) -> KeypointSet:
    n = len(xy)
    return KeypointSet(np.array(xy, np.float64), np.ones(n), np.zeros(n), np.ones(n),
                       np.tile(np.eye(2), (n, 1, 1)))  # fmt: skip


def test_matches_are_paired_with_their_keypoints_images_and_inliers():
    compiled = _compiled("homography.yaml")
    expected = {
        "all": ["matches", "out"],
        "inliers": ["fit", "inliers"],
        "a": {"keypoints": ["f0", "keypoints"], "image": ["gray", "out"]},
        "b": {"keypoints": ["f1", "keypoints"], "image": ["warp", "image"]},
    }  # fmt: skip  (homography.yaml: f0 on gray, f1 on warp.image, fit reads matches)
    assert pairing.match_pair(compiled, "matches", "out") == expected
    assert pairing.match_pair(compiled, "fit", "inliers") == expected
    points = _compiled("fundamental.yaml")
    assert pairing.epipolar_pair(points, "fit") == {
        "a": {"points": ["fit", "inliers_a"], "image": ["gray_l", "out"]},
        "b": {"points": ["fit", "inliers_b"], "image": ["gray_r", "out"]},
    }
    assert pairing.cloud_colours(_compiled("stereo.yaml"), "cloud") == ("cloud", "colours")
    assert pairing.prediction_samples(_compiled("cnn_digits.yaml"), "predicted") == (
        "split",
        "test",
    )


def _lines(page: str, layer: int) -> list[tuple[float, ...]]:
    group = re.search(rf'<g class="layer{layer}"[^>]*>(.*?)</g>', page).group(1)
    return [tuple(map(float, m)) for m in re.findall(
        r'<line x1="([\d.-]+)" y1="([\d.-]+)" x2="([\d.-]+)" y2="([\d.-]+)"/>', group)]  # fmt: skip


def test_the_report_draws_matches_over_the_pair_inliers_and_outliers_apart():
    compiled = _compiled("homography.yaml")
    a = _keypoints([[1, 2], [3, 4], [5, 6]])
    b = _keypoints([[10, 20], [30, 40], [50, 60]])
    whole = MatchSet(np.array([[0, 2], [1, 1], [2, 0]], np.int64), np.zeros(3))
    inliers = whole.take(np.array([0, 2]))
    image_a, image_b = np.zeros((70, 40), np.float32), np.ones((80, 60), np.float32)
    found = {("f0", "keypoints"): a, ("f1", "keypoints"): b, ("gray", "out"): image_a,
             ("warp", "image"): image_b, ("fit", "inliers"): inliers}  # fmt: skip
    page = linked_html(compiled, found, ("matches", "out"), MatchesPort, whole, "matches")
    assert "inliers (2)" in page and "outliers (1)" in page
    offset = 40 + GAP  # image b starts right of image a
    assert _lines(page, 0) == [(1, 2, 50 + offset, 60), (5, 6, 10 + offset, 20)]
    assert _lines(page, 1) == [(3, 4, 30 + offset, 40)]
    assert f'viewBox="0 0 {40 + GAP + 60} 80"' in page
    assert page.count('type="checkbox"') == 2 and ":not(:checked) ~ svg .layer1" in page
    del found[("warp", "image")]  # an image the report does not hold: no pair drawn
    assert linked_html(compiled, found, ("matches", "out"), MatchesPort, whole, "m") == ""


def test_epipolar_lines_in_the_report_pass_through_the_matching_point():
    compiled = _compiled("fundamental.yaml")
    F = np.array([[0, 0, 0], [0, 0, -1], [0, 1, 0]], np.float64)  # x' = x + t: rows match
    points_a = np.array([[10.0, 5.0], [20.0, 30.0]])
    points_b = np.array([[4.0, 12.0]])
    found = {
        ("fit", "inliers_a"): points_a,
        ("fit", "inliers_b"): points_b,
        ("gray_l", "out"): np.zeros((40, 50)),
        ("gray_r", "out"): np.zeros((40, 60)),
    }
    page = linked_html(compiled, found, ("fit", "F"), compiled.steps["fit"].outputs["F"], F, "F")
    offset = 50 + GAP
    assert _lines(page, 0) == [(offset, 5, offset + 60, 5), (offset, 30, offset + 60, 30)]
    assert _lines(page, 1) == [(0, 12, 50, 12)]
    assert "points (3)" in page


def _pictures(page: str) -> list[np.ndarray]:
    found = re.findall(r'src="data:image/png;base64,([^"]+)"', page)
    return [iio.imread(io.BytesIO(base64.b64decode(data))) for data in found]


def test_the_report_colours_a_cloud_by_its_image_or_by_depth_with_a_switch():
    compiled = _compiled("stereo.yaml")
    grid = np.stack(np.meshgrid(np.arange(20.0), np.arange(20.0)), -1).reshape(-1, 2)
    cloud = np.column_stack([grid, np.full(len(grid), 3.0)])
    colours = np.zeros((len(grid), 3), np.float32)
    colours[:, 0] = 1.0  # every point red
    found = {("cloud", "points"): cloud, ("cloud", "colours"): colours}
    page = shown_html(compiled, found, ("cloud", "points"), Points3DPort, cloud, "cloud")
    by_image, by_depth = _pictures(page)

    def drawn(picture: np.ndarray) -> set[tuple[int, ...]]:  # the colours but the white ground
        return {tuple(p) for p in picture[..., :3].reshape(-1, 3).tolist()} - {(255, 255, 255)}

    assert drawn(by_image) == {(255, 0, 0)}
    assert (255, 0, 0) not in drawn(by_depth) and len(drawn(by_depth)) == 1  # one depth: one hue
    assert 'type="radio"' in page and "image colour" in page and "colour bar" in page
    alone = shown_html(compiled, {}, ("cloud", "points"), Points3DPort, cloud, "cloud")
    assert len(_pictures(alone)) == 1 and 'type="radio"' not in alone  # no colours held


@pytest.mark.parametrize("key", ["matches", "fit.inliers"])
def test_report_values_are_found_by_node_and_port(key):
    compiled = _compiled("homography.yaml")
    value = object()
    found = pairing.outputs_by_ref(compiled, {"inliers": 1}, {key: (MatchesPort, value)})
    node, _, port = key.partition(".")
    assert found[(node, port or "out")] is value
    assert found[("fit", "inliers")] in (1, value)


def test_the_report_inlines_the_layout_and_the_graphs_data():
    from graphvision.views.graph_view import graph_data, graph_html, layout_script

    compiled = _compiled("coins.yaml")
    data = graph_data(compiled, {"binary": "computed", "gray": "cached"}, {"binary": 0.25})
    assert data["nodes"][0] == {"id": "image", "kind": "input", "type": "Image"}
    binary = next(n for n in data["nodes"] if n["id"] == "binary")
    assert binary == {"id": "binary", "kind": "node", "op": "threshold.local",
                      "status": "computed", "seconds": 0.25}  # fmt: skip
    assert {"from": "gray", "from_port": "out", "to": "binary", "port": "image"} in data["edges"]
    page = graph_html('<svg width="10" height="10"></svg>', {"nodes": [{"id": "</script>"}]})
    assert "<\\/script>" in page and "</script></div>" in page  # the data cannot end its script
    script = layout_script()
    assert script.startswith("<script>") and "GraphvisionGraph.layOutPage()" in script
    assert "src=" not in script[:200] and "http" not in script.split("layOutPage")[-1]
