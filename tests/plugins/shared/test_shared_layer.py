"""The plugins' shared layer: parameter types and drawing primitives behave the same in
every family that uses them."""

from __future__ import annotations

import numpy as np
import pytest
from pydantic import TypeAdapter, ValidationError

from graphvision_plugins.shared.draw import colour_canvas, draw_circle, draw_segment, plot_points
from graphvision_plugins.shared.params import Count, Fraction, OddSize, Positive, Probability, Seed


@pytest.mark.parametrize(
    ("kind", "good", "bad"),
    [
        (Seed, [0, 7], [-1]),
        (Probability, [0.5, 1e-9], [0.0, 1.0, 1.5]),
        (Fraction, [0.0, 1.0, 0.3], [-0.1, 1.01]),
        (Positive, [1e-9, 3.0], [0.0, -1.0]),
        (Count, [1, 10], [0]),
        (OddSize, [1, 3, 31], [0, 2, 4]),
    ],
)
def test_parameter_types_accept_and_refuse_their_bounds(kind, good, bad):
    adapter = TypeAdapter(kind)
    for value in good:
        assert adapter.validate_python(value) == value
    for value in bad:
        with pytest.raises(ValidationError):
            adapter.validate_python(value)


def test_an_even_size_is_refused_saying_why():
    with pytest.raises(ValidationError, match="must be odd so the window is centred on a pixel"):
        TypeAdapter(OddSize).validate_python(4)


def test_the_canvas_is_a_float32_rgb_copy():
    gray = np.linspace(0, 1, 12, dtype=np.float32).reshape(3, 4)
    canvas = colour_canvas(gray)
    assert canvas.shape == (3, 4, 3) and canvas.dtype == np.float32
    assert (canvas == gray[..., None]).all()
    canvas[0, 0] = 5.0
    assert gray[0, 0] == 0.0  # a copy: drawing never marks the input
    frozen = np.zeros((2, 2, 3), np.float32)
    frozen.flags.writeable = False
    colour_canvas(frozen)[0, 0] = 1.0  # writable even when the input is not


def test_primitives_clip_to_the_canvas_and_never_wrap_around():
    """Negative indices would paint the far side of the canvas; nothing outside is drawn."""
    canvas = np.zeros((10, 10, 3), np.float32)
    draw_segment(canvas, np.array([-5.0, -5.0]), np.array([3.0, 3.0]), (1.0, 0.0, 0.0))
    painted = np.argwhere(canvas[..., 0] > 0)
    assert [tuple(p) for p in painted] == [(i, i) for i in range(4)]
    canvas[:] = 0
    plot_points(canvas, np.array([-1.0, 2.0, 12.0]), np.array([-1.0, 2.0, 1.0]), (0, 1, 0))
    assert np.argwhere(canvas[..., 1] > 0).tolist() == [[2, 2]]
    canvas[:] = 0
    draw_circle(canvas, 0.0, 0.0, 3, (0, 0, 1))
    rows, cols = np.nonzero(canvas[..., 2])
    assert rows.max() <= 3 and cols.max() <= 3 and len(rows) > 0  # only the quarter inside
