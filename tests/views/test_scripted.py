"""report.html holds what the studio's viewers draw: a label map with the image it is
tinted over, a classifier's confusion matrix with its right and wrong samples, a network's
training curves (views/scripted.py)."""

from __future__ import annotations

import base64
import io
import zlib

import imageio.v3 as iio
import numpy as np

from graphvision.views.graph_view import layout_script

from .report_values import (
    GRAY,
    classifier_values,
    cloud_points,
    cnn_page,
    coins_page,
    homography_page,
    labels_map,
    page_data,
    stereo_page,
)


def test_a_label_map_is_kept_with_the_image_it_is_tinted_over():
    page = coins_page()
    data = page_data(page)
    described = data["values"]["coins.labels"]
    assert described["view"] == "labels" and described["over"] == ["gray", "out"]
    assert described["shape"] == [24, 32]
    raw = data["raw"]["coins.labels"]
    values = np.frombuffer(zlib.decompress(base64.b64decode(raw["deflate"])), raw["dtype"])
    np.testing.assert_array_equal(values.reshape(raw["shape"]), labels_map())
    png = data["pictures"]["gray.out"].split(",", 1)[1]
    picture = iio.imread(io.BytesIO(base64.b64decode(png)))
    assert picture.shape[:2] == (24, 32) and np.all(picture == round(255 * GRAY))
    assert '<div class="gv-view" data-view="coins.labels">' in page
    assert "GraphvisionGraph.showValues()" in layout_script()  # the page draws them


def test_a_label_map_without_its_image_is_the_pages_own_picture():
    page = coins_page(with_image=False)
    assert 'data-view="coins.labels"' not in page and 'data-values="1"' not in page
    assert "each its own colour" in page  # the labels' picture, as before


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
    raw = data["raw"]["cloud.points"]
    points = np.frombuffer(zlib.decompress(base64.b64decode(raw["deflate"])), raw["dtype"])
    # 21 000 points, at most 20 000 shown: every second one
    np.testing.assert_array_equal(points.reshape(raw["shape"]), cloud_points()[::2].astype("<f4"))
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
