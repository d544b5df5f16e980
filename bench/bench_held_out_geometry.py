"""Issue 24 (items 2, 3, 6, 8): structured light, the generalised Hough transform,
multi-scale template matching and Hough lines on held-out scenes, beside the ground truth
and OpenCV / scikit-image on the same inputs, in one run.

The scenes are those of the tests (``tests/plugins/test_held_out_structured_light.py``,
``tests/plugins/test_held_out_hough_template.py``), with more seeds:

* Structured light: the projector on the camera's left turned 8°, a slanted plane and a
  cylinder, 4×4 area integration per pixel; 768 columns / 8 bits (3 a stripe) and
  912 / 7 (7.125 a stripe). Mean and RMS depth error against the rendered depth, the
  quantisation's predicted RMS ``2 h w / √12`` (``h`` the depth of half a projector pixel,
  ``w`` the stripe width in pixels), and ``h``.
* Generalised Hough: the score of a copy of the model at three vote spreads; copies
  shifted along the ridges of their votes; 24 scenes of arrows on photographed textures
  (8 seeds × gravel, brick, grass) among polygons: the scores of the whole arrow (turned
  10°), of the arrow with 37 % of its outline hidden, and of the best false instance
  (searched down to 0.05), against the truth (1 and 0.63 of the outline visible).
* Multi-scale template matching: a 33×41 template of a sinusoid texture and the texture
  magnified by each of the 13 scales the search tries (0.6–1.8), 311×427: error of the
  location found against the truth; ``cv2.matchTemplate`` (TM_CCOEFF_NORMED) on
  ``cv2.resize`` d images at the same 13 scales (INTER_AREA when shrinking, INTER_LINEAR
  when enlarging), its peak refined by the same quadratic and mapped back with the same
  actual factors.
* Hough lines: 27 turned rectangles of random contrast, 6 seeds: true sides found (within
  2° and 2 px of the side's middle) and false lines with the defaults, beside
  ``skimage.transform.hough_line`` + ``hough_line_peaks`` (defaults: threshold 0.5 × the
  accumulator's maximum, min_distance 9, min_angle 10) on the same Canny edges.

Run: ``python bench/bench_held_out_geometry.py``.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import skimage.transform
from timing import best

sys.path.insert(0, str(Path(__file__).parent.parent))

from graphvision_plugins import edges, hough, pyramids
from graphvision_plugins.hough import quadratic_peak_2d
from tests.plugins.hough import test_held_out_hough_template as scenes
from tests.plugins.stereo import test_held_out_structured_light as light


def _cv2():
    try:
        import cv2
    except ImportError:
        return None
    return cv2


def structured_light_rows() -> list[str]:
    rows = [
        "| structured light, held out | mean error mm | RMSE mm | quantisation RMS mm "
        "| half a projector pixel mm | decoded % |",
        "| --- | ---: | ---: | ---: | ---: | ---: |",
    ]
    for bits, columns in ((8, 768), (7, 912)):
        scene = light.held_out_scene(bits=bits, projector_width=columns)
        errors, half = light.depth_errors(scene)
        stripe = columns / 2**bits
        rows.append(
            f"| {columns} columns, {bits} bits | {1e3 * errors.mean():+.2f} "
            f"| {1e3 * math.sqrt(np.mean(errors**2)):.2f} "
            f"| {1e3 * 2 * half * stripe / math.sqrt(12):.2f} | {1e3 * half:.2f} "
            f"| {100 * errors.size / scene.depth.size:.1f} |"
        )
    return rows


def ght_rows() -> list[str]:
    rows = [
        "| generalised Hough | scores (truth) | instances (truth) |",
        "| --- | --- | ---: |",
    ]
    model, model_edges = scenes.shape_model(scenes.ARROW, blur=0.6)
    copy = np.full((110, 150), 0.25, np.float32)
    copy[30 : 30 + model.shape[0], 55 : 55 + model.shape[1]] = model
    copy_edges = edges.canny(copy, sigma=1.0).edges
    for spread in (0.0, 1.0, 2.5):
        found = hough.generalized_hough(copy_edges, copy, model_edges, model, vote_sigma=spread)
        rows.append(
            f"| copy of the model, vote_sigma {spread:g} | "
            f"{', '.join(f'{s:.2f}' for s in found.scores)} (1) | {found.count} (1) |"
        )
    for name, polygon, spread in (
        ("stairs", scenes.STAIRS, 1.0),
        ("stairs", scenes.STAIRS, 2.0),
        ("arrow", scenes.ARROW, 2.0),
    ):
        shape_model, shape_edges = scenes.shape_model(polygon)
        image = np.full((160, 200), 0.25)
        scenes.fill(image, polygon + np.array([83.3, 61.7]), 0.75)
        image = image.astype(np.float32)
        found = hough.generalized_hough(
            edges.canny(image, sigma=1.0).edges, image, shape_edges, shape_model, vote_sigma=spread
        )
        rows.append(
            f"| sharp {name}, shifted copies on its vote ridges, vote_sigma {spread:g} | "
            f"{', '.join(f'{s:.2f}' for s in found.scores)} (1) | {found.count} (1) |"
        )
    whole, hidden, false, counts = [], [], [], []
    turns = [-20.0, -10.0, 0.0, 10.0, 20.0]
    for ground in scenes.GROUNDS:
        for seed in range(8):
            scene = scenes.arrow_scene(seed, ground)
            found = hough.generalized_hough(
                edges.canny(scene.image, sigma=1.0).edges,
                scene.image,
                model_edges,
                model,
                rotations=turns,
                threshold=0.05,
                max_instances=50,
            )
            gaps = np.linalg.norm(found.locations[:, None] - scene.references[None], axis=2)
            true = gaps.min(axis=1) < 1.5
            false.append(found.scores[~true].max(initial=0.0))
            for k in np.nonzero(true)[0]:
                (whole if gaps[k].argmin() == 0 else hidden).append(found.scores[k])
            counts.append(int((found.scores >= 0.4).sum()))
    rows += [
        f"| 24 arrow scenes: whole arrow, min–mean | {min(whole):.2f}–{np.mean(whole):.2f} (1) "
        f"| {len(whole)} found (24) |",
        f"| 24 arrow scenes: 37 % hidden, min–max | {min(hidden):.2f}–{max(hidden):.2f} "
        f"(0.63) | {len(hidden)} found (24) |",
        f"| 24 arrow scenes: best false instance, max | {max(false):.2f} (0) | – |",
        f"| 24 arrow scenes: instances at the default threshold 0.4 | – | {sum(counts)} (48) |",
    ]
    return rows


def _cv2_multiscale(cv2, image: np.ndarray, template: np.ndarray, grid: np.ndarray):
    """cv2.matchTemplate over the same scales; the best peak refined by a quadratic and
    mapped back with the factors of the sizes made."""
    height, width = image.shape
    h, w = template.shape
    best_score, best_at = -np.inf, (0.0, 0.0)
    for s in grid:
        size = (round(width / s), round(height / s))
        mode = cv2.INTER_AREA if s > 1 else cv2.INTER_LINEAR
        resized = cv2.resize(image, size, interpolation=mode)
        response = cv2.matchTemplate(resized, template, cv2.TM_CCOEFF_NORMED).astype(np.float64)
        row, col = np.unravel_index(int(np.argmax(response)), response.shape)
        if response[row, col] <= best_score:
            continue
        dy, dx = 0.0, 0.0
        if 0 < row < response.shape[0] - 1 and 0 < col < response.shape[1] - 1:
            dy, dx = quadratic_peak_2d(response, np.array([row]), np.array([col]))[0]
        factor_x, factor_y = width / size[0], height / size[1]
        best_score = response[row, col]
        best_at = (
            (col + dx + (w - 1) / 2 + 0.5) * factor_x - 0.5,
            (row + dy + (h - 1) / 2 + 0.5) * factor_y - 0.5,
        )
    return np.array(best_at)


def template_rows(cv2) -> list[str]:
    grid = np.geomspace(0.6, 1.8, 13)
    ours, theirs, times_ours, times_cv = [], [], [], []
    for scale in grid:
        scene = scenes.scaled_scene(float(scale))

        def run(scene=scene):
            return pyramids.match_multiscale(scene.image, scene.template, **scenes.MULTISCALE_GRID)

        ours.append(float(np.linalg.norm(run().location[0] - scene.centre)))
        if scale in (grid[2], grid[9]):
            times_ours.append(best(run, repeats=2))
        if cv2 is not None:

            def run_cv(scene=scene):
                return _cv2_multiscale(cv2, scene.image, scene.template, grid)

            theirs.append(float(np.linalg.norm(run_cv() - scene.centre)))
            if scale in (grid[2], grid[9]):
                times_cv.append(best(run_cv, repeats=2))
    rows = [
        "| multi-scale template, 13 scales | location error mean px | max px | ms (2 scenes) |",
        "| --- | ---: | ---: | ---: |",
        f"| graphvision match_multiscale | {np.mean(ours):.3f} | {max(ours):.3f} "
        f"| {1e3 * np.mean(times_ours):.0f} |",
    ]
    if cv2 is not None:
        rows.append(
            f"| cv2.resize + cv2.matchTemplate, same scales | {np.mean(theirs):.3f} "
            f"| {max(theirs):.3f} | {1e3 * np.mean(times_cv):.0f} |"
        )
    return rows


def lines_rows() -> list[str]:
    rows = [
        "| Hough lines, 27 rectangles | seed | true sides | found / false | ms |",
        "| --- | ---: | ---: | ---: | ---: |",
    ]
    totals = {"ours": [0, 0, 0], "skimage": [0, 0, 0]}
    for seed in range(3, 9):
        image, truth = scenes.rectangles_scene(seed)
        found = edges.canny(image, sigma=1.0, low=0.02, high=0.04).edges
        ours = hough.hough_lines(found, image)
        t_ours = best(lambda found=found, image=image: hough.hough_lines(found, image), 2)

        def run_sk(found=found):
            h, theta, dist = skimage.transform.hough_line(found)
            return skimage.transform.hough_line_peaks(h, theta, dist)

        _, theta, dist = run_sk()
        flip = theta < 0  # skimage: θ in [-π/2, π/2); bring to [0, π) with ρ negated
        sk_lines = np.column_stack(
            [np.where(flip, -dist, dist), np.where(flip, theta + math.pi, theta)]
        )
        t_sk = best(run_sk, 2)
        for name, lines, t in (("ours", ours.lines, t_ours), ("skimage", sk_lines, t_sk)):
            hits, false = scenes.matched_lines(lines, truth)
            label = "graphvision hough.lines" if name == "ours" else "skimage hough_line + peaks"
            rows.append(f"| {label} | {seed} | {len(truth)} | {hits} / {false} | {1e3 * t:.0f} |")
            totals[name][0] += len(truth)
            totals[name][1] += hits
            totals[name][2] += false
    for name, (n, hits, false) in totals.items():
        label = "graphvision, all seeds" if name == "ours" else "skimage, all seeds"
        rows.append(f"| {label} | – | {n} | {hits} ({100 * hits / n:.1f} %) / {false} | – |")
    return rows


def main() -> list[str]:
    cv2 = _cv2()
    rows = [
        *structured_light_rows(),
        "",
        *ght_rows(),
        "",
        *template_rows(cv2),
        "",
        *lines_rows(),
    ]
    if cv2 is None:
        rows.append("\nOpenCV is not installed (pip install -e '.[bench]'): its rows are missing.")
    return rows


if __name__ == "__main__":
    print("\n".join(main()))
