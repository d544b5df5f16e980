"""Photographs with known faces: scikit-image's photographs with lfw faces pasted at seeded
boxes, and the astronaut with the face she shows (seeded; every face's box is known).

A pasted face is one of the 100 faces of scikit-image's ``lfw_subset`` (25 × 25 crops of
Labeled Faces in the Wild), enlarged bilinearly to a square of ``min_side`` to
``max_side`` pixels and pasted, gray, into the photograph where it overlaps no other
face (each face's box grown by a quarter of its side stays clear of the others). Its
true box is the pasted square. By default the faces come from the 25 that
``recognition.lfw_faces`` holds out (seed 0, test fraction 0.25), so that a detector
trained on the other 75 is measured on faces it never saw.

The photographs other than the astronaut show no human face (the cameraman of
``camera`` does, in three-quarter view: it is left out). The astronaut's face box,
:data:`ASTRONAUT_FACE`, is not drawn by hand: it is the mean box of OpenCV's four Haar
frontal-face cascades on the gray astronaut (detectors other than the LBP cascade
graphvision evaluates), recorded with the calls that gave them; the mirrored
astronaut's box is its mirror image.
"""

from __future__ import annotations

from typing import Annotated, Literal, NamedTuple

import numpy as np
from pydantic import Field

from graphvision import Boxes, BoxSet, ColorImage, node

from ..recognition._scenes import SceneBoxes, SceneBoxSet, SceneImages
from ..shared.checks import all_of, ordered, to_float_image
from ..shared.params import Seed

__all__ = [
    "ASTRONAUT_FACE",
    "FaceCollage",
    "FacePhoto",
    "FaceScenes",
    "face_collage",
    "face_scenes",
    "paste_faces",
    "photograph",
]

ASTRONAUT_FACE = (176.25, 65.25, 274.25, 163.25)
"""The astronaut's face (x0, y0, x1, y1) in ``skimage.data.astronaut()`` (512 × 512),
measured without a hand: the mean of the boxes OpenCV 4.10's four Haar frontal-face
cascades find on the gray astronaut (``cv2.CascadeClassifier(cv2.data.haarcascades +
name).detectMultiScale(cv2.cvtColor(astronaut, cv2.COLOR_RGB2GRAY), 1.1, 3)``, (x, y,
w, h)): ``haarcascade_frontalface_default.xml`` (177, 66, 95, 95), ``_alt`` (176, 65,
98, 98), ``_alt2`` (177, 66, 97, 97), ``_alt_tree`` (175, 64, 102, 102). Haar-like
features and other training data than the LBP cascade graphvision evaluates; the four
agree within 2 px on the corner and 7 px on the side."""

FacePhoto = Literal[
    "astronaut",
    "astronaut_mirrored",
    "chelsea",
    "clock",
    "coffee",
    "coins",
    "hubble_deep_field",
    "immunohistochemistry",
    "moon",
    "motorcycle",
    "retina",
    "rocket",
]
"""Photographs scikit-image ships (offline); ``motorcycle`` is the left view of
``stereo_motorcycle``, ``astronaut_mirrored`` the astronaut mirrored left to right."""

LfwFaces = Literal["test", "train", "all"]

FACE_FREE_MARGIN = 0.25
"""A pasted face keeps this fraction of its side clear of every other face."""


def photograph(name: str) -> tuple[np.ndarray, np.ndarray]:
    """A photograph as float32 RGB (gray ones repeated) and the boxes (K, 4) of the faces
    it shows."""
    import skimage.data

    if name == "motorcycle":
        data = skimage.data.stereo_motorcycle()[0]
    else:
        data = getattr(skimage.data, name.removesuffix("_mirrored"))()
    image = to_float_image(data, source=f"sample '{name}'")
    if image.ndim == 2:
        image = np.repeat(image[..., None], 3, axis=2)
    faces = np.array([ASTRONAUT_FACE] if name.startswith("astronaut") else [], np.float64)
    faces = faces.reshape(-1, 4)
    if name.endswith("_mirrored"):
        width = image.shape[1]
        image = image[:, ::-1]
        faces = np.column_stack(
            [width - faces[:, 2], faces[:, 1], width - faces[:, 0], faces[:, 3]]
        )
    return np.ascontiguousarray(image, np.float32), faces


def lfw_face_images(which: str) -> np.ndarray:
    """The faces of ``lfw_subset`` (N, 25, 25) float64 in [0, 1]: all 100, or the 25 that
    ``recognition.lfw_faces`` holds out with its defaults (``test``), or the other 75."""
    from skimage.data import lfw_subset

    from ..recognition._data import FACE, stratified_split

    images = lfw_subset()
    labels = np.where(np.arange(len(images)) < 100, FACE, 1 - FACE)
    if which == "all":
        return images[:100]
    train, test = stratified_split(labels, 0.25, 0)
    chosen = test if which == "test" else train
    return images[chosen[labels[chosen] == FACE]]


def _clear(box: np.ndarray, taken: list[np.ndarray]) -> bool:
    for other in taken:
        margin = FACE_FREE_MARGIN * max(box[2] - box[0], other[2] - other[0])
        if not (
            box[0] >= other[2] + margin
            or other[0] >= box[2] + margin
            or box[1] >= other[3] + margin
            or other[1] >= box[3] + margin
        ):
            return False
    return True


def paste_faces(
    image: np.ndarray,
    known: np.ndarray,
    faces: np.ndarray,
    count: int,
    sides: tuple[int, int],
    rng: np.random.Generator,
) -> tuple[np.ndarray, np.ndarray]:
    """``image`` (H, W, 3) with ``count`` of ``faces`` (N, h, w) (drawn without
    replacement) pasted as squares of ``sides`` (min, max) pixels, clear of the ``known``
    boxes and of each other (fewer when 100 random places were all taken); returns the
    image and every face's box, known ones first."""
    from skimage.transform import resize

    height, width = image.shape[:2]
    out = image.copy()
    taken = [np.asarray(box, np.float64) for box in known]
    picks = rng.choice(len(faces), size=min(count, len(faces)), replace=False)
    for pick in picks:
        side = int(rng.integers(sides[0], sides[1] + 1))
        if side > min(height, width):
            continue
        for _attempt in range(100):
            top = int(rng.integers(0, height - side + 1))
            left = int(rng.integers(0, width - side + 1))
            box = np.array([left, top, left + side, top + side], np.float64)
            if _clear(box, taken):
                face = np.clip(resize(faces[pick], (side, side), order=1), 0, 1)
                out[top : top + side, left : left + side] = face[..., None]
                taken.append(box)
                break
    return out, np.array(taken, np.float64).reshape(-1, 4)


class FaceCollage(NamedTuple):
    image: ColorImage
    faces: Boxes


_sides = ordered(("min_side", "max_side"))


@node("synthetic.face_collage", version=1, check=_sides)
def face_collage(
    *,
    photo: FacePhoto = "chelsea",
    faces: Annotated[int, Field(ge=0, le=100)] = 3,
    min_side: Annotated[int, Field(ge=8, le=512)] = 40,
    max_side: Annotated[int, Field(ge=8, le=512)] = 120,
    lfw: LfwFaces = "test",
    seed: Seed = 0,
) -> FaceCollage:
    """A photograph with ``faces`` lfw faces pasted at seeded boxes, and the box of every
    face in it (the pasted ones and those the photograph shows: the astronaut's).

    Each pasted face is an lfw crop enlarged bilinearly to a square of side
    :math:`s \\sim \\mathcal{U}\\{s_{min}, \\dots, s_{max}\\}` at a uniformly drawn
    position where its box, grown by :math:`s/4`, meets no other face (fewer faces when
    100 tries find no such place, or when a drawn side exceeds the photograph's). The
    truth of a detector is then known exactly: recall and false positives are counted
    against these boxes at IoU ≥ 0.5, the PASCAL criterion.

    Parameters
    ----------
    photo : str
        One of scikit-image's photographs (see :data:`FacePhoto`).
    faces : int
        Faces pasted (the astronaut's own face is always there).
    min_side, max_side : int
        Smallest and largest side of a pasted face, in pixels.
    lfw : {'test', 'train', 'all'}
        Paste the 25 faces ``recognition.lfw_faces`` holds out (seed 0), its 75 training
        faces, or all 100.
    seed : int
        Seed of the faces drawn, their sides and positions.

    Returns
    -------
    image : ColorImage
        The photograph (H, W, 3) float32 with the faces pasted.
    faces : Boxes
        Every face's box (x0, y0, x1, y1), score 1.

    References
    ----------
    G. B. Huang, M. Ramesh, T. Berg and E. Learned-Miller, "Labeled Faces in the Wild",
    UMass TR 07-49, 2007; M. Everingham et al., "The PASCAL visual object classes (VOC)
    challenge", IJCV 88(2), 2010.
    """
    image, known = photograph(photo)
    rng = np.random.default_rng(seed)
    pasted, boxes = paste_faces(
        image, known, lfw_face_images(lfw), faces, (min_side, max_side), rng
    )
    return FaceCollage(pasted, BoxSet(boxes, np.ones(len(boxes))))


def _fit(image: np.ndarray, boxes: np.ndarray, side: int) -> tuple[np.ndarray, np.ndarray]:
    """``image`` scaled to cover ``side`` × ``side`` (anti-aliased) and centre-cropped, with
    its boxes moved along (clipped to the crop; those left with less than half their area
    are dropped)."""
    from skimage.transform import resize

    height, width = image.shape[:2]
    scale = side / min(height, width)
    size = (max(side, round(height * scale)), max(side, round(width * scale)))
    if size != (height, width):
        image = resize(image, size, order=1, anti_aliasing=scale < 1)
    top, left = (size[0] - side) // 2, (size[1] - side) // 2
    crop = image[top : top + side, left : left + side]
    moved = boxes * np.array([size[1] / width, size[0] / height] * 2)
    moved -= np.array([left, top, left, top], np.float64)
    clipped = np.clip(moved, 0, side)
    area = np.prod(moved[:, 2:] - moved[:, :2], axis=1)
    kept = np.prod(clipped[:, 2:] - clipped[:, :2], axis=1) >= 0.5 * area
    return np.ascontiguousarray(crop, np.float32), clipped[kept]


class FaceScenes(NamedTuple):
    images: SceneImages
    faces: SceneBoxes


DEFAULT_PHOTOS: tuple[FacePhoto, ...] = (
    "astronaut",
    "astronaut_mirrored",
    "chelsea",
    "coffee",
    "rocket",
    "motorcycle",
)


@node(
    "synthetic.face_scenes",
    version=1,
    check=all_of(_sides, ordered(("min_faces", "max_faces"), ("max_side", "side"))),
)
def face_scenes(
    *,
    photos: Annotated[tuple[FacePhoto, ...], Field(min_length=1, max_length=256)] = DEFAULT_PHOTOS,
    min_faces: Annotated[int, Field(ge=0, le=100)] = 1,
    max_faces: Annotated[int, Field(ge=0, le=100)] = 3,
    min_side: Annotated[int, Field(ge=8, le=512)] = 40,
    max_side: Annotated[int, Field(ge=8, le=512)] = 120,
    side: Annotated[int, Field(ge=32, le=1024)] = 512,
    lfw: LfwFaces = "test",
    seed: Seed = 0,
) -> FaceScenes:
    """Gray scenes with known faces for measuring a face detector: each photograph scaled
    to cover ``side`` × ``side`` and centre-cropped (the astronaut, 512 × 512, is left as
    it is) and, unless it shows a face of its own (the astronaut), given
    ``min_faces``…``max_faces`` pasted lfw faces as ``synthetic.face_collage`` pastes
    them (after the scaling, so their sides are as drawn).

    Gray is the channel mean, :math:`I = (R + G + B) / 3`.

    Parameters
    ----------
    photos : tuple of str
        One scene per photograph, in this order (repeats allowed: each draws new faces).
    min_faces, max_faces : int
        Faces pasted per photograph without a face of its own.
    min_side, max_side : int
        Sides of the pasted faces in scene pixels.
    side : int
        Side of every (square) scene.
    lfw : {'test', 'train', 'all'}
        Which lfw faces are pasted (see ``synthetic.face_collage``).
    seed : int
        Seed of the faces, their number, sides and positions.

    Returns
    -------
    images : SceneImages
        The scenes (N, side, side) float32.
    faces : SceneBoxes
        Every face's box, score 1, with the scene it is in.

    References
    ----------
    G. B. Huang et al., "Labeled Faces in the Wild", UMass TR 07-49, 2007.
    """
    rng = np.random.default_rng(seed)
    faces = lfw_face_images(lfw)
    images, boxes, owners = [], [], []
    for index, name in enumerate(photos):
        image, known = _fit(*photograph(name), side)
        count = 0 if len(known) else int(rng.integers(min_faces, max_faces + 1))
        image, placed = paste_faces(image, known, faces, count, (min_side, max_side), rng)
        images.append(image.mean(axis=2))
        boxes.append(placed)
        owners.append(np.full(len(placed), index, np.int64))
    xyxy = np.concatenate(boxes)
    truth = SceneBoxSet(xyxy, np.ones(len(xyxy)), np.concatenate(owners), len(photos))
    return FaceScenes(np.asarray(images, np.float32), truth)
