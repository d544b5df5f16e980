"""Detection by feature constellations (Lowe 2004, section 7): every instance of a model
image in a scene, from SIFT matches voting for the model's pose in a generalised Hough
space, each vote cluster verified by an affine then a homography fit.

The stages, each a function in a module of its own (``_model_views``, ``_votes``,
``_verify``, ``_probability``, ``_polygons``) and the nodes here:

0. **Model views** (:func:`model_views`): SIFT features of the model and of views of
   it simulated at larger tilts (:func:`simulate_view`; Morel & Yu's affine
   simulation, or Lowe's "multiple training views" of an object), each feature
   knowing its position in the model and its view's map to the model. A SIFT
   descriptor survives some 30° to 45° out of plane; the views carry the model to 60°.
1. **Match** (:func:`match_to_model`) every scene feature to its nearest model feature
   by the ratio test against the nearest one *from another place* of the model (Lowe's
   rule for several training views of one object). The direction matters: with several
   instances a model feature has several equally good scene neighbours, so the model →
   scene ratio test and a symmetric check (``matching.match``, the single-object
   recipe) would keep at most one of them.
2. **Vote** (:func:`pose_votes`): each match predicts the model's pose from its two
   keypoints' scales, orientations and positions, and votes in the 2 closest bins of
   each of the 4 dimensions (16 bins) of a hash table, one table per view.
3. **Verify** (:func:`verify_cluster`) each bin with at least ``min_votes`` votes,
   largest first: RANSAC on an affine map, matches gathered top-down from all the
   matches agreeing with it in position, orientation and scale, then RANSAC on a
   homography, gathered and refitted (DLT, then Levenberg-Marquardt) until the inlier
   set is stable.
4. **Accept** by Lowe's probability that the agreeing matches are not chance
   (:func:`pose_probability`) and suppress overlapping instances (polygon IoU).

Instances are the model's corners mapped by the homography (pixel centres (0, 0),
(w-1, 0), (w-1, h-1), (0, h-1), as ``synthetic.object_scenes`` draws them).
"""

from __future__ import annotations

from typing import Annotated, Any, NamedTuple

import numpy as np
from pydantic import Field

from graphvision import Array, FloatImage, GrayImage, node

from ..features import sift
from ..shared.params import Fraction, Probability, Seed
from ..synthetic import ObjectScenes
from ._instances import Instances, InstanceSet
from ._model_views import ConstellationParams, ModelViews, match_to_model, model_views
from ._verify import locate_instances
from ._votes import vote_picture

__all__ = [
    "FoundInScenes",
    "FoundInstances",
    "find_instances",
    "find_instances_in_scenes",
]


Tilts = Annotated[
    list[Annotated[float, Field(ge=1.0, le=8.0)]],
    Field(max_length=8, description="Tilts t = 1/cos θ of the simulated model views."),
]
Ratio = Annotated[float, Field(gt=0, le=1, description="Lowe's ratio of nearest distances.")]
SamePlace = Annotated[
    float, Field(ge=0, le=100, description="Model pixels within which two features are one place.")
]
OrientationBin = Annotated[float, Field(ge=1, le=180, description="Orientation bin, degrees.")]
ScaleBin = Annotated[float, Field(gt=1, le=8, description="Scale bin, a factor.")]
LocationBin = Annotated[
    float, Field(gt=0, le=4, description="Location bin, in model sides at the predicted scale.")
]
MinVotes = Annotated[
    int, Field(ge=3, le=1000, description="Fewest votes of a bin worth verifying.")
]
Threshold = Annotated[float, Field(gt=0, le=100, description="Inlier distance, scene pixels.")]
Tolerance = Annotated[float, Field(gt=0, le=180, description="Orientation agreement, degrees.")]
ScaleTolerance = Annotated[float, Field(gt=1, le=8, description="Scale agreement, a factor.")]
MinInliers = Annotated[
    int, Field(ge=5, le=10_000, description="Fewest distinct inliers of an instance.")
]
MaxClusters = Annotated[int, Field(ge=1, le=100_000, description="Most bins verified per scene.")]
VoteCell = Annotated[int, Field(ge=1, le=64, description="Pixels per cell of the vote picture.")]


def _params(**values: Any) -> ConstellationParams:
    return ConstellationParams(**values)


class FoundInstances(NamedTuple):
    instances: Instances
    votes: FloatImage


class FoundInScenes(NamedTuple):
    instances: Instances
    votes: Array


def _find(
    views: ModelViews, scene: np.ndarray, params: ConstellationParams, cell: int
) -> tuple[InstanceSet, np.ndarray]:
    found = sift(scene)
    pairs = match_to_model(found.descriptors, views, params.ratio, params.same_place)
    instances, votes = locate_instances(views, found.keypoints, pairs, scene.shape, params)
    return instances, vote_picture(votes, scene.shape, cell)


@node("matching.find_instances", version=1)
def find_instances(
    model: GrayImage,
    scene: GrayImage,
    *,
    tilts: Tilts = [1.414, 2.0],  # noqa: B006
    ratio: Ratio = 0.8,
    same_place: SamePlace = 3.0,
    orientation_bin: OrientationBin = 30.0,
    scale_bin: ScaleBin = 2.0,
    location_bin: LocationBin = 0.25,
    min_votes: MinVotes = 3,
    threshold: Threshold = 3.0,
    orientation_tolerance: Tolerance = 30.0,
    scale_tolerance: ScaleTolerance = 2.0,
    min_inliers: MinInliers = 8,
    min_probability: Probability = 0.98,
    prior: Probability = 0.01,
    nms_iou: Fraction = 0.2,
    max_clusters: MaxClusters = 300,
    vote_cell: VoteCell = 4,
    seed: Seed = 0,
) -> FoundInstances:
    r"""Every instance of ``model`` in ``scene``: detection by feature constellations
    (Lowe 2004, section 7).

    1. SIFT features (``features.sift``) of the model, of simulated views of it tilted
       by each of ``tilts`` (so that features survive 60° out of plane: Morel & Yu's
       affine simulation, Lowe's multiple training views) and of the scene;
    2. each scene feature matched to its nearest model feature by the ratio test against
       the nearest model feature from another place (section 7.1);
    3. each match votes for the pose :math:`(x, y, \log s, \phi)` of the model in its
       view, :math:`s = \sigma_i/\sigma_j`, :math:`\phi = \theta_i - \theta_j`,
       :math:`r = x_i + s R(\phi)(c - u_j)`, in the 2 closest bins of each dimension
       (section 7.3);
    4. each bin with at least ``min_votes`` votes is verified: RANSAC on an affine map,
       matches gathered top-down, RANSAC on a homography, outliers removed and the fit
       repeated (section 7.4's least squares, then Levenberg-Marquardt);
    5. accepted when :math:`P(m \mid f) = P(m) / (P(m) + P(f \mid \neg m)(1 - P(m)))`
       reaches ``min_probability``, :math:`P(f \mid \neg m)` the binomial tail of the
       inliers among the scene features inside the projected model (section 7.4); of
       overlapping instances the better supported stays.

    Parameters
    ----------
    model : GrayImage
        The object's picture (a planar object: its instances are homographies of it).
    scene : GrayImage
        The picture to search.
    tilts : list of float
        Tilts :math:`t = 1 / \cos\theta` of the simulated views of the model, each in
        ASIFT's directions (the model itself is always a view). [] is Lowe's single
        training view; [1.414, 2] adds 45° and 60° out of plane.
    ratio : float
        Lowe's ratio test, against the nearest model feature from another place.
    same_place : float
        Model pixels within which two model features count as one place.
    orientation_bin, scale_bin, location_bin : float
        Hough bins: degrees; a factor; model sides at the predicted scale (Lowe: 30°, 2,
        0.25).
    min_votes : int
        Fewest votes of a bin that is verified (Lowe: 3).
    threshold : float
        Inlier distance of the homography, scene pixels.
    orientation_tolerance, scale_tolerance : float
        An inlier's orientation and scale agree with the pose within these (degrees, a
        factor).
    min_inliers : int
        Fewest distinct inlier positions of an accepted instance.
    min_probability : float
        Least :math:`P(m \mid f)` of an accepted instance (Lowe: 0.98).
    prior : float
        :math:`P(m)`, the prior probability of a pose hypothesis.
    nms_iou : float
        Of two instances overlapping by more (polygon IoU), the one with fewer inliers
        is dropped.
    max_clusters : int
        Most Hough bins verified per scene, largest first.
    vote_cell : int
        Scene pixels per cell of the vote picture.
    seed : int
        Seed of the RANSAC samples.
    Returns
    -------
    instances : Instances
        One row per instance: the model's corners in the scene, the homography, the
        inlier count and :math:`P(m \mid f)`; best supported first.
    votes : FloatImage
        The Hough table seen from above: per ``vote_cell`` × ``vote_cell`` block of the
        scene, the most votes of a bin covering it (over view, scale and orientation).

    References
    ----------
    .. [1] D. G. Lowe, "Distinctive image features from scale-invariant keypoints",
       IJCV 60(2), 2004, section 7.
    .. [2] J.-M. Morel, G. Yu, "ASIFT: a new framework for fully affine invariant image
       comparison", SIAM J. Imaging Sciences 2(2), 2009 (simulated tilts).
    .. [3] D. H. Ballard, "Generalizing the Hough transform to detect arbitrary shapes",
       Pattern Recognition 13(2), 1981.
    """
    params = _params(
        ratio=ratio,
        same_place=same_place,
        orientation_bin=orientation_bin,
        scale_bin=scale_bin,
        location_bin=location_bin,
        min_votes=min_votes,
        threshold=threshold,
        orientation_tolerance=orientation_tolerance,
        scale_tolerance=scale_tolerance,
        min_inliers=min_inliers,
        min_probability=min_probability,
        prior=prior,
        nms_iou=nms_iou,
        max_clusters=max_clusters,
        seed=seed,
    )
    _check_model(model)
    views = model_views(model, tilts, {})
    instances, votes = _find(views, scene, params, vote_cell)
    return FoundInstances(instances, votes)


def _check_model(model: np.ndarray) -> None:
    if min(model.shape) < 16:
        raise ValueError(
            f"the model is {model.shape[1]}×{model.shape[0]} pixels: at least 16×16 is needed "
            "for SIFT to find features in it"
        )


@node("matching.find_instances_in_scenes", version=1)
def find_instances_in_scenes(
    model: GrayImage,
    scenes: ObjectScenes,
    *,
    tilts: Tilts = [1.414, 2.0],  # noqa: B006
    ratio: Ratio = 0.8,
    same_place: SamePlace = 3.0,
    orientation_bin: OrientationBin = 30.0,
    scale_bin: ScaleBin = 2.0,
    location_bin: LocationBin = 0.25,
    min_votes: MinVotes = 3,
    threshold: Threshold = 3.0,
    orientation_tolerance: Tolerance = 30.0,
    scale_tolerance: ScaleTolerance = 2.0,
    min_inliers: MinInliers = 8,
    min_probability: Probability = 0.98,
    prior: Probability = 0.01,
    nms_iou: Fraction = 0.2,
    max_clusters: MaxClusters = 300,
    vote_cell: VoteCell = 4,
    seed: Seed = 0,
) -> FoundInScenes:
    r"""``matching.find_instances`` in every scene of a set: the model's views are
    described once, each scene in turn.

    Parameters
    ----------
    model : GrayImage
        The object's picture.
    scenes : ObjectScenes
        The scenes to search (their true instances are not used).
    tilts : list of float
        Tilts :math:`t = 1 / \cos\theta` of the simulated views of the model, each in
        ASIFT's directions (the model itself is always a view). [] is Lowe's single
        training view; [1.414, 2] adds 45° and 60° out of plane.
    ratio : float
        Lowe's ratio test, against the nearest model feature from another place.
    same_place : float
        Model pixels within which two model features count as one place.
    orientation_bin, scale_bin, location_bin : float
        Hough bins: degrees; a factor; model sides at the predicted scale (Lowe: 30°, 2,
        0.25).
    min_votes : int
        Fewest votes of a bin that is verified (Lowe: 3).
    threshold : float
        Inlier distance of the homography, scene pixels.
    orientation_tolerance, scale_tolerance : float
        An inlier's orientation and scale agree with the pose within these (degrees, a
        factor).
    min_inliers : int
        Fewest distinct inlier positions of an accepted instance.
    min_probability : float
        Least :math:`P(m \mid f)` of an accepted instance (Lowe: 0.98).
    prior : float
        :math:`P(m)`, the prior probability of a pose hypothesis.
    nms_iou : float
        Of two instances overlapping by more (polygon IoU), the one with fewer inliers
        is dropped.
    max_clusters : int
        Most Hough bins verified per scene, largest first.
    vote_cell : int
        Scene pixels per cell of the vote picture.
    seed : int
        Seed of the RANSAC samples.
    Returns
    -------
    instances : Instances
        The instances of all scenes, ``owner`` the scene of each.
    votes : Array
        (N, ceil(H / vote_cell), ceil(W / vote_cell)) float32, each scene's vote picture.

    References
    ----------
    .. [1] D. G. Lowe, "Distinctive image features from scale-invariant keypoints",
       IJCV 60(2), 2004, section 7.
    """
    params = _params(
        ratio=ratio,
        same_place=same_place,
        orientation_bin=orientation_bin,
        scale_bin=scale_bin,
        location_bin=location_bin,
        min_votes=min_votes,
        threshold=threshold,
        orientation_tolerance=orientation_tolerance,
        scale_tolerance=scale_tolerance,
        min_inliers=min_inliers,
        min_probability=min_probability,
        prior=prior,
        nms_iou=nms_iou,
        max_clusters=max_clusters,
        seed=seed,
    )
    _check_model(model)
    views = model_views(model, tilts, {})
    parts, pictures = [], []
    for index, scene in enumerate(scenes.images):
        instances, picture = _find(views, scene, params, vote_cell)
        parts.append(
            InstanceSet(
                instances.quads,
                instances.homographies,
                instances.inliers,
                instances.probability,
                np.full(len(instances), index, np.int64),
                len(scenes),
            )
        )
        pictures.append(picture)
    return FoundInScenes(InstanceSet.concatenate(parts, len(scenes)), np.stack(pictures))
