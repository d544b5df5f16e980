"""Classical recognition and detection (seed: "Recognition & Detection", "Recognition
using local features: Bag of words model"): labelled sample sets, PCA and dual PCA,
1-nearest-neighbour, HOG, integral images and Haar-like features, AdaBoost and the
Viola–Jones cascade, a linear SVM, sliding-window detection with non-maximum
suppression, and the bag-of-words model. Trained models are port types, among them
an LBP cascade read from OpenCV's XML format (``recognition.lbp_cascade``) and
evaluated on graphvision's own integral images; face detectors are measured on scenes
with known faces (``synthetic.face_scenes``).
"""

from ._boost import adaboost, boost_stumps, cascade, cascade_table, train_cascade
from ._bow import bag_of_words, dense_sift, fit_kmeans, kmeans, nearest_word
from ._classify import accuracy, predict
from ._data import (
    augment,
    combine,
    lfw_faces,
    negative_patches,
    pixel_features,
    pixels,
    texture_patches,
)
from ._detect import (
    box_count,
    box_iou,
    detect,
    detect_subspace,
    draw_boxes,
    iou_matrix,
    mine_negatives,
    nms,
    non_max_suppression,
)
from ._draw import draw_predictions, prediction_mosaic, predictions
from ._faces import detect_scenes, draw_scenes, face_scores, lbp_detect_scenes
from ._haar import (
    HAAR_TYPES,
    haar,
    haar_corners,
    haar_feature_table,
    haar_values,
    integral_image,
    integral_image_node,
    sample_haar_features,
)
from ._hog import hog, hog_cells, hog_features, hog_picture
from ._lbp_cascade import lbp_cascade, lbp_detect
from ._lbp_model import LBPCascade, LBPCascadeModel, LBPCascadePort
from ._models import (
    CascadePort,
    ClassifierPort,
    LinearClassifierPort,
    NearestClassifierPort,
    StumpClassifierPort,
)
from ._opencv_cascade import parse_opencv_cascade, read_opencv_cascade
from ._scenes import SceneBoxes, SceneBoxesPort, SceneBoxSet, SceneImages, SceneImagesPort
from ._subspace import fit_pca, nearest_neighbour, pca, project, reconstruction_error, residual
from ._svm import fit_linear_svm, linear_svm
from ._types import BagsPort, FeaturesPort, SamplesPort, SubspacePort, VocabularyPort, mosaic

__all__ = [
    "HAAR_TYPES",
    "BagsPort",
    "CascadePort",
    "ClassifierPort",
    "FeaturesPort",
    "LBPCascade",
    "LBPCascadeModel",
    "LBPCascadePort",
    "LinearClassifierPort",
    "NearestClassifierPort",
    "SamplesPort",
    "SceneBoxSet",
    "SceneBoxes",
    "SceneBoxesPort",
    "SceneImages",
    "SceneImagesPort",
    "StumpClassifierPort",
    "SubspacePort",
    "VocabularyPort",
    "accuracy",
    "adaboost",
    "augment",
    "bag_of_words",
    "boost_stumps",
    "box_count",
    "box_iou",
    "cascade",
    "cascade_table",
    "combine",
    "dense_sift",
    "detect",
    "detect_scenes",
    "detect_subspace",
    "draw_boxes",
    "draw_predictions",
    "draw_scenes",
    "face_scores",
    "fit_kmeans",
    "fit_linear_svm",
    "fit_pca",
    "haar",
    "haar_corners",
    "haar_feature_table",
    "haar_values",
    "hog",
    "hog_cells",
    "hog_features",
    "hog_picture",
    "integral_image",
    "integral_image_node",
    "iou_matrix",
    "kmeans",
    "lbp_cascade",
    "lbp_detect",
    "lbp_detect_scenes",
    "lfw_faces",
    "linear_svm",
    "mine_negatives",
    "mosaic",
    "nearest_neighbour",
    "nearest_word",
    "negative_patches",
    "nms",
    "non_max_suppression",
    "parse_opencv_cascade",
    "pca",
    "pixel_features",
    "pixels",
    "predict",
    "prediction_mosaic",
    "predictions",
    "project",
    "read_opencv_cascade",
    "reconstruction_error",
    "residual",
    "sample_haar_features",
    "texture_patches",
    "train_cascade",
]
