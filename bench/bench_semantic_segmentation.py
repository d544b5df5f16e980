"""Semantic segmentation (issue 28, item 3): ``pipelines/segment_scenes.yaml``'s U-Net
beside per-pixel classifiers of scikit-learn on the same scenes.

Protocol: the scenes of the pipeline (training: 100 scenes of seed 0; held out: 40 of
seed 1000 like the training ones, and 40 "unlike" scenes of seed 2000: other
photographs as backgrounds, brighter backgrounds, 0 to 8 shapes of sizes 5–14, twice
the noise). Every method is scored by ``segmentation.evaluate`` (mean IU over the five
classes, background included; pixel accuracy).

* graphvision: the pipeline, cold (no cache), with its defaults; its wall time and the
  process's CPU time are reported (the machine is shared, so the wall time includes
  waiting for a core).
* scikit-learn, per-pixel features: ``skimage.feature.multiscale_basic_features(image,
  intensity=True, edges=True, texture=True, sigma_min=1, sigma_max=16)`` (scikit-image's
  "trainable segmentation": Gaussian-smoothed intensity, gradient magnitude and Hessian
  eigenvalues at 5 scales, 15 features per pixel), ``SAMPLES`` training pixels drawn at
  random (seed 0) from the training scenes, then
  ``RandomForestClassifier(n_estimators=50, max_depth=12, n_jobs=1, random_state=0,
  class_weight="balanced")`` and ``LogisticRegression(max_iter=500,
  class_weight="balanced")`` on standardised features.

Run: ``python bench/bench_semantic_segmentation.py``.
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

import graphvision as gv
from graphvision_plugins import segmentation
from graphvision_plugins.synthetic import LabelledSceneSet

PIPELINE = Path(__file__).parent.parent / "pipelines" / "segment_scenes.yaml"
SAMPLES = 60_000


def _features(images: np.ndarray) -> np.ndarray:
    from skimage.feature import multiscale_basic_features

    return np.stack(
        [multiscale_basic_features(image, sigma_min=1, sigma_max=16) for image in images]
    )


def _baselines(train, sets: dict) -> list[tuple[str, dict]]:
    from sklearn.ensemble import RandomForestClassifier
    from sklearn.linear_model import LogisticRegression
    from sklearn.pipeline import make_pipeline
    from sklearn.preprocessing import StandardScaler

    features = _features(train.images)
    rng = np.random.default_rng(0)
    pick = rng.choice(train.labels.size, SAMPLES, replace=False)
    x, y = features.reshape(-1, features.shape[-1])[pick], train.labels.ravel()[pick]
    models = {
        "scikit-learn random forest, per-pixel features": RandomForestClassifier(
            n_estimators=50, max_depth=12, n_jobs=1, random_state=0, class_weight="balanced"
        ),
        "scikit-learn logistic regression, per-pixel features": make_pipeline(
            StandardScaler(), LogisticRegression(max_iter=500, class_weight="balanced")
        ),
    }
    rows = []
    for name, model in models.items():
        began = time.perf_counter()
        model.fit(x, y)
        scores = {"time": time.perf_counter() - began}
        for label, truth in sets.items():
            f = _features(truth.images)
            predicted = model.predict(f.reshape(-1, f.shape[-1])).reshape(truth.labels.shape)
            labelled = LabelledSceneSet(truth.images, predicted.astype(np.int32), truth.names)
            scores[label] = segmentation.evaluate(labelled, truth)
        rows.append((name, scores))
    return rows


def _pipeline_scenes() -> tuple[LabelledSceneSet, dict]:
    """The pipeline's training, held-out and unlike scenes, made from its own parameters
    (read from the YAML file; ``${params.seed}`` is its default, 0)."""
    import yaml

    from graphvision_plugins import synthetic

    nodes = yaml.safe_load(PIPELINE.read_text())["nodes"]

    def scenes(name: str) -> LabelledSceneSet:
        params = {k: 0 if v == "${params.seed}" else v for k, v in nodes[name]["params"].items()}
        return synthetic.shape_scenes(**params)

    return scenes("train_scenes"), {
        "test": scenes("test_scenes"),
        "unlike": scenes("unlike_scenes"),
    }


def main() -> list[str]:
    graph = gv.load_pipeline(PIPELINE)
    began, cpu = time.perf_counter(), time.process_time()
    result = gv.run(graph, cache=gv.Cache(None, None))
    wall, cpu = time.perf_counter() - began, time.process_time() - cpu
    out = result.outputs
    rows = [
        "| method | mIoU held out | pixel acc. held out | mIoU unlike | pixel acc. unlike "
        "| time (s) |",
        "| --- | ---: | ---: | ---: | ---: | ---: |",
        f"| graphvision U-Net (segment_scenes.yaml, cold) | {out['miou']:.3f} | "
        f"{out['pixel_accuracy']:.3f} | {out['miou_unlike']:.3f} | "
        f"{out['pixel_accuracy_unlike']:.3f} | {wall:.1f} wall, {cpu:.1f} CPU |",
    ]
    train, sets = _pipeline_scenes()
    for name, scores in _baselines(train, sets):
        test, unlike = scores["test"], scores["unlike"]
        rows.append(
            f"| {name} | {test.miou:.3f} | {test.pixel_accuracy:.3f} | {unlike.miou:.3f} | "
            f"{unlike.pixel_accuracy:.3f} | {scores['time']:.1f} fit |"
        )
    iou = out["class_iou"]
    rows += [
        "",
        "U-Net IoU per class (held out): "
        + ", ".join(f"{n} {v:.3f}" for n, v in zip(iou["name"], iou["iou"], strict=True)),
    ]
    return rows


if __name__ == "__main__":
    print("\n".join(main()))
