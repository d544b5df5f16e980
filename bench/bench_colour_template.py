"""Colour spaces, template matching, FFT convolution and pyramids beside scikit-image,
scipy and OpenCV, in one run.

* RGB → HSV / L*a*b* / YCbCr on the astronaut (512², float32): max difference to
  ``skimage.color`` (float64 reference) and time; ``cv2.cvtColor`` on the same float32
  image (its Lab and YCrCb use other ranges, so only times are compared there).
* NCC of a 40×60 patch over camera (512²): max difference to
  ``skimage.feature.match_template`` (float64) and to ``cv2.matchTemplate(TM_CCOEFF_NORMED)``.
* Convolution with a 31×31 kernel (wrap): ``frequency.fft_convolve`` vs
  ``scipy.signal.fftconvolve`` of the wrap-padded image and ``filters.convolve``.
* A 4-level Gaussian pyramid of camera vs ``skimage.transform.pyramid_gaussian`` and
  ``cv2.pyrDown``.

Ratios are the other library's time over graphvision's (above 1: graphvision is faster).
Run: ``python bench/bench_colour_template.py``.
"""

from __future__ import annotations

import numpy as np
import scipy.signal
import skimage.color
import skimage.data
import skimage.feature
import skimage.transform
from timing import best

from graphvision_plugins import colour, filters, frequency, pyramids


def _cv2():
    try:
        import cv2
    except ImportError:
        return None
    return cv2


def colour_rows(cv2) -> list[str]:
    rgb = (skimage.data.astronaut() / 255).astype(np.float32)
    reference = {"hsv": skimage.color.rgb2hsv, "lab": skimage.color.rgb2lab}
    reference["ycbcr"] = skimage.color.rgb2ycbcr
    codes = {"hsv": "COLOR_RGB2HSV", "lab": "COLOR_RGB2Lab", "ycbcr": "COLOR_RGB2YCrCb"}
    rows = [
        "| RGB → | max diff to skimage | ms | skimage ms (ratio) | cv2.cvtColor ms (ratio) |",
        "| --- | ---: | ---: | ---: | ---: |",
    ]
    for space in colour.SPACES:
        ours = colour.from_rgb(rgb, space=space)
        diff = np.abs(ours - reference[space](rgb.astype(np.float64))).max()
        t_ours = best(lambda space=space: colour.from_rgb(rgb, space=space))
        t_sk = best(lambda space=space: reference[space](rgb))
        cell = "n/a"
        if cv2 is not None:
            code = getattr(cv2, codes[space])
            t_cv = best(lambda code=code: cv2.cvtColor(rgb, code))
            cell = f"{t_cv * 1e3:.2f} ({t_cv / t_ours:.2f})"
        rows.append(
            f"| {space} | {diff:.1e} | {t_ours * 1e3:.2f} | {t_sk * 1e3:.2f} "
            f"({t_sk / t_ours:.2f}) | {cell} |"
        )
    return rows


def template_rows(cv2) -> list[str]:
    camera = (skimage.data.camera() / 255).astype(np.float32)
    patch = camera[200:240, 250:310].copy()
    ours = pyramids.match_template(camera, patch)
    reference = skimage.feature.match_template(camera.astype(np.float64), patch.astype(np.float64))
    t_ours = best(lambda: pyramids.match_template(camera, patch))
    t_sk = best(lambda: skimage.feature.match_template(camera, patch))
    rows = [
        "| NCC 40×60 over 512² | max diff to skimage (float64) | ms | ratio |",
        "| --- | ---: | ---: | ---: |",
        f"| graphvision | {np.abs(ours - reference).max():.1e} | {t_ours * 1e3:.1f} | 1 |",
        f"| skimage match_template (float32) | "
        f"{np.abs(skimage.feature.match_template(camera, patch) - reference).max():.1e} "
        f"| {t_sk * 1e3:.1f} | {t_sk / t_ours:.2f} |",
    ]
    if cv2 is not None:
        found = cv2.matchTemplate(camera, patch, cv2.TM_CCOEFF_NORMED)
        t_cv = best(lambda: cv2.matchTemplate(camera, patch, cv2.TM_CCOEFF_NORMED))
        rows.append(
            f"| cv2.matchTemplate TM_CCOEFF_NORMED | {np.abs(found - reference).max():.1e} "
            f"| {t_cv * 1e3:.1f} | {t_cv / t_ours:.2f} |"
        )
    return rows


def convolution_rows() -> list[str]:
    camera = (skimage.data.camera() / 255).astype(np.float32)
    kernel = np.random.default_rng(0).normal(size=(31, 31))
    ours = frequency.fft_convolve(camera, kernel, boundary="wrap")
    spatial = filters.convolve(camera, kernel, boundary="wrap")
    padded = np.pad(camera.astype(np.float64), 15, mode="wrap")
    t_ours = best(lambda: frequency.fft_convolve(camera, kernel, boundary="wrap"))
    t_scipy = best(lambda: scipy.signal.fftconvolve(padded, kernel, mode="valid"))
    t_spatial = best(lambda: filters.convolve(camera, kernel, boundary="wrap"), repeats=2)
    return [
        "| 31×31 convolution, wrap, 512² | max diff to spatial | ms | ratio |",
        "| --- | ---: | ---: | ---: |",
        f"| frequency.fft_convolve | {np.abs(ours - spatial).max():.1e} | {t_ours * 1e3:.1f} | 1 |",
        f"| scipy.signal.fftconvolve (padded) | – | {t_scipy * 1e3:.1f} | {t_scipy / t_ours:.2f} |",
        f"| filters.convolve (spatial) | 0 | {t_spatial * 1e3:.1f} | {t_spatial / t_ours:.2f} |",
    ]


def pyramid_rows(cv2) -> list[str]:
    camera = (skimage.data.camera() / 255).astype(np.float32)
    t_ours = best(lambda: pyramids.gaussian_pyramid(camera, levels=4))
    t_sk = best(lambda: list(skimage.transform.pyramid_gaussian(camera, max_layer=3, sigma=1.0)))
    rows = [
        "| Gaussian pyramid, 4 levels of 512² | ms | ratio |",
        "| --- | ---: | ---: |",
        f"| graphvision | {t_ours * 1e3:.2f} | 1 |",
        f"| skimage pyramid_gaussian | {t_sk * 1e3:.2f} | {t_sk / t_ours:.2f} |",
    ]
    if cv2 is not None:

        def run_cv():
            level = camera
            for _ in range(3):
                level = cv2.pyrDown(level)
            return level

        t_cv = best(run_cv)
        rows.append(f"| cv2.pyrDown ×3 | {t_cv * 1e3:.2f} | {t_cv / t_ours:.2f} |")
    return rows


def main() -> list[str]:
    cv2 = _cv2()
    return [
        *colour_rows(cv2),
        "",
        *template_rows(cv2),
        "",
        *convolution_rows(),
        "",
        *pyramid_rows(cv2),
    ]


if __name__ == "__main__":
    print("\n".join(main()))
