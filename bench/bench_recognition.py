"""Recognition side by side with scikit-image, scikit-learn and OpenCV, one run, same split.

* Accuracy on the lfw_subset split of ``recognition.lfw_faces`` (150/50, seed 0):
  PCA + 1-NN (graphvision vs ``sklearn.decomposition.PCA`` + ``KNeighborsClassifier(1)``
  for 10/20/50 components), HOG + linear SVM (graphvision vs ``skimage.feature.hog`` +
  ``sklearn.svm.LinearSVC``), 2,000 Haar-like features + AdaBoost with 100 stumps
  (graphvision vs the same features + ``sklearn.ensemble.AdaBoostClassifier``), with
  training times.
* Feature extractors, best of 5: HOG of the 200 lfw images and of camera (512²), Haar-like
  features (2,000 of them on 200 images); scikit-image, and OpenCV's HOGDescriptor (its
  own variant: trilinear votes, Gaussian block weights, so times only).
* Face detection on the astronaut: ``pipelines/face_detect.yaml`` against OpenCV's
  frontal-face Haar cascade and scikit-image's LBP cascade; boxes, IoU with the face
  (x 175–270, y 60–165), false positives, time.
* Bag of words on brick/grass/gravel patches (``pipelines/textures_bow.yaml``).

Ratios are the other library's time over graphvision's (above 1: graphvision is faster).
Run: ``python bench/bench_recognition.py`` (needs the ``bench`` extra).
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np
import skimage.data
from timing import best

import graphvision as gv
from graphvision_plugins import recognition as rec

PIPELINES = Path(__file__).parent.parent / "pipelines"
FACE = np.array([[175.0, 60.0, 270.0, 165.0]])


def _timed(func):
    began = time.perf_counter()
    value = func()
    return value, time.perf_counter() - began


def accuracy_rows() -> list[str]:
    from skimage.feature import hog
    from sklearn.decomposition import PCA
    from sklearn.ensemble import AdaBoostClassifier
    from sklearn.neighbors import KNeighborsClassifier
    from sklearn.svm import LinearSVC

    split = rec.lfw_faces()
    train_px, test_px = rec.pixels(split.train), rec.pixels(split.test)
    y_train, y_test = split.train.labels, split.test.labels
    rows = [
        "| method | graphvision accuracy | train s | reference | reference accuracy | train s |",
        "| --- | ---: | ---: | --- | ---: | ---: |",
    ]
    for k in (10, 20, 50):

        def ours(k=k):
            subspace = rec.pca(train_px, components=k)
            return rec.nearest_neighbour(rec.project(train_px, subspace)), subspace

        (nn, subspace), seconds = _timed(ours)
        score = rec.accuracy(
            rec.project(test_px, subspace), rec.predict(nn, rec.project(test_px, subspace))
        )

        def theirs(k=k):
            pca = PCA(k).fit(train_px.features)
            return KNeighborsClassifier(1).fit(pca.transform(train_px.features), y_train), pca

        (knn, pca), ref_seconds = _timed(theirs)
        ref = knn.score(pca.transform(test_px.features), y_test)
        rows.append(
            f"| PCA ({k}) + 1-NN | {score:.2f} | {seconds:.3f} | sklearn PCA + KNeighbors(1) "
            f"| {ref:.2f} | {ref_seconds:.3f} |"
        )
    train_hog, test_hog = rec.hog(split.train), rec.hog(split.test)
    svm, seconds = _timed(lambda: rec.linear_svm(train_hog))
    score = rec.accuracy(test_hog, rec.predict(svm, test_hog))
    sk_train = np.stack([hog(i, 9, (6, 6), (2, 2)) for i in split.train.images])
    sk_test = np.stack([hog(i, 9, (6, 6), (2, 2)) for i in split.test.images])
    linear, ref_seconds = _timed(lambda: LinearSVC(C=1.0).fit(sk_train, y_train))
    rows.append(
        f"| HOG + linear SVM | {score:.2f} | {seconds:.3f} | skimage hog + LinearSVC "
        f"| {linear.score(sk_test, y_test):.2f} | {ref_seconds:.3f} |"
    )
    train_haar, test_haar = rec.haar(split.train), rec.haar(split.test)
    boosted, seconds = _timed(lambda: rec.adaboost(train_haar, rounds=100))
    score = rec.accuracy(test_haar, rec.predict(boosted, test_haar))
    ada, ref_seconds = _timed(
        lambda: AdaBoostClassifier(n_estimators=100, random_state=0).fit(
            train_haar.features, y_train
        )
    )
    rows.append(
        f"| 2,000 Haar-like + AdaBoost (100 stumps) | {score:.2f} | {seconds:.3f} | same "
        f"features + sklearn AdaBoostClassifier | {ada.score(test_haar.features, y_test):.2f} "
        f"| {ref_seconds:.3f} |"
    )
    return rows


def extractor_rows(cv2) -> list[str]:
    from skimage.feature import haar_like_feature, hog
    from skimage.transform import integral_image

    lfw = skimage.data.lfw_subset().astype(np.float32)
    camera = (skimage.data.camera() / 255).astype(np.float32)
    samples = rec.SamplesPort.validate(rec._types.SampleSet(lfw, np.zeros(len(lfw), np.int64)))
    rows = [
        "| features | graphvision ms | skimage ms | skimage / graphvision | OpenCV ms |",
        "| --- | ---: | ---: | ---: | ---: |",
    ]
    cv2 = cv2 if hasattr(cv2, "HOGDescriptor") else None  # OpenCV 5 moved it to contrib
    cv_hog_small = cv2 and cv2.HOGDescriptor((24, 24), (12, 12), (6, 6), (6, 6), 9)
    lfw_u8 = (lfw * 255).astype(np.uint8)
    ours = best(lambda: rec.hog_features(lfw, 9, (6, 6), (2, 2)))
    theirs = best(lambda: [hog(i, 9, (6, 6), (2, 2)) for i in lfw])
    cv = best(lambda: [cv_hog_small.compute(i[:24, :24]) for i in lfw_u8]) if cv2 else None
    rows.append(_extractor_row("HOG, 200 lfw images 25×25", ours, theirs, cv))
    cv_hog = cv2 and cv2.HOGDescriptor((512, 512), (24, 24), (8, 8), (8, 8), 9)
    camera_u8 = skimage.data.camera()
    ours = best(lambda: rec.hog_features(camera[None], 9, (8, 8), (3, 3)))
    theirs = best(lambda: hog(camera, 9, (8, 8), (3, 3)))
    cv = best(lambda: cv_hog.compute(camera_u8)) if cv2 else None
    rows.append(_extractor_row("HOG, camera 512², 8×8 cells, 3×3 blocks", ours, theirs, cv))
    table = rec.sample_haar_features((25, 25), 2000, 0)
    names = list(rec.HAAR_TYPES)
    kinds = np.array([names[t] for t in table[:, 0]], dtype=object)
    rects = np.empty(len(table), dtype=object)
    for i, (t, r, c, h, w) in enumerate(table):
        rects[i] = [
            [(r + dr * h, c + dc * w), (r + dr * h + h - 1, c + dc * w + w - 1)]
            for dr, dc in rec.HAAR_TYPES[names[t]][1]
        ]
    ours = best(lambda: rec.haar(samples, count=2000))
    theirs = best(
        lambda: [haar_like_feature(integral_image(i), 0, 0, 25, 25, kinds, rects) for i in lfw],
        repeats=2,
    )
    rows.append(_extractor_row("2,000 Haar-like features, 200 images", ours, theirs, None))
    return rows


def _extractor_row(what: str, ours: float, theirs: float, cv: float | None) -> str:
    cv_text = "n/a" if cv is None else f"{cv * 1e3:.1f}"
    return f"| {what} | {ours * 1e3:.1f} | {theirs * 1e3:.1f} | {theirs / ours:.1f} | {cv_text} |"


def detection_rows(cv2) -> list[str]:
    rows = [
        "| detector | boxes | best IoU with the face | false positives | ms |",
        "| --- | ---: | ---: | ---: | ---: |",
    ]
    graph = gv.load_pipeline(PIPELINES / "face_detect.yaml")
    result = gv.run(graph, outputs=["boxes"])
    detect_ms = sum(
        n.seconds for n in result.record.nodes if n.name in ("gray", "windows", "boxes")
    )
    boxes = result.outputs["boxes"].xyxy
    rows.append(_detection_row("graphvision LBP cascade (face_detect.yaml)", boxes, detect_ms))
    gray = skimage.data.astronaut().mean(axis=2)
    if hasattr(cv2, "CascadeClassifier"):  # OpenCV 5 moved it to contrib
        cascade = cv2.CascadeClassifier(
            cv2.data.haarcascades + "haarcascade_frontalface_default.xml"
        )
        gray_u8 = gray.astype(np.uint8)
        found, seconds = _timed(lambda: cascade.detectMultiScale(gray_u8))
        xyxy = np.array([[x, y, x + w, y + h] for x, y, w, h in found], np.float64).reshape(-1, 4)
        rows.append(_detection_row("OpenCV Haar cascade (frontalface_default)", xyxy, seconds))
    from skimage.feature import Cascade

    detector = Cascade(skimage.data.lbp_frontal_face_cascade_filename())
    found, seconds = _timed(
        lambda: detector.detect_multi_scale(
            gray / 255, scale_factor=1.2, step_ratio=1, min_size=(60, 60), max_size=(123, 123)
        )
    )
    xyxy = np.array(
        [[d["c"], d["r"], d["c"] + d["width"], d["r"] + d["height"]] for d in found], np.float64
    ).reshape(-1, 4)
    rows.append(_detection_row("skimage LBP cascade (gallery settings)", xyxy, seconds))
    return rows


def _detection_row(what: str, boxes: np.ndarray, seconds: float) -> str:
    iou = rec.iou_matrix(boxes, FACE)[:, 0] if len(boxes) else np.zeros(0)
    best_iou = float(iou.max()) if len(iou) else 0.0
    false = int((iou < 0.5).sum())
    return f"| {what} | {len(boxes)} | {best_iou:.2f} | {false} | {seconds * 1e3:.0f} |"


def bow_rows() -> list[str]:
    result = gv.run(gv.load_pipeline(PIPELINES / "textures_bow.yaml"), outputs=["accuracy"])
    seconds = sum(n.seconds for n in result.record.nodes)
    return [
        "| pipeline | accuracy on 96 held-out patches | s |",
        "| --- | ---: | ---: |",
        f"| textures_bow.yaml (dense SIFT, 50 words, linear SVM) | "
        f"{result.outputs['accuracy']:.2f} | {seconds:.1f} |",
    ]


def main() -> list[str]:
    try:
        import cv2
    except ImportError:
        cv2 = None
    return [
        *accuracy_rows(),
        "",
        *extractor_rows(cv2),
        "",
        *detection_rows(cv2),
        "",
        *bow_rows(),
    ]


if __name__ == "__main__":
    print("\n".join(main()))
