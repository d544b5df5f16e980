"""Semantic segmentation (seed: "assigning a class label to each pixel … we apply CNNs to
encode each pixel"): an encoder–decoder network with skip connections (U-Net) in NumPy,
trained per pixel by the softmax cross-entropy of every pixel, applied to whole scenes
(fully convolutional), scored by the mean intersection over union and the pixel accuracy,
and drawn as coloured label maps with their legend and as a training curve. A trained
network is the ``Segmenter`` port type (widths + weights + class names + curve), so it is
cached and crosses processes.
"""

from ._draw import class_colours, draw_curve, draw_labels
from ._evaluate import SegmentationScores, class_iou, confusion_matrix, evaluate
from ._model import Segmenter, SegmenterModel, SegmenterPort
from ._train import class_weights, fit_unet, predict, train
from ._unet import Conv, MaxPool, Relu, UNet, UpConv, build_unet, pixel_cross_entropy

__all__ = [
    "Conv",
    "MaxPool",
    "Relu",
    "SegmentationScores",
    "Segmenter",
    "SegmenterModel",
    "SegmenterPort",
    "UNet",
    "UpConv",
    "build_unet",
    "class_colours",
    "class_iou",
    "class_weights",
    "confusion_matrix",
    "draw_curve",
    "draw_labels",
    "evaluate",
    "fit_unet",
    "pixel_cross_entropy",
    "predict",
    "train",
]
