"""The port types the engine defines, in one list (the registry starts from it)."""

from __future__ import annotations

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
from graphvision.values.records import BoxesPort, CameraPort, KeypointsPort, MatchesPort
from graphvision.values.scalars import BoolPort, FloatPort, IntPort, TablePort, TextPort

__all__ = ["builtin_port_types"]


def builtin_port_types() -> list[type[PortType]]:
    """The port types the engine defines (plugins may register more)."""
    return [
        ArrayPort,
        FloatImagePort,
        ImagePort,
        GrayImagePort,
        ColorImagePort,
        BinaryImagePort,
        LabelImagePort,
        KernelPort,
        Points2DPort,
        Points3DPort,
        DescriptorsPort,
        HomographyPort,
        KeypointsPort,
        MatchesPort,
        CameraPort,
        BoxesPort,
        FloatPort,
        IntPort,
        BoolPort,
        TextPort,
        TablePort,
    ]
