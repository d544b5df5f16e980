"""A node called directly takes what ``gv.run`` takes (issue 29, item 12): its inputs go
through the same dtype policy as graph inputs, so a ``uint8`` photo (OpenCV, imageio) is the
image its PNG gives, in a notebook as in a run."""

from __future__ import annotations

import numpy as np
import pytest

import graphvision as gv
from graphvision.values.images import BinaryImagePort, ColorImagePort, FloatImagePort
from graphvision_plugins import colour, filters, regions

RNG = np.random.default_rng(29)
GRAY8 = (RNG.random((20, 24)) * 255).astype(np.uint8)
RGB8 = (RNG.random((20, 24, 3)) * 255).astype(np.uint8)
MASK8 = np.where(RNG.random((20, 24)) > 0.5, 255, 0).astype(np.uint8)  # a mask saved as PNG


def _uint8_for(port: gv.PortType | type) -> np.ndarray:
    if isinstance(port, type) and issubclass(port, BinaryImagePort):
        return MASK8
    if isinstance(port, type) and issubclass(port, ColorImagePort):
        return RGB8
    return GRAY8


def test_every_node_checks_a_uint8_image_input_as_the_float_image_it_stands_for(registry):
    """For every node whose inputs are images or masks, a direct call's checks give the node
    the same values for ``uint8`` arrays as for the arrays the dtype policy makes of them."""
    checked = 0
    for op, spec in sorted(registry.nodes.items()):
        ports = {name: port for name, port in spec.inputs.items() if not port.optional}
        kinds = [port.choices[0] if port.choices else port.type for port in ports.values()]
        if not ports or not all(issubclass(k, FloatImagePort | BinaryImagePort) for k in kinds):
            continue
        raw = [_uint8_for(kind) for kind in kinds]
        policy = [
            MASK8 > 0 if issubclass(kind, BinaryImagePort) else gv.to_float_image(array)
            for kind, array in zip(kinds, raw, strict=True)
        ]
        from_uint8, _ = spec.check_call((), dict(zip(ports, raw, strict=True)))
        from_policy, _ = spec.check_call((), dict(zip(ports, policy, strict=True)))
        for name, a, b in zip(spec.inputs, from_uint8, from_policy, strict=True):
            if name in ports:
                assert a.dtype == b.dtype and np.array_equal(a, b), f"{op} input {name}"
        checked += 1
    assert checked >= 40  # the image nodes of the built-in families


@pytest.mark.parametrize(
    ("call", "op", "given"),
    [
        (filters.gaussian, "filters.gaussian", RGB8),
        (colour.to_gray, "colour.to_gray", RGB8),
        (filters.box, "filters.box", GRAY8),
    ],
)
def test_a_direct_call_on_uint8_gives_what_gv_run_gives(registry, call, op, given):
    graph = gv.Graph("one")
    image = graph.input("image", "ColorImage" if given.ndim == 3 else "GrayImage")
    graph.output("out", graph.add("node", op, image=image))
    expected = gv.run(graph, registry, inputs={"image": given}, executor="sync").outputs["out"]
    got = call(given)
    assert np.asarray(got).dtype == np.asarray(expected).dtype
    np.testing.assert_array_equal(got, expected)


def test_a_mask_saved_as_0_255_is_a_mask_in_a_direct_call():
    expected = regions.label(MASK8 > 0)
    np.testing.assert_array_equal(regions.label(MASK8), expected)


@pytest.mark.parametrize(
    ("array", "message"),
    [
        (GRAY8.astype(np.int64), "has dtype int64; expected unsigned integers, bool or float"),
        (GRAY8.astype(np.float64), r"has float values in \[0, \d+\]; expected \[0, 1\]"),
        (np.dstack([GRAY8] * 5), r"must be H×W \(gray\) or H×W×3 \(RGB\), got shape"),
    ],
)
def test_what_the_dtype_policy_refuses_is_named_with_node_and_input(array, message):
    with pytest.raises(gv.PortValueError, match=rf"^filters\.gaussian: input 'image' {message}"):
        filters.gaussian(array)
