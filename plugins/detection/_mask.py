"""Mask R-CNN (seed: "mask RCNN, which adds a branch for predicting segmentation masks on
each ROI, which allows the network to perform both object detection and instance
segmentation at the same time"): training the mask branch on a Faster R-CNN's features,
and predicting each detection's mask, pasted back into its scene."""

from __future__ import annotations

import json
from typing import Annotated, Any

import numpy as np
from pydantic import Field

from graphvision import Array, node, one_blas_thread

from ..cnn import build_architecture, check_layer_texts
from ..shared.boxes import iou_matrix
from ..shared.params import Epochs, Positive, Seed
from ..synthetic._digit_scenes import Scenes, SceneSet
from ._faster_types import FasterRcnn, FasterRcnnModel
from ._mask_head import (
    MaskHead,
    MaskHeadModel,
    mask_targets,
    paste_mask,
    roi_align,
    train_mask_network,
)
from ._types import Detections

__all__ = ["mask_inputs", "predict_masks", "train_mask_head"]


def check_masks(scenes: SceneSet, masks: np.ndarray, what: str = "masks") -> None:
    """ValueError unless ``masks`` holds one (H, W) mask per true box of the scenes."""
    want = (len(scenes.xyxy), *scenes.images.shape[1:])
    if masks.shape != want:
        raise ValueError(
            f"{what} must hold one {want[1]}×{want[2]} mask per true box, shape {want}; "
            f"got {masks.shape}"
        )


def mask_inputs(
    model: FasterRcnnModel, image: np.ndarray, xyxy: np.ndarray, size: int
) -> np.ndarray:
    """The mask branch's input for boxes of one scene: the RoIAlign of the Faster R-CNN's
    feature map and of the scene itself, (R, C + 1, size, size) float32."""
    features_net = model.architectures(image.shape)[0]
    maps = features_net.forward(model.feature_weights, image[None, None].astype(np.float32))[0][0]
    return np.concatenate(
        [
            roi_align(maps, xyxy, model.stride, size),
            roi_align(image[None].astype(np.float32), xyxy, 1, size),
        ],
        axis=1,
    )


def _jittered(truth: np.ndarray, copies: int, shape: tuple[int, ...], rng: np.random.Generator):
    """Each true box and ``copies`` seeded jittered copies (shifted and scaled by up to 15 %
    of its size, inside the scene) overlapping it by IoU ≥ 0.5; boxes and their true box."""
    base = np.repeat(truth, copies + 1, axis=0)
    owner = np.repeat(np.arange(len(truth)), copies + 1)
    noise = rng.uniform(-0.15, 0.15, base.shape) * np.tile(base[:, 2:] - base[:, :2], 2)
    noise[:: copies + 1] = 0
    boxes = base + noise
    boxes[:, [0, 2]] = np.clip(boxes[:, [0, 2]], 0, shape[1])
    boxes[:, [1, 3]] = np.clip(boxes[:, [1, 3]], 0, shape[0])
    sound = (boxes[:, 2] - boxes[:, 0] >= 2) & (boxes[:, 3] - boxes[:, 1] >= 2)
    boxes, owner = boxes[sound], owner[sound]
    near = np.diag(iou_matrix(boxes, truth[owner])) >= 0.5
    return boxes[near], owner[near]


def _training_set(
    model: FasterRcnnModel, scenes: SceneSet, masks: np.ndarray, size: int, jitter: int,
    seed: int,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:  # fmt: skip
    """Inputs, targets and class channels of the training ROIs of all scenes."""
    rng = np.random.default_rng(seed)
    inputs, targets, channels = [], [], []
    for scene in range(len(scenes)):
        mine = np.flatnonzero(scenes.owner == scene)
        if len(mine) == 0:
            continue
        boxes, which = _jittered(scenes.xyxy[mine], jitter, scenes.images.shape[1:], rng)
        inputs.append(mask_inputs(model, scenes.images[scene], boxes, size))
        targets.append(mask_targets(masks[mine[which]], boxes, size))
        channels.append(np.searchsorted(model.classes, scenes.label[mine[which]]))
    if not inputs:
        raise ValueError("the training scenes hold no object to learn masks from")
    return np.concatenate(inputs), np.concatenate(targets), np.concatenate(channels)


def _layers_parse(**params: Any) -> None:
    check_layer_texts(params["layers"])


@node("detection.train_mask_head", version=1, check=_layers_parse)
def train_mask_head(
    model: FasterRcnn,
    scenes: Scenes,
    masks: Array,
    *,
    resolution: Annotated[int, Field(ge=4, le=56)] = 14,
    layers: Annotated[list[str], Field(min_length=1)] = [  # noqa: B006
        "conv 16x3",
        "relu",
        "conv 16x3",
        "relu",
    ],
    jitter: Annotated[int, Field(ge=0, le=32)] = 4,
    epochs: Epochs = 10,
    batch_size: Annotated[int, Field(ge=1, le=1024)] = 32,
    learning_rate: Positive = 0.05,
    momentum: Annotated[float, Field(ge=0, lt=1)] = 0.9,
    weight_decay: Annotated[float, Field(ge=0)] = 1e-4,
    seed: Seed = 0,
) -> MaskHead:
    r"""Train Mask R-CNN's mask branch on a trained Faster R-CNN's feature map: a small fully
    convolutional network on each ROI's RoIAlign (``resolution`` × ``resolution``; the
    scene's own pixels are one more channel), ending in a 1 × 1 convolution with one mask
    logit map per class; per-pixel sigmoid cross-entropy on the map of the ROI's class
    only, against the ROI's true mask sampled at the same bins:

    .. math:: L_{mask} = -\frac{1}{m^2}\sum_{ij} \big(y_{ij}\log\sigma(z^k_{ij})
              + (1 - y_{ij})\log(1 - \sigma(z^k_{ij}))\big)

    The ROIs are the true boxes and ``jitter`` seeded jittered copies of each overlapping
    it by IoU ≥ 0.5 (the positive ROIs, as the paper's mask loss). Trained after the
    detector, on its frozen features (the paper trains all branches together).

    Parameters
    ----------
    model : FasterRcnn
        A trained Faster R-CNN (``detection.train_faster_rcnn``).
    scenes : Scenes
        Training scenes with their true boxes.
    masks : Array
        (M, H, W) bool, the true mask of each true box (``synthetic.instance_scenes``).
    resolution : int
        Side m of the masks (14 or 28 in the paper).
    layers : list of str
        The branch's layers before its last (``conv Kx1``, K classes, is appended); each
        convolution keeps the size.
    jitter : int
        Jittered copies of each true box.
    epochs, batch_size : int
        Passes over the ROIs and ROIs per step.
    learning_rate, momentum, weight_decay : float
        SGD with momentum.
    seed : int
        Seed of the jitter, the initial weights and the order.

    Returns
    -------
    MaskHead
        The trained branch.

    References
    ----------
    K. He, G. Gkioxari, P. Dollár and R. Girshick, "Mask R-CNN", ICCV 2017.
    """
    check_masks(scenes, masks)
    if not set(np.unique(scenes.label)) <= set(model.classes.tolist()):
        raise ValueError(
            f"the scenes hold classes {sorted(set(np.unique(scenes.label)))} but the Faster "
            f"R-CNN knows {model.classes.tolist()}"
        )
    with one_blas_thread():
        inputs, targets, channels = _training_set(model, scenes, masks, resolution, jitter, seed)
        texts = [*layers, f"conv {len(model.classes)}x1"]
        network = build_architecture(inputs.shape[1:], texts)
        if network.shapes[-1][1:] != (resolution, resolution):
            raise ValueError(
                f"the mask layers turn {resolution}×{resolution} ROIs into "
                f"{network.shapes[-1][1:]} maps; keep the size (no pooling, 'conv FxK' pads)"
            )
        weights, history = train_mask_network(
            network, inputs, targets, channels, epochs=epochs, batch_size=batch_size,
            learning_rate=learning_rate, momentum=momentum, weight_decay=weight_decay,
            seed=seed,
        )  # fmt: skip
    spec = json.dumps({"input": list(inputs.shape[1:]), "layers": texts})
    return MaskHeadModel(spec, weights, model.classes.copy(), history)


@node("detection.predict_masks", version=1)
def predict_masks(
    model: FasterRcnn, head: MaskHead, scenes: Scenes, detections: Detections
) -> Array:
    """Each detection's mask: the mask branch on the RoIAlign of its box, the sigmoid of the
    map of its class, resampled bilinearly into the box and thresholded at 0.5 (Mask
    R-CNN's inference, section 3.1).

    Parameters
    ----------
    model : FasterRcnn
        The Faster R-CNN the branch was trained on.
    head : MaskHead
        The trained mask branch (``detection.train_mask_head``).
    scenes : Scenes
        The scenes the detections were found in.
    detections : Detections
        Detections of the model's classes.

    Returns
    -------
    Array
        (D, H, W) bool, one scene-sized mask per detection, in their order.

    References
    ----------
    K. He, G. Gkioxari, P. Dollár and R. Girshick, "Mask R-CNN", ICCV 2017.
    """
    if detections.scenes != len(scenes):
        raise ValueError(
            f"the detections cover {detections.scenes} scenes but {len(scenes)} scenes are given"
        )
    if not np.isin(detections.label, head.classes).all():
        raise ValueError(
            f"the detections hold classes the mask head lacks ({head.classes.tolist()})"
        )
    network = head.parsed()
    size = network.shapes[0][1]
    shape = scenes.images.shape[1:]
    out = np.zeros((len(detections), *shape), bool)
    with one_blas_thread():
        for scene in np.unique(detections.owner):
            mine = np.flatnonzero(detections.owner == scene)
            inputs = mask_inputs(model, scenes.images[scene], detections.xyxy[mine], size)
            logits = network.forward(head.weights, inputs)[0]
            channel = np.searchsorted(head.classes, detections.label[mine])
            probability = 1 / (1 + np.exp(-logits[np.arange(len(mine)), channel]))
            for row, index in enumerate(mine):
                out[index] = paste_mask(probability[row], detections.xyxy[index], shape)
    return out
