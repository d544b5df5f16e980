"""Faces in photographs, side by side on the same held-out scenes and the same cascade file.

* Scenes: ``synthetic.face_scenes(photos=..., seed=100)``: the astronaut (her face box is
  the mean of OpenCV's four Haar frontal-face cascades' boxes), her mirror image, and the
  cat, coffee, rocket, motorcycle and retina photographs, eight times each, with 1–3 of
  the 25 held-out lfw faces pasted at seeded boxes, 40–120 px: 42 gray scenes of 512².
  ``min_neighbours`` of graphvision's detector was chosen on seeds 0–7, not on these.
  The lfw-trained cascade saw none of these photographs (its negatives and hard
  negatives come from brick, clock, coins, grass, gravel, hubble_deep_field,
  immunohistochemistry, moon, page and text).
* Detectors on every scene, the same gray pixels (channel mean; OpenCV gets them as
  uint8):
  - graphvision ``recognition.lbp_detect`` on ``recognition.lbp_cascade()`` (scikit-image's
    copy of OpenCV's ``lbpcascade_frontalface.xml``), as face_detect.yaml runs it (step 1,
    8 neighbours), and as OpenCV scans and is called below (step 0: every second reduced
    pixel up to scale 2, every one above; 3 neighbours);
  - ``skimage.feature.Cascade(skimage.data.lbp_frontal_face_cascade_filename())
    .detect_multi_scale(gray, scale_factor=1.1, step_ratio=1, min_size=(24, 24),
    max_size=(512, 512))`` (its defaults: 4 neighbours, intersection score 0.5);
  - OpenCV ``cv2.CascadeClassifier(file).detectMultiScale(gray_u8, 1.1, 3)`` on the same
    file with its ``featuhreParams`` tag corrected (OpenCV refuses the file as shipped).
    OpenCV 5 moved the cascade classifier to opencv-contrib: without it the row says so;
  - the lfw-trained Haar cascade of faces_cascade.yaml (its own settings).
* Scores as ``recognition.face_scores``: a found box is a hit when it claims an unclaimed
  true face at IoU ≥ 0.5 (best score first), recall, false positives per image, mean IoU
  of the hits, and the false positives per photograph.
* Times: milliseconds per 512² scene, wall and CPU (all threads), the median over the
  scenes after one warm-up scene, and the astronaut alone, best of 5 (wall); ratios are
  the other library's time over graphvision's. OpenCV runs on its default threads
  (``cv2.getNumThreads()``), the others on one. Cold runs of face_detect.yaml and
  faces_cascade.yaml (no cache).

Run: ``python bench/bench_faces.py`` (needs the ``bench`` extra; OpenCV's cascade
classifier needs ``opencv-contrib-python-headless`` on OpenCV 5).
"""

from __future__ import annotations

import statistics
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
import skimage.data
from timing import best

import graphvision as gv
from graphvision_plugins import recognition as rec
from graphvision_plugins import synthetic as syn
from graphvision_plugins.recognition._scenes import SceneBoxSet

PIPELINES = Path(__file__).parent.parent / "pipelines"
PHOTOS = ("astronaut", "astronaut_mirrored") + ("chelsea", "coffee", "rocket", "motorcycle",
                                                "retina") * 8  # fmt: skip
SEED = 100

Detector = Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]]


def graphvision_lbp() -> Detector:
    cascade = rec.lbp_cascade()

    def detect(gray: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        found = rec.lbp_detect(gray, cascade, scale_factor=1.1, step=1, min_neighbours=8)
        return found.xyxy, found.score

    return detect


def graphvision_lbp_opencv_scan() -> Detector:
    cascade = rec.lbp_cascade()

    def detect(gray: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        found = rec.lbp_detect(gray, cascade, scale_factor=1.1, step=0, min_neighbours=3)
        return found.xyxy, found.score

    return detect


def skimage_lbp() -> Detector:
    from skimage.feature import Cascade

    cascade = Cascade(skimage.data.lbp_frontal_face_cascade_filename())

    def detect(gray: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        found = cascade.detect_multi_scale(
            gray, scale_factor=1.1, step_ratio=1, min_size=(24, 24), max_size=(512, 512)
        )
        xyxy = [[d["c"], d["r"], d["c"] + d["width"], d["r"] + d["height"]] for d in found]
        return np.array(xyxy, np.float64).reshape(-1, 4), np.ones(len(xyxy))

    return detect


def opencv_lbp(cv2, folder: Path) -> Detector | None:
    if cv2 is None or not hasattr(cv2, "CascadeClassifier"):
        return None
    text = Path(skimage.data.lbp_frontal_face_cascade_filename()).read_text()
    corrected = folder / "lbpcascade_frontalface.xml"
    corrected.write_text(text.replace("featuhreParams", "featureParams"))
    cascade = cv2.CascadeClassifier(str(corrected))
    if cascade.empty():
        return None

    def detect(gray: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        gray_u8 = np.round(gray * 255).astype(np.uint8)
        found = cascade.detectMultiScale(gray_u8, 1.1, 3)
        xyxy = [[x, y, x + w, y + h] for x, y, w, h in np.asarray(found).reshape(-1, 4)]
        return np.array(xyxy, np.float64).reshape(-1, 4), np.ones(len(xyxy))

    return detect


def lfw_haar() -> Detector:
    graph = gv.load_pipeline(PIPELINES / "faces_cascade.yaml")
    model = gv.run(graph, outputs=["cascade"]).outputs["cascade"]

    def detect(gray: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        found = rec.detect_scenes(  # faces_cascade.yaml's settings
            gray[None], model, scale_step=1.2, min_scale=1.5, max_scale=6.0, step=2,
            threshold=0.0, min_neighbours=5,
        )  # fmt: skip
        return found.xyxy, found.score

    return detect


def measure(detect: Detector, images: np.ndarray) -> tuple[SceneBoxSet, list[float], list[float]]:
    """The boxes found in every scene, and the wall and CPU seconds (all threads) of each."""
    detect(images[0])  # warm-up (numba's compiled code, OpenCV's buffers)
    boxes, scores, owners, seconds, cpu = [], [], [], [], []
    for index, gray in enumerate(images):
        began, began_cpu = time.perf_counter(), time.process_time()
        xyxy, score = detect(gray)
        seconds.append(time.perf_counter() - began)
        cpu.append(time.process_time() - began_cpu)
        boxes.append(xyxy)
        scores.append(score)
        owners.append(np.full(len(xyxy), index, np.int64))
    found = SceneBoxSet(
        np.concatenate(boxes).reshape(-1, 4),
        np.concatenate(scores).astype(np.float64),
        np.concatenate(owners),
        len(images),
    )
    return found, seconds, cpu


def detector_rows(cv2) -> list[str]:
    scenes = syn.face_scenes(photos=PHOTOS, seed=SEED)
    astronaut = scenes.images[0]
    rows = [
        f"{len(scenes.images)} held-out scenes of 512², {len(scenes.faces)} true faces "
        f"(synthetic.face_scenes seed {SEED}).",
        "",
        "| detector | recall | false positives / image | IoU of hits | ms / scene "
        "| CPU ms / scene | astronaut ms | ratio to graphvision |",
        "| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |",
    ]
    per_photo = [
        "| detector | " + " | ".join(dict.fromkeys(PHOTOS)) + " |",
        "| --- |" + " ---: |" * len(dict.fromkeys(PHOTOS)),
    ]
    with tempfile.TemporaryDirectory() as folder:
        detectors = [
            ("graphvision LBP cascade (face_detect.yaml)", graphvision_lbp()),
            (
                "graphvision LBP cascade, OpenCV's scan and call (step 0, 3)",
                graphvision_lbp_opencv_scan(),
            ),
            ("skimage Cascade.detect_multi_scale, same file", skimage_lbp()),
            ("OpenCV CascadeClassifier, same file", opencv_lbp(cv2, Path(folder))),
            ("graphvision Haar cascade trained on lfw (faces_cascade.yaml)", lfw_haar()),
        ]
        ours = None
        for name, detect in detectors:
            if detect is None:
                rows.append(
                    f"| {name} | n/a: this OpenCV has no CascadeClassifier (OpenCV 5 "
                    "moved it to opencv-contrib) | | | | | | |"
                )
                continue
            found, seconds, cpu = measure(detect, scenes.images)
            scores = rec.face_scores(found, scenes.faces)
            alone = best(lambda detect=detect: detect(astronaut), repeats=5)
            ours = alone if ours is None else ours
            rows.append(
                f"| {name} | {scores.recall:.3f} | {scores.false_positives:.2f} | "
                f"{scores.face_iou:.3f} | {statistics.median(seconds) * 1e3:.0f} | "
                f"{statistics.median(cpu) * 1e3:.0f} | {alone * 1e3:.0f} | {alone / ours:.2f} |"
            )
            false = scores.table["false_positives"]
            counts = {
                photo: int(false[[p == photo for p in PHOTOS]].sum())
                for photo in dict.fromkeys(PHOTOS)
            }
            per_photo.append(f"| {name} | " + " | ".join(map(str, counts.values())) + " |")
    threads = cv2.getNumThreads() if cv2 is not None else 0
    rows += ["", f"OpenCV threads: {threads}; false positives per photograph "
             "(the collages appear 8 times each):", "", *per_photo]  # fmt: skip
    return rows


def pipeline_rows() -> list[str]:
    rows = ["| pipeline | cold run s | outputs |", "| --- | ---: | --- |"]
    for name in ("face_detect", "faces_cascade"):
        graph = gv.load_pipeline(PIPELINES / f"{name}.yaml")
        began = time.perf_counter()
        out = gv.run(graph, outputs=["recall", "false_positives", "face_iou"]).outputs
        seconds = time.perf_counter() - began
        rows.append(
            f"| {name}.yaml | {seconds:.1f} | recall {out['recall']:.3f}, false positives "
            f"/ image {out['false_positives']:.2f}, face_iou {out['face_iou']:.3f} |"
        )
    return rows


def main() -> list[str]:
    try:
        import cv2
    except ImportError:
        cv2 = None
    return [*detector_rows(cv2), "", *pipeline_rows()]


if __name__ == "__main__":
    print("\n".join(main()))
