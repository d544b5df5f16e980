"""report.html holds what the studio's viewers draw: a label map with the image it is
tinted over, a classifier's confusion matrix with its right and wrong samples, a network's
training curves (views/scripted.py)."""

from __future__ import annotations

import base64
import io
import re

import imageio.v3 as iio
import numpy as np

from graphvision.execution.record import RunRecord
from graphvision.values.images import FloatImagePort, ImagePort
from graphvision.views import scripted
from graphvision.views.graph_view import layout_script
from graphvision.views.html import html_report
from graphvision.views.scripted import PageValues
from graphvision.views.viewers import picture_html

from .report_values import (
    GRAY,
    classifier_values,
    cloud_points,
    cnn_page,
    coins_page,
    compiled,
    decoded,
    homography_page,
    labels_map,
    page_data,
    stereo_maps,
    stereo_maps_page,
    stereo_page,
)


def test_a_label_map_is_kept_with_the_image_it_is_tinted_over():
    page = coins_page()
    data = page_data(page)
    described = data["values"]["coins.labels"]
    assert described["view"] == "labels" and described["over"] == ["gray", "out"]
    assert described["shape"] == [24, 32]
    np.testing.assert_array_equal(decoded(data["raw"]["coins.labels"]), labels_map())
    png = data["pictures"]["gray.out"].split(",", 1)[1]
    picture = iio.imread(io.BytesIO(base64.b64decode(png)))
    assert picture.shape[:2] == (24, 32) and np.all(picture == round(255 * GRAY))
    assert '<div class="gv-view" data-view="coins.labels">' in page
    assert "GraphvisionGraph.showValues()" in layout_script()  # the page draws them


def test_a_label_map_without_its_image_is_drawn_alone_its_picture_kept_underneath():
    page = coins_page(with_image=False)
    described = page_data(page)["values"]["coins.labels"]
    assert described["view"] == "labels" and "over" not in described and described["step"] == 1
    np.testing.assert_array_equal(decoded(page_data(page)["raw"]["coins.labels"]), labels_map())
    assert "each its own colour" in page  # the labels' picture, without script


def test_float_maps_and_images_ride_the_page_with_their_values_reduced_over_the_cap(
    monkeypatch,
):
    monkeypatch.setattr(scripted, "MAX_VALUES", 2_000)
    maps = stereo_maps()
    data = page_data(stereo_maps_page())
    values, raw = data["values"], data["raw"]
    assert values["disparity.out"]["view"] == "floatmap" and values["disparity.out"]["step"] == 1
    assert values["disparity.out"]["units"] == "disparity, pixels"
    np.testing.assert_array_equal(decoded(raw["disparity.out"]), maps["disparity"])  # NaN too
    # quarter pixels travel exactly as uint16 codes (value × 4), NaN its own code
    assert raw["disparity.out"]["dtype"] == "uint16" and raw["disparity.out"]["scale"] == 4
    # 60×80 = 4800 pixels over 2000: every 2nd pixel on each axis, 30×40 = 1200
    assert values["depth.out"]["step"] == 2 and values["depth.out"]["full"] == [60, 80]
    np.testing.assert_array_equal(decoded(raw["depth.out"]), maps["depth"][::2, ::2])
    assert values["picture.out"]["view"] == "image" and raw["picture.out"]["scale"] == 16
    assert raw["picture.out"]["dtype"] == "uint8"  # eighths × 16: codes of at most 16
    np.testing.assert_array_equal(decoded(raw["picture.out"]), maps["disparity_picture"])
    # an image of 8-bit levels travels as its bytes and decodes to the same float32 values
    assert raw["view.out"]["dtype"] == "uint8" and raw["view.out"]["scale"] == 255
    np.testing.assert_array_equal(decoded(raw["view.out"]), maps["cloud_picture"])


def test_a_map_is_reduced_to_at_most_the_cap_and_no_further():
    page = PageValues(compiled("stereo.yaml"), {})
    for shape in ((512, 512), (500, 741), (1, 300_000), (513, 512), (295, 295, 3), (296, 296, 3)):
        kind = ImagePort if len(shape) == 3 else FloatImagePort
        found = page._map({"node": "n", "port": "out"}, kind, np.zeros(shape, np.float32))
        assert found is not None
        rows, cols, channels = (*shape, 1)[:3]
        assert np.prod(found["shape"]) <= scripted.MAX_VALUES, shape
        step = found["step"]
        assert step == (1 if shape in ((512, 512), (295, 295, 3)) else 2), shape
        if step > 1:  # one pixel fewer skipped would be over the cap
            assert -(-rows // (step - 1)) * -(-cols // (step - 1)) * channels > scripted.MAX_VALUES


def test_a_classifiers_matrix_and_first_right_and_wrong_samples_are_in_the_page():
    data = page_data(cnn_page())
    _, table, samples = classifier_values()
    described = data["values"]["predicted.out"]
    counts = np.zeros((3, 3), int)
    np.add.at(counts, (table["label"], table["predicted"]), 1)
    assert described["confusion"] == {"classes": [0, 1, 2], "counts": counts.tolist()}
    right = np.flatnonzero(table["label"] == table["predicted"])[:8]
    wrong = np.flatnonzero(table["label"] != table["predicted"])[:8]
    shown = np.concatenate([right, wrong])
    # rows renumbered into the samples the page holds: only those 16 are kept
    assert [row[0] for row in described["right"] + described["wrong"]] == list(range(16))
    assert [row[1:] for row in described["wrong"]] == [
        [int(table["label"][i]), int(table["predicted"][i])] for i in wrong
    ]
    assert described["samples"] == ["split", "test"]
    kept = data["values"]["split.test"]
    assert kept["side"] == [4, 4]
    np.testing.assert_allclose(kept["pixels"], samples.images[shown].ravel(), atol=5e-4)


def test_a_networks_curves_are_in_the_page_with_training_and_held_out_accuracy():
    data = page_data(cnn_page())
    network, _, _ = classifier_values()
    assert data["values"]["cnn.out"]["curves"] == {
        "loss": network.history.tolist(),
        "accuracy": {"training": network.accuracy.tolist(),
                     "held out": network.held_out_accuracy.tolist()},
    }  # fmt: skip
    assert data["values"]["cnn.out"]["keep"]  # the filters' picture stays beside them


def test_a_cloud_is_kept_for_the_3d_view_with_its_colours_evenly_taken():
    data = page_data(stereo_page())
    described = data["values"]["cloud.points"]
    assert described["view"] == "points3d" and described["colours"] == ["cloud", "colours"]
    assert described["count"] == 21_000
    # 21 000 points, at most 20 000 shown: every second one
    points = decoded(data["raw"]["cloud.points"])
    np.testing.assert_array_equal(points, cloud_points()[::2].astype("<f4"))
    colours = data["raw"]["cloud.colours"]
    assert colours["shape"] == [10_500, 3]


def test_matches_are_kept_with_their_pair_keypoints_and_full_size_images():
    data = page_data(homography_page())
    described = data["values"]["matches.out"]
    assert described["view"] == "matches" and described["columns"] == {"a": [0, 1, 2],
                                                                        "b": [2, 1, 0]}  # fmt: skip
    assert described["pair"]["inliers"] == ["fit", "inliers"]
    assert data["values"]["fit.inliers"]["columns"] == {"a": [0, 2], "b": [2, 0]}
    assert data["values"]["f1.keypoints"]["columns"] == {"x": [10, 30, 50], "y": [20, 40, 60]}
    sizes = {}
    for key, url in data["pictures"].items():
        sizes[key] = iio.imread(io.BytesIO(base64.b64decode(url.split(",", 1)[1]))).shape[:2]
    assert sizes == {"gray.out": (70, 40), "warp.image": (80, 60)}  # keypoints' pixels


def test_a_map_whose_values_take_too_many_bytes_is_sent_reduced_under_the_cap(monkeypatch):
    monkeypatch.setattr(scripted, "MAX_MAP_BYTES", 4_000)
    noise = np.random.default_rng(3).uniform(0, 100, (64, 64)).astype(np.float32)
    page = PageValues(compiled("stereo.yaml"), {})
    found = page._map({"node": "depth", "port": "out"}, FloatImagePort, noise)
    assert found is not None and found["step"] > 1  # 4096 values: under MAX_VALUES
    raw = page.raw["depth.out"]
    assert len(raw["deflate"]) <= 4_000
    sent = noise[:: found["step"], :: found["step"]]
    low, high = float(sent.min()), float(sent.max())  # 16-bit codes over the range
    np.testing.assert_allclose(decoded(raw), sent, rtol=0, atol=(high - low) / 131070 * 1.01)
    assert found["shape"] == list(decoded(raw).shape) and found["full"] == [64, 64]


def test_continuous_values_travel_as_16_bit_codes_within_half_a_step_of_their_own():
    rng = np.random.default_rng(5)
    values = rng.uniform(-3.0, 61.0, (40, 50)).astype(np.float32)  # no 1/256 multiples
    values[3, 4], values[7, 9] = np.nan, -3.5  # NaN rides as its own code; the low end
    raw = scripted._raw(values, compact=True)
    assert raw["dtype"] == "uint16" and raw["offset"] == -3.5 and raw["nan"] == 65535
    step = (61.0 + 3.5) / 65534  # the finite range in 65,534 steps (65,535 is NaN)
    back = decoded(raw)
    assert np.isnan(back[3, 4]) and np.isnan(back).sum() == 1
    np.testing.assert_allclose(back, values, rtol=0, atol=step / 2 * 1.01)
    assert np.abs(back - values)[np.isfinite(values)].max() > step / 10  # not exact: coded
    assert len(raw["deflate"]) < len(scripted._raw(values)["deflate"]) * 0.6  # float32 planes
    # an infinity cannot be coded: float32, exact
    values[0, 0] = np.inf
    assert scripted._raw(values, compact=True)["dtype"] == "float32"


def _fallback_pictures(page: str, key: str) -> list[np.ndarray]:
    """The pictures of the page's own drawing of value ``key`` (seen without script)."""
    box = re.search(rf'<div class="gv-view" data-view="{key}">(.*?)</div></div>', page, re.S)
    assert box, key
    found = re.findall(r'src="data:image/png;base64,([^"]+)"', box.group(1))
    return [iio.imread(io.BytesIO(base64.b64decode(png))) for png in found]


def test_a_value_the_script_draws_keeps_a_small_picture_for_the_page_without_script():
    rng = np.random.default_rng(3)
    disparity = (rng.integers(16, 240, (300, 450)) / 4).astype(np.float32)  # quarter pixels
    picture = (rng.integers(0, 9, (200, 300, 3)) / 8).astype(np.float32)  # eighths
    page = html_report(
        compiled("stereo.yaml"),
        {"disparity": disparity, "disparity_picture": picture},
        RunRecord("stereo", "threads"),
    )
    data = page_data(page)
    for key, values in (("disparity.out", disparity), ("picture.out", picture)):
        # the viewer's values: every pixel, exactly (what the script draws and reads out)
        assert data["values"][key]["step"] == 1
        np.testing.assert_array_equal(decoded(data["raw"][key]), values)
        pictures = _fallback_pictures(page, key)
        assert pictures and all(max(p.shape[:2]) <= 200 for p in pictures)  # FALLBACK_LONGEST
    # a drawing no viewer of the script replaces keeps its size (512 at most, as before)
    alone = PageValues(compiled("stereo.yaml"), {})
    shown = alone.wrap(None, ImagePort, picture, lambda: picture_html(picture, "p"))
    png = re.search(r'base64,([^"]+)"', shown).group(1)
    assert iio.imread(io.BytesIO(base64.b64decode(png))).shape[:2] == (200, 300)
