"""Every pipeline in pipelines/ runs as it is, on its default inputs."""

from __future__ import annotations

import json

import numpy as np
import pytest

import graphvision as gv

from .conftest import PIPELINES

RECOMPUTE_AT_MOST = 5.0
"""Seconds: a node slower than this cold is not recomputed by the mixed run."""


def encoded(result: gv.RunResult) -> dict[str, tuple[dict[str, tuple[str, tuple, bytes]], str]]:
    """Each output as its port type's arrays (dtype, shape, bytes) and header: the bits."""
    bits = {}
    for name, value in result.outputs.items():
        arrays, meta = result.compiled.output_type(name).encode(value)
        bits[name] = (
            {
                k: (a.dtype.str, a.shape, np.ascontiguousarray(a).tobytes())
                for k, a in arrays.items()
            },
            json.dumps(meta, sort_keys=True, default=str),
        )
    return bits


@pytest.mark.heavy
@pytest.mark.parametrize("path", sorted(PIPELINES.glob("*.yaml")), ids=lambda p: p.name)
def test_pipeline_runs_on_defaults_and_gives_the_same_bits_warm(path, tmp_path):
    """Cold, then warm with every other node's entries removed (so nodes compute on values
    read back from the disk cache), then fully warm: every output equal bit for bit.

    A node that took over ``RECOMPUTE_AT_MOST`` seconds cold (a network's training) keeps
    its entries: its readers still compute on its value read back, and training twice
    to the same bits is each trainer's own test (``make test`` stays under ten minutes)."""
    graph = gv.load_pipeline(path)
    cold = gv.run(graph, cache=gv.Cache(None, gv.DiskStore(tmp_path)))
    assert set(cold.outputs) == set(cold.compiled.outputs)
    store = gv.DiskStore(tmp_path)
    for node in cold.record.nodes[1::2]:
        if node.seconds > RECOMPUTE_AT_MOST:
            continue
        for key in node.keys.values():
            store.path(key).unlink(missing_ok=True)
    mixed = gv.run(graph, cache=gv.Cache(None, store))
    assert {n.status for n in mixed.record.nodes} >= {"cached"}
    warm = gv.run(graph, cache=gv.Cache(None, gv.DiskStore(tmp_path)))
    assert encoded(mixed) == encoded(cold)
    assert encoded(warm) == encoded(cold)


def test_denoise_shows_what_each_filter_is_for():
    out = gv.run(gv.load_pipeline(PIPELINES / "denoise.yaml")).outputs
    # median beats Gaussian on salt and pepper; both improve on the noisy images
    assert out["psnr_median_on_salt_pepper"] > out["psnr_gaussian_on_salt_pepper"] + 3
    assert out["psnr_median_on_salt_pepper"] > out["psnr_noisy_salt_pepper"] + 10
    assert out["psnr_gaussian_on_gaussian"] > out["psnr_noisy_gaussian"] + 3


def test_coins_counts_24_coins_in_four_rows_of_six():
    out = gv.run(gv.load_pipeline(PIPELINES / "coins.yaml")).outputs
    assert out["count"] == 24  # the photograph shows 24 coins
    rows = np.sort(out["regions"]["centroid_y"])
    gaps = np.diff(rows)
    assert (gaps > 30).sum() == 3  # 4 rows, separated by more than 30 pixels
    assert all(len(group) == 6 for group in np.split(rows, np.flatnonzero(gaps > 30) + 1))
    assert out["overlay"].shape == (303, 384, 3)


def test_document_local_threshold_survives_where_otsu_fails():
    out = gv.run(gv.load_pipeline(PIPELINES / "document.yaml")).outputs
    dim_corner = (slice(120, 191), slice(0, 60))  # lower left: the light falls off there
    text_block = (slice(40, 110), slice(200, 384))
    # printed text covers well under half of any part of a page
    assert out["ink_otsu"][dim_corner].mean() > 0.5
    assert out["ink_local"][dim_corner].mean() < 0.35
    assert 0.05 < out["ink_local"][text_block].mean() < 0.35
    assert out["disagreement"][dim_corner].mean() > 0.3


def test_homography_pipeline_recovers_the_true_warp():
    out = gv.run(gv.load_pipeline(PIPELINES / "homography.yaml")).outputs
    assert out["corner_error"] < 3.0  # the success criterion of the benchmark protocol
    assert len(out["inliers"]) > 200 and out["inlier_ratio"] > 0.8
    assert out["matches_drawn"].shape == (512, 1024, 3)


def test_panorama_pipeline_stitches_the_two_views():
    out = gv.run(gv.load_pipeline(PIPELINES / "panorama.yaml")).outputs
    assert out["corner_error"] < 3.0
    assert out["panorama"].shape[1] > out["left"].shape[1] + 100


def test_line_fit_pipeline_shows_ransac_beating_least_squares():
    out = gv.run(gv.load_pipeline(PIPELINES / "line_fit.yaml")).outputs
    assert out["error_ransac"] < 0.5 < 2.0 < out["error_lstsq"]
    assert out["ransac_inliers"].sum() == pytest.approx(120, abs=10)  # 60% of 200 are inliers


def test_homography_of_identical_images_is_the_identity():
    graph = gv.load_pipeline(PIPELINES / "homography.yaml")
    result = gv.run(
        graph,
        overrides={
            "warp.max_rotation": 0,
            "warp.min_scale": 1.0,
            "warp.max_scale": 1.0,
            "warp.perspective": 0,
        },
        outputs=["homography", "corner_error"],
    )
    np.testing.assert_allclose(result.outputs["homography"], np.eye(3), atol=1e-3)
    assert result.outputs["corner_error"] < 0.1


def test_a_featureless_image_fails_in_the_named_node():
    flat = np.full((128, 128, 3), 0.5, np.float32)
    with pytest.raises(gv.RunError) as info:
        gv.run(
            gv.load_pipeline(PIPELINES / "homography.yaml"),
            inputs={"image": flat},
            outputs=["homography"],
        )
    assert list(info.value.failures) == ["fit"]
    assert (
        "node 'fit' (op geometry.homography_ransac) failed: ValueError: need at least 4 "
        "matches to estimate a homography, got 0"
    ) in str(info.value)
