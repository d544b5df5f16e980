"""Annotations for node signatures: value types for type checkers, port types for the registry.

Each name is an :data:`typing.Annotated` alias whose first argument is the
value's Python type and whose metadata is the port type::

    GrayImage = Annotated[NDArray[np.float32], GrayImagePort]

A type checker (mypy, an editor) sees ``NDArray[np.float32]`` and checks the
node's body and its callers; the registry reads ``GrayImagePort`` to check
edges, validate values and encode them. So a node is written once::

    @node("mine.darken")
    def darken(image: GrayImage, *, factor: float = 0.5) -> GrayImage:
        '''image × factor.'''
        return (image * np.float32(factor)).astype(np.float32)

**Generic nodes.** The type variables below are *constrained*: their
constraints list the specific port types first, so the registry binds a
connected ``GrayImage`` to ``GrayImage`` and the output follows (a gray image
in, a gray image out, checked before the run), while the type checker sees
one array type and accepts a body that returns a new array. A value of a port
type outside the list binds to the first constraint it is a subtype of.

**Adding a type.** Subclass a port class (:class:`~graphvision.ArrayPort`,
:class:`~graphvision.RecordPort`, ...) with a name ending in ``Port`` and
publish an alias beside it; the alias is what signatures use and the class
name without ``Port`` is what pipeline files say. :func:`port_of` turns an
alias (or a port class) into its port class.
"""

from __future__ import annotations

import typing
from typing import Annotated, Any, TypeVar, get_args, get_origin

import numpy as np
from numpy.typing import NDArray

from graphvision.values.geometry import DescriptorsPort, HomographyPort, Points2DPort, Points3DPort
from graphvision.values.images import (
    BinaryImagePort,
    ColorImagePort,
    FloatImagePort,
    GrayImagePort,
    ImagePort,
    KernelPort,
    LabelImagePort,
)
from graphvision.values.ports import ArrayPort, PortType
from graphvision.values.records import (
    BoxesPort,
    BoxSet,
    CameraPort,
    KeypointSet,
    KeypointsPort,
    MatchesPort,
    MatchSet,
    PinholeCamera,
)
from graphvision.values.scalars import BoolPort, FloatPort, IntPort, TablePort, TextPort

__all__ = [
    "AnyImageT",
    "Array",
    "BinaryImage",
    "Bool",
    "Boxes",
    "Camera",
    "ColorImage",
    "Descriptors",
    "Float",
    "FloatImage",
    "GrayImage",
    "Homography",
    "Image",
    "ImageT",
    "Int",
    "Kernel",
    "Keypoints",
    "LabelImage",
    "Matches",
    "Points2D",
    "Points3D",
    "Table",
    "Text",
    "port_of",
]

Array = Annotated[NDArray[Any], ArrayPort]
FloatImage = Annotated[NDArray[np.float32], FloatImagePort]
Image = Annotated[NDArray[np.float32], ImagePort]
GrayImage = Annotated[NDArray[np.float32], GrayImagePort]
ColorImage = Annotated[NDArray[np.float32], ColorImagePort]
BinaryImage = Annotated[NDArray[np.bool_], BinaryImagePort]
LabelImage = Annotated[NDArray[np.int32], LabelImagePort]
Kernel = Annotated[NDArray[np.float64], KernelPort]
Points2D = Annotated[NDArray[np.float64], Points2DPort]
Points3D = Annotated[NDArray[np.float64], Points3DPort]
Descriptors = Annotated[NDArray[np.float32], DescriptorsPort]
Homography = Annotated[NDArray[np.float64], HomographyPort]
Keypoints = Annotated[KeypointSet, KeypointsPort]
Matches = Annotated[MatchSet, MatchesPort]
Camera = Annotated[PinholeCamera, CameraPort]
Boxes = Annotated[BoxSet, BoxesPort]
Float = Annotated[float, FloatPort]
Int = Annotated[int, IntPort]
Bool = Annotated[bool, BoolPort]
Text = Annotated[str, TextPort]
Table = Annotated[dict[str, NDArray[Any]], TablePort]

ImageT = TypeVar("ImageT", GrayImage, ColorImage, Image)
"""An intensity image whose kind (gray, colour, either) the output keeps."""

AnyImageT = TypeVar("AnyImageT", GrayImage, ColorImage, Image, FloatImage)
"""Any float image, intensities or filter responses, kept from input to output."""


def port_of(annotation: Any) -> type[PortType] | None:
    """The port class an annotation names, or None.

    Accepts an alias of this module (or any ``Annotated[..., SomePort]``) and,
    for plugins written before the aliases existed, a bare port class.

    >>> port_of(GrayImage).type_name()
    'GrayImage'
    """
    if get_origin(annotation) is typing.Annotated:
        found = [item for item in get_args(annotation)[1:] if _is_port_class(item)]
        return found[0] if found else None
    return annotation if _is_port_class(annotation) else None


def _is_port_class(obj: Any) -> bool:
    return isinstance(obj, type) and issubclass(obj, PortType) and obj is not PortType
