"""Faster R-CNN and Mask R-CNN (issue 28 items 1, 2) beside the selective-search R-CNN.

* R-CNN (``pipelines/rcnn.yaml``) and Faster R-CNN (``pipelines/faster_rcnn.yaml``) on the
  same 50 held-out scenes (seed 1000, held-out digits), both from the same backbone
  recipe: mAP@0.5, mean IoU of the true positives, recall at IoU 0.5 of the first 10, 50
  and 300 proposals per scene (selective search / the RPN), training time of each
  detector, and time per scene measured alone after the run (R-CNN: selective search,
  then ROI pooling, head and class-wise NMS; Faster R-CNN: one pass of the network with
  the RPN's 300 proposals, then class-wise NMS).
* Mask R-CNN (``pipelines/mask_rcnn.yaml``) on its held-out instance scenes: box mAP@0.5,
  COCO mask AP at IoU 0.5 and 0.75, training time of the mask branch, time per scene of
  detection and masks.

Each pipeline runs once, cold, with the sync executor (one node at a time: each node's own
time); the pipeline's wall and CPU times are reported too (on a shared machine the CPU
time is the cold run's time alone).

Run: ``python bench/bench_faster_rcnn.py`` (needs scikit-learn: the ``bench`` extra).
"""

from __future__ import annotations

import time
from pathlib import Path

import graphvision as gv
from graphvision_plugins import detection

PIPELINES = Path(__file__).parent.parent / "pipelines"


def _run(name: str, extra: tuple[str, ...]) -> tuple[dict, dict[str, float], str]:
    graph = gv.load_pipeline(PIPELINES / name)
    for ref in extra:
        graph.output(f"the_{ref.replace('.', '_')}", ref)
    began, cpu = time.perf_counter(), time.process_time()
    result = gv.run(graph, executor="sync", cache=None)
    wall = f"{time.perf_counter() - began:.1f} s (CPU {time.process_time() - cpu:.1f} s)"
    return result.outputs, {n.name: n.seconds for n in result.record.nodes}, wall


def _per_scene(call, scenes: int) -> float:
    began = time.perf_counter()
    call()
    return (time.perf_counter() - began) / scenes * 1000


def detection_rows() -> list[str]:
    rcnn, rcnn_s, rcnn_wall = _run("rcnn.yaml", ("detector", "test_scenes", "test_proposals"))
    fast, fast_s, fast_wall = _run("faster_rcnn.yaml", ("model", "test_scenes"))
    scenes = rcnn["the_test_scenes"]
    n = len(scenes)
    rcnn_ms = _per_scene(
        lambda: detection.nms(
            detection.detect(rcnn["the_detector"], scenes, detection.scene_proposals(scenes))
        ),
        n,
    )
    fast_ms = _per_scene(
        lambda: detection.nms(detection.faster_rcnn(fast["the_model"], scenes).detections), n
    )
    found = detection.faster_rcnn(fast["the_model"], scenes)
    recalls = []
    for count in (10, 50, 300):
        selective = detection.scene_recall(rcnn["the_test_proposals"], scenes, count=count)
        rpn = detection.scene_recall(found.proposals, scenes, count=count)
        recalls.append(f"{count}: {selective:.3f} / {rpn:.3f}")
    return [
        "| held-out digit scenes (50, seed 1000) | R-CNN (selective search) | Faster R-CNN |",
        "| --- | ---: | ---: |",
        f"| mAP@0.5 | {rcnn['map50']:.3f} | {fast['map50']:.3f} |",
        f"| mean IoU of true positives | {rcnn['tp_iou']:.3f} | {fast['tp_iou']:.3f} |",
        f"| time per scene (proposals + detection + NMS) | {rcnn_ms:.0f} ms | {fast_ms:.0f} ms |",
        f"| backbone training (same recipe) | {rcnn_s['backbone']:.1f} s | "
        f"{fast_s['backbone']:.1f} s |",
        f"| detector training | head {rcnn_s['detector']:.1f} s | joint RPN + head + "
        f"fine-tuning {fast_s['model']:.1f} s |",
        f"| whole pipeline, cold, sync: wall (CPU) | {rcnn_wall} | {fast_wall} |",
        "",
        "Recall at IoU 0.5 of the first n proposals per scene, selective search / RPN: "
        + "; ".join(recalls),
    ]


def mask_rows() -> list[str]:
    out, seconds, wall = _run("mask_rcnn.yaml", ("model", "mask_head", "test.scenes"))
    scenes = out["the_test_scenes"]
    model, head = out["the_model"], out["the_mask_head"]

    def masks() -> None:
        found = detection.nms(detection.faster_rcnn(model, scenes).detections)
        detection.predict_masks(model, head, scenes, found)

    per_scene = _per_scene(masks, len(scenes))
    return [
        "| held-out instance scenes (50, seed 1000) | figure |",
        "| --- | ---: |",
        f"| box mAP@0.5 | {out['map50']:.3f} |",
        f"| mask AP at IoU 0.5 (COCO) | {out['mask_map50']:.3f} |",
        f"| mask AP at IoU 0.75 (COCO) | {out['mask_map75']:.3f} |",
        f"| Faster R-CNN training, mask branch training | {seconds['model']:.1f} s, "
        f"{seconds['mask_head']:.1f} s |",
        f"| time per scene (detection + masks) | {per_scene:.0f} ms |",
        f"| whole pipeline, cold, sync: wall (CPU) | {wall} |",
    ]


def main() -> list[str]:
    return [
        "### Faster R-CNN beside R-CNN",
        "",
        *detection_rows(),
        "",
        "### Mask R-CNN",
        "",
        *mask_rows(),
    ]


if __name__ == "__main__":
    import sys

    parts = {"detection": detection_rows, "masks": mask_rows}
    for part in sys.argv[1:] or list(parts):  # e.g. python bench_faster_rcnn.py masks
        print("\n".join(parts[part]()), flush=True)
