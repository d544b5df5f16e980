"""Port types: the lattice, validation messages and the array encoding."""

from __future__ import annotations

import numpy as np
import pytest

import graphvision as gv


def test_lattice():
    assert gv.GrayImage.is_a(gv.Image) and gv.Image.is_a(gv.FloatImage)
    assert not gv.Image.is_a(gv.GrayImage)
    assert not gv.BinaryImage.is_a(gv.Image) and not gv.LabelImage.is_a(gv.Image)
    assert gv.Int.is_a(gv.Float) and not gv.Float.is_a(gv.Int)


@pytest.mark.parametrize(
    ("port", "value", "message"),
    [
        (gv.Image, np.zeros((4, 4)), r"expected Image \(float32 in \[0, 1\].*dtype=float64"),
        (gv.Image, np.full((2, 2), 2.0, np.float32), r"values in \[0, 1\], got range \[2, 2\]"),
        (gv.Image, np.full((2, 2), np.nan, np.float32), "got range"),
        (gv.Image, np.zeros((2, 2, 4), np.float32), "H×W or H×W×3"),
        (gv.GrayImage, np.zeros((2, 2, 3), np.float32), "expected GrayImage"),
        (gv.GrayImage, np.zeros((0, 3), np.float32), "empty array"),
        (gv.FloatImage, np.full((2, 2), np.inf, np.float32), "finite"),
        (gv.BinaryImage, np.zeros((2, 2), np.uint8), "expected BinaryImage"),
        (gv.LabelImage, np.zeros((2, 2), np.int64), "expected LabelImage"),
        (gv.Array, np.array([None]), "expected Array"),
        (gv.Float, "1.0", "expected Float"),
        (gv.Int, 1.5, "expected Int"),
        (gv.Int, True, "expected Int"),
        (gv.Table, {"a": np.zeros(2), "b": np.zeros(3)}, r"equal length, got \[2, 3\]"),
        (gv.Table, {"a": np.zeros((2, 2))}, "column 'a' to be a 1-D"),
    ],
)
def test_validation_messages(port, value, message):
    with pytest.raises(gv.PortValueError, match=message):
        port.validate(value)


def test_scalars_normalise():
    assert gv.Float.validate(np.float32(0.5)) == 0.5 and isinstance(gv.Float.validate(2), float)
    assert gv.Int.validate(np.int64(3)) == 3


@pytest.mark.parametrize(
    ("port", "value"),
    [
        (gv.GrayImage, np.random.default_rng(0).random((3, 4)).astype(np.float32)),
        (gv.LabelImage, np.arange(6, dtype=np.int32).reshape(2, 3)),
        (gv.Table, {"x": np.arange(3.0), "n": np.arange(3)}),
        (gv.Float, 2.5),
        (gv.Text, "hello"),
    ],
)
def test_encode_decode_round_trip(port, value):
    arrays, meta = port.encode(port.validate(value))
    again = port.decode(arrays, meta)
    if isinstance(value, dict):
        assert list(again) == list(value)
        for k in value:
            np.testing.assert_array_equal(again[k], value[k])
    else:
        np.testing.assert_array_equal(again, value)


def test_writing_by_type(tmp_path):
    assert [p.name for p in gv.Image.write(np.zeros((2, 2), np.float32), tmp_path / "i")] == [
        "i.png"
    ]
    assert [p.name for p in gv.Array.write(np.zeros(3), tmp_path / "a")] == ["a.npy"]
    files = gv.Table.write({"x": np.arange(2)}, tmp_path / "t")
    assert (tmp_path / "t.csv").read_text().splitlines() == ["x", "0", "1"] and len(files) == 2
