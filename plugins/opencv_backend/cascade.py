"""OpenCV implementation of LBP cascade detection (``cv2.CascadeClassifier``), where the
installed OpenCV has it: the 4.x wheels do, OpenCV 5 dropped the class (its objdetect
module keeps no cascade classifier).

Whether it can run is decided twice. From the installed wheel's release, read from its
metadata (``requires``' ``"opencv-python-headless<5"``...; nothing imported): so that
``graphvision nodes`` and ``describe``, which print from the plugin index without
importing OpenCV, show it unavailable on OpenCV 5 and the install hint asks for
``opencv-python-headless<5`` (``graphvision[opencv]`` alone installs 5). Then, when a run
considers it, from the imported module (:func:`has_cascade_classifier`): a build without
a wheel's metadata (OpenCV compiled from source) is judged by what it has."""

from __future__ import annotations

import os
import tempfile
import xml.etree.ElementTree as ElementTree
from typing import Any

import numpy as np

from graphvision import BoxSet, implements

from .convert import EXTRA, WHEELS, cv, to_u8

__all__ = ["cascade_xml", "cv_lbp_detect", "has_cascade_classifier"]


def has_cascade_classifier() -> str:
    """'' when the installed OpenCV has ``CascadeClassifier``, else why not (the
    ``requires`` check of :func:`cv_lbp_detect`; it imports ``cv2``)."""
    cv2 = cv()
    if hasattr(cv2, "CascadeClassifier"):
        return ""
    return (
        f"OpenCV {cv2.__version__} has no CascadeClassifier: OpenCV 5 dropped it; "
        "opencv-python-headless 4.x has it"
    )


def cascade_xml(model: Any) -> str:
    """An :class:`~graphvision_plugins.recognition.LBPCascadeModel` in OpenCV's cascade
    format (``opencv_traincascade``'s XML, stumps of 256-category LBP features), the
    subset words written as OpenCV's signed 32-bit integers."""
    root = ElementTree.Element("opencv_storage")
    cascade = ElementTree.SubElement(root, "cascade", type_id="opencv-cascade-classifier")

    def add(parent: ElementTree.Element, tag: str, text: object = None) -> ElementTree.Element:
        element = ElementTree.SubElement(parent, tag)
        if text is not None:
            element.text = str(text)
        return element

    for tag, text in (("stageType", "BOOST"), ("featureType", "LBP")):
        add(cascade, tag, text)
    add(cascade, "height", model.height)
    add(cascade, "width", model.width)
    add(add(cascade, "featureParams"), "maxCatCount", 256)
    add(cascade, "stageNum", len(model.stage_threshold))
    stages = add(cascade, "stages")
    words = model.subsets.astype(np.uint32).view(np.int32)
    ends = model.stage_end
    for s, threshold in enumerate(model.stage_threshold):
        stage = add(stages, "_")
        first = 0 if s == 0 else int(ends[s - 1])
        add(stage, "maxWeakCount", int(ends[s]) - first)
        add(stage, "stageThreshold", repr(float(threshold)))
        weak = add(stage, "weakClassifiers")
        for k in range(first, int(ends[s])):
            item = add(weak, "_")
            nodes = [0, -1, int(model.feature[k]), *(int(w) for w in words[k])]
            add(item, "internalNodes", " ".join(map(str, nodes)))
            add(item, "leafValues", " ".join(repr(float(v)) for v in model.leaves[k]))
    features = add(cascade, "features")
    for rect in model.rects:
        add(add(features, "_"), "rect", " ".join(str(int(v)) for v in rect))
    return '<?xml version="1.0"?>\n' + ElementTree.tostring(root, encoding="unicode")


def _classifier(model: Any) -> Any:
    """``cv2.CascadeClassifier`` loaded from :func:`cascade_xml` of ``model``."""
    cv2 = cv()
    handle, path = tempfile.mkstemp(suffix=".xml")
    try:
        with os.fdopen(handle, "w") as file:
            file.write(cascade_xml(model))
        classifier = cv2.CascadeClassifier(path)
    finally:
        os.unlink(path)
    if classifier.empty():  # pragma: no cover - the model's port validated it
        raise ValueError("OpenCV could not load the cascade written from the model")
    return classifier


@implements(
    "recognition.lbp_detect",
    backend="opencv",
    requires=("cv2", *(f"{wheel}<5" for wheel in WHEELS), has_cascade_classifier),
    extra=EXTRA,
)
def cv_lbp_detect(
    image: np.ndarray,
    cascade: Any,
    *,
    scale_factor: float = 1.1,
    step: int = 1,
    min_size: float = 24.0,
    max_size: float = 4096.0,
    min_neighbours: int = 8,
    eps: float = 0.2,
) -> BoxSet:
    """``cv2.CascadeClassifier.detectMultiScale`` on the 8-bit image (every window kept,
    ``minNeighbors=0``), grouped by ``cv2.groupRectangles(min_neighbours', eps)``.
    OpenCV scans every second reduced pixel up to scale 2 (``step`` is the reference's),
    so about a quarter of the windows: a group needs more than
    ``min_neighbours' = ⌊min_neighbours · step² / 4⌋`` of them, or ``min_neighbours``
    at ``step`` 0 (the reference's OpenCV scan: the same windows). Scores are the
    groups' window counts (OpenCV's)."""
    cv2 = cv()
    side = (int(round(min_size)),) * 2
    largest = min(int(max_size), max(image.shape[:2]))
    windows = _classifier(cascade).detectMultiScale(
        to_u8(image), scaleFactor=scale_factor, minNeighbors=0, minSize=side,
        maxSize=(largest, largest),
    )  # fmt: skip
    if len(windows) == 0:
        return BoxSet(np.zeros((0, 4)), np.zeros(0))
    threshold = min_neighbours if step == 0 else min_neighbours * step * step // 4
    boxes, counts = cv2.groupRectangles([list(map(int, w)) for w in windows], threshold, eps)
    if len(boxes) == 0:
        return BoxSet(np.zeros((0, 4)), np.zeros(0))
    boxes = np.asarray(boxes, np.float64).reshape(-1, 4)
    xyxy = np.c_[boxes[:, :2], boxes[:, :2] + boxes[:, 2:]]
    score = np.asarray(counts, np.float64).ravel()
    order = np.argsort(-score, kind="stable")
    return BoxSet(xyxy[order], score[order])
