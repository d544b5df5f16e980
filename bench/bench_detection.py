"""Modern detection (issue 14): the CNN, selective search and the R-CNN pipeline, one run.

* Digits (``pipelines/cnn_digits.yaml``, seeded 80/20 split): held-out accuracy and
  training time of our CNN and of our softmax regression, beside scikit-learn's
  ``LogisticRegression(max_iter=2000)`` and ``MLPClassifier(hidden_layer_sizes=(64,),
  max_iter=1000, random_state=0)`` on the same split.
* Selective search on coins (``pipelines/proposals.yaml``): recall at IoU 0.5 of the 24
  coins' boxes against the number of proposals, and time, beside a sliding-window
  baseline with the same number of boxes (square windows of 24–64 px on a grid whose
  step is the same fraction of each size, the fraction chosen so that the count matches;
  ``cv2.ximgproc`` is not installable here: opencv-contrib is not in the bench extra).
* R-CNN (``pipelines/rcnn.yaml``): training times of the backbone and of the head,
  proposals and detection time per image, mAP@0.5 and true-positive IoU with and without
  box regression; the region proposal network's recall against selective search's at
  5–50 proposals per held-out scene.

Run: ``python bench/bench_detection.py`` (needs the ``bench`` extra for scikit-learn).
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np
import skimage.data

import graphvision as gv
from graphvision_plugins import detection
from graphvision_plugins.cnn import digits

PIPELINES = Path(__file__).parent.parent / "pipelines"
SIZES = (24, 32, 40, 48, 56, 64)


def _node_seconds(result: gv.RunResult) -> dict[str, float]:
    return {n.name: n.seconds for n in result.record.nodes}


def digits_rows() -> list[str]:
    from sklearn.linear_model import LogisticRegression
    from sklearn.neural_network import MLPClassifier

    result = gv.run(gv.load_pipeline(PIPELINES / "cnn_digits.yaml"))
    seconds = _node_seconds(result)
    out = result.outputs
    split = digits()
    x_train = split.train.images.reshape(len(split.train), -1)
    x_test = split.test.images.reshape(len(split.test), -1)
    rows = [
        "| classifier | held-out accuracy | training s |",
        "| --- | ---: | ---: |",
        f"| graphvision CNN (2 conv + dense, 15 epochs) | {out['accuracy']:.3f} | "
        f"{seconds['cnn']:.2f} |",
        f"| graphvision softmax regression (30 epochs) | {out['linear_accuracy']:.3f} | "
        f"{seconds['linear']:.2f} |",
    ]
    for name, model in (
        ("scikit-learn LogisticRegression", LogisticRegression(max_iter=2000)),
        ("scikit-learn MLPClassifier (64)", MLPClassifier((64,), max_iter=1000, random_state=0)),
    ):
        began = time.perf_counter()
        model.fit(x_train, split.train.labels)
        spent = time.perf_counter() - began
        accuracy = float(np.mean(model.predict(x_test) == split.test.labels))
        rows.append(f"| {name} | {accuracy:.3f} | {spent:.2f} |")
    return rows


def sliding_windows(shape: tuple[int, int], count: int) -> np.ndarray:
    """About ``count`` square windows of the sizes in SIZES, each on a grid of step
    ``fraction · size``, the fraction chosen so that the total is closest to ``count``."""
    rows, cols = shape

    def windows(fraction: float) -> np.ndarray:
        boxes = []
        for size in SIZES:
            step = max(fraction * size, 1.0)
            ys = np.arange(0, rows - size + 1, step)
            xs = np.arange(0, cols - size + 1, step)
            y, x = np.meshgrid(ys, xs, indexing="ij")
            boxes.append(
                np.column_stack([x.ravel(), y.ravel(), x.ravel() + size, y.ravel() + size])
            )
        return np.concatenate(boxes)

    fractions = np.geomspace(0.05, 4, 200)
    counts = np.array([len(windows(f)) for f in fractions])
    return windows(float(fractions[np.argmin(np.abs(counts - count))]))


def proposal_rows() -> list[str]:
    result = gv.run(gv.load_pipeline(PIPELINES / "proposals.yaml"))
    seconds = _node_seconds(result)["proposals"]
    out = result.outputs
    truth, proposals = out["truth"].xyxy, out["proposals"].xyxy
    shape = skimage.data.coins().shape
    rows = [
        f"Selective search on coins: {len(proposals)} proposals in {seconds:.2f} s "
        f"(2 colour spaces × 2 scales × 2 similarity sets); recall at IoU 0.5 of the "
        f"{len(truth)} coins:",
        "",
        "| proposals | selective search recall | sliding windows (same count) recall |",
        "| ---: | ---: | ---: |",
    ]
    for n in (10, 20, 50, 100, 200, len(proposals)):
        ours = detection.recall_at(proposals[:n], truth, 0.5)
        windows = sliding_windows(shape, n)
        theirs = detection.recall_at(windows, truth, 0.5)
        rows.append(f"| {n} ({len(windows)} windows) | {ours:.3f} | {theirs:.3f} |")
    return rows


def rcnn_rows() -> list[str]:
    graph = gv.load_pipeline(PIPELINES / "rcnn.yaml")
    for name in ("detector", "test_scenes", "test_proposals", "rpn"):
        graph.output(f"the_{name}", name)
    result = gv.run(graph, executor="sync")  # one node at a time: each node's own time
    seconds = _node_seconds(result)
    out = result.outputs
    scenes = out["the_test_scenes"]
    # per-image times measured alone (in the run, both detect nodes share the cores);
    # detection includes the class-wise NMS
    began = time.perf_counter()
    proposals = detection.scene_proposals(scenes)
    propose = (time.perf_counter() - began) / len(scenes)
    began = time.perf_counter()
    detection.nms(detection.detect(out["the_detector"], scenes, proposals))
    detect = (time.perf_counter() - began) / len(scenes)
    began = time.perf_counter()
    detection.rpn_proposals(out["the_rpn"], scenes, max_boxes=10)
    rpn = (time.perf_counter() - began) / len(scenes)
    recalls = []
    for count in (5, 10, 20, 50):
        by_rpn = detection.rpn_proposals(out["the_rpn"], scenes, max_boxes=count)
        recalls.append(
            f"{count}: {detection.scene_recall(by_rpn, scenes):.3f} / "
            f"{detection.scene_recall(proposals, scenes, count=count):.3f}"
        )
    return [
        "| what | figure |",
        "| --- | --- |",
        f"| backbone training (cnn.train on warped proposals) | {seconds['backbone']:.1f} s |",
        f"| head training (ROI pooling + classifier + ridge regressors) | "
        f"{seconds['detector']:.1f} s |",
        f"| per test image (80×80): selective search, detection | {propose * 1000:.0f} ms, "
        f"{detect * 1000:.0f} ms |",
        f"| mAP@0.5, with / without box regression | {out['map50']:.3f} / "
        f"{out['map50_without_regression']:.3f} |",
        f"| mean IoU of true positives, with / without | {out['tp_iou']:.3f} / "
        f"{out['tp_iou_without_regression']:.3f} |",
        f"| region proposal network: training, proposals per image | {seconds['rpn']:.1f} s, "
        f"{rpn * 1000:.0f} ms |",
        f"| recall at IoU 0.5 of the first n proposals per scene, RPN / selective search | "
        f"{'; '.join(recalls)} |",
    ]


def main() -> list[str]:
    return [
        "### Digits",
        "",
        *digits_rows(),
        "",
        "### Proposals",
        "",
        *proposal_rows(),
        "",
        "### R-CNN on synthetic digit scenes",
        "",
        *rcnn_rows(),
    ]


if __name__ == "__main__":
    print("\n".join(main()))
