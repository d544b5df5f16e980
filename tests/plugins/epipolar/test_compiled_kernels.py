"""The compiled F RANSAC, 8-point null vector and DLT triangulation against the NumPy
computations they replace (the generic ``fitting.ransac`` with ``eight_point`` and
``sampson_distance``; ``np.linalg.svd``)."""

from __future__ import annotations

import numpy as np
import pytest

from graphvision_plugins import synthetic
from graphvision_plugins.epipolar import _geometry
from graphvision_plugins.epipolar._kernels import null_vector_8x9
from graphvision_plugins.fitting import ransac


def outlier_scene(seed: int, share: float = 0.3):
    scene = synthetic.two_view_scene(count=300, noise=0.5, seed=seed)
    a, b = scene.a.copy(), scene.b.copy()
    rng = np.random.default_rng(seed)
    wrong = rng.random(len(b)) < share
    b[wrong] = rng.uniform(0, 640, (wrong.sum(), 2))
    return a, b


@pytest.mark.parametrize(("seed", "threshold"), [(0, 1.0), (1, 2.0), (2, 0.5)])
def test_compiled_f_ransac_finds_the_generic_loops_inliers(seed, threshold):
    a, b = outlier_scene(seed)
    generic = ransac(
        len(a),
        8,
        lambda s: _geometry.eight_point(a[s], b[s]),
        lambda F: _geometry.sampson_distance(F, a, b),
        threshold,
        refit=lambda i: _geometry.eight_point(a[i], b[i]),
        confidence=0.999,
        max_iterations=500,
        seed=seed,
    )
    compiled = _geometry.ransac_eight_point(a, b, threshold, 0.999, 500, seed)
    assert compiled.iterations == generic.iterations
    np.testing.assert_array_equal(compiled.inliers, generic.inliers)
    np.testing.assert_allclose(compiled.model, generic.model, rtol=1e-9, atol=1e-12)


def test_the_null_vector_and_degeneracy_test_are_the_svds():
    rng = np.random.default_rng(0)
    for trial in range(400):
        design = rng.normal(size=(8, 9))
        if trial % 2:  # rows nearly dependent: σ8/σ1 from 1e-4 to 1e-14, across the 1e-9 test
            design[7] = 2 * design[6] - design[5] + 10.0 ** -rng.uniform(4, 14) * design[7]
        null, degenerate = null_vector_8x9(design)
        _, singular, vt = np.linalg.svd(design)
        assert degenerate == (singular[7] < 1e-9 * singular[0])
        if not degenerate:
            assert abs(abs(null @ vt[8]) - 1.0) < 1e-6


def test_compiled_triangulation_is_the_svd_dlt():
    scene = synthetic.two_view_scene(count=500, noise=0.5, seed=3)
    Pa, Pb, a, b = scene.camera_a.P, scene.camera_b.P, scene.a, scene.b
    rows = np.stack(
        [
            a[:, :1] * Pa[2] - Pa[0],
            a[:, 1:] * Pa[2] - Pa[1],
            b[:, :1] * Pb[2] - Pb[0],
            b[:, 1:] * Pb[2] - Pb[1],
        ],
        axis=1,
    )
    rows /= np.linalg.norm(rows, axis=2, keepdims=True)
    null = np.linalg.svd(rows)[2][:, -1]
    expected = null[:, :3] / null[:, 3:]
    np.testing.assert_allclose(_geometry.triangulate_linear(Pa, Pb, a, b), expected, rtol=1e-11)
