"""Every pipeline in pipelines/ runs as it is, on its default inputs."""

from __future__ import annotations

import pytest

import graphvision as gv

from .conftest import PIPELINES


@pytest.mark.parametrize("path", sorted(PIPELINES.glob("*.yaml")), ids=lambda p: p.name)
def test_pipeline_runs_on_defaults(path):
    result = gv.run(gv.load_pipeline(path))
    assert set(result.outputs) == set(result.compiled.outputs)


def test_denoise_shows_what_each_filter_is_for():
    out = gv.run(gv.load_pipeline(PIPELINES / "denoise.yaml")).outputs
    # median beats Gaussian on salt and pepper; both improve on the noisy images
    assert out["psnr_median_on_salt_pepper"] > out["psnr_gaussian_on_salt_pepper"] + 3
    assert out["psnr_median_on_salt_pepper"] > out["psnr_noisy_salt_pepper"] + 10
    assert out["psnr_gaussian_on_gaussian"] > out["psnr_noisy_gaussian"] + 3
