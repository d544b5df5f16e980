"""Port types: the lattice, validation messages and the array encoding."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import graphvision as gv


def test_lattice():
    assert gv.GrayImagePort.is_a(gv.ImagePort) and gv.ImagePort.is_a(gv.FloatImagePort)
    assert not gv.ImagePort.is_a(gv.GrayImagePort)
    assert not gv.BinaryImagePort.is_a(gv.ImagePort) and not gv.LabelImagePort.is_a(gv.ImagePort)
    assert gv.IntPort.is_a(gv.FloatPort) and not gv.FloatPort.is_a(gv.IntPort)


@pytest.mark.parametrize(
    ("port", "value", "message"),
    [
        (gv.ImagePort, np.zeros((4, 4)), r"expected Image \(float32 in \[0, 1\].*dtype=float64"),
        (gv.ImagePort, np.full((2, 2), 2.0, np.float32), r"values in \[0, 1\], got range \[2, 2\]"),
        (gv.ImagePort, np.full((2, 2), np.nan, np.float32), "got range"),
        (gv.ImagePort, np.zeros((2, 2, 4), np.float32), "H×W or H×W×3"),
        (gv.GrayImagePort, np.zeros((2, 2, 3), np.float32), "expected GrayImage"),
        (gv.GrayImagePort, np.zeros((0, 3), np.float32), "empty array"),
        (gv.FloatImagePort, np.full((2, 2), np.inf, np.float32), "finite"),
        (gv.BinaryImagePort, np.zeros((2, 2), np.uint8), "expected BinaryImage"),
        (gv.LabelImagePort, np.zeros((2, 2), np.int64), "expected LabelImage"),
        (gv.ArrayPort, np.array([None]), "expected Array"),
        (gv.FloatPort, "1.0", "expected Float"),
        (gv.IntPort, 1.5, "expected Int"),
        (gv.IntPort, True, "expected Int"),
        (gv.TablePort, {"a": np.zeros(2), "b": np.zeros(3)}, r"equal length, got \[2, 3\]"),
        (gv.TablePort, {"a": np.zeros((2, 2))}, "column 'a' to be a 1-D"),
    ],
)
def test_validation_messages(port, value, message):
    with pytest.raises(gv.PortValueError, match=message):
        port.validate(value)


@pytest.mark.parametrize("ends", [(3e38, 3e38), (-3e38, -3e38), (-3.4e38, 3.4e38)])
def test_a_float_map_of_huge_finite_values_is_accepted(ends):
    value = np.array([ends], np.float32)
    assert gv.FloatImagePort.validate(value) is value


@pytest.mark.parametrize("bad", [np.nan, -np.inf, np.inf])
def test_a_float_map_with_one_bad_value_among_huge_ones_is_refused(bad):
    value = np.array([[3e38, bad], [3e38, 1.0]], np.float32)
    with pytest.raises(gv.PortValueError, match="finite values, got NaN or inf"):
        gv.FloatImagePort.validate(value)


def test_scalars_normalise():
    assert gv.FloatPort.validate(np.float32(0.5)) == 0.5 and isinstance(
        gv.FloatPort.validate(2), float
    )
    assert gv.IntPort.validate(np.int64(3)) == 3


@pytest.mark.parametrize(
    ("port", "value"),
    [
        (gv.GrayImagePort, np.random.default_rng(0).random((3, 4)).astype(np.float32)),
        (gv.LabelImagePort, np.arange(6, dtype=np.int32).reshape(2, 3)),
        (gv.TablePort, {"x": np.arange(3.0), "n": np.arange(3)}),
        (gv.FloatPort, 2.5),
        (gv.TextPort, "hello"),
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
    assert [p.name for p in gv.ImagePort.write(np.zeros((2, 2), np.float32), tmp_path / "i")] == [
        "i.png"
    ]
    assert [p.name for p in gv.ArrayPort.write(np.zeros(3), tmp_path / "a")] == ["a.npy"]
    files = gv.TablePort.write({"x": np.arange(2)}, tmp_path / "t")
    assert (tmp_path / "t.csv").read_text().splitlines() == ["x", "0", "1"] and len(files) == 2


def _camera(**changes):
    fields = {"K": np.array([[500.0, 0, 320], [0, 500, 240], [0, 0, 1]]), **changes}
    return gv.PinholeCamera(**fields)


def test_camera_projection_and_checks():
    # a point on the optical axis, 2 m ahead of a camera at C = (0, 0, -1): the principal point
    camera = _camera(C=np.array([0.0, 0.0, -1.0]))
    x = camera.P @ np.array([0.0, 0.0, 1.0, 1.0])
    np.testing.assert_allclose(x[:2] / x[2], [320.0, 240.0])
    np.testing.assert_allclose(camera.t, [0.0, 0.0, 1.0])
    with pytest.raises(gv.PortValueError, match="camera R must be a rotation"):
        gv.CameraPort.validate(_camera(R=np.diag([1.0, 1.0, -1.0])))
    with pytest.raises(gv.PortValueError, match=r"camera 'K' must be float64 \(3, 3\)"):
        gv.CameraPort.validate(_camera(K=np.eye(3, dtype=np.float32)))
    with pytest.raises(gv.PortValueError, match="upper triangular"):
        gv.CameraPort.validate(_camera(K=np.ones((3, 3))))
    arrays, meta = gv.CameraPort.encode(camera)
    np.testing.assert_array_equal(gv.CameraPort.decode(arrays, meta).P, camera.P)


def test_points3d_checks_and_ply(tmp_path):
    with pytest.raises(gv.PortValueError, match="expected Points3D"):
        gv.Points3DPort.validate(np.zeros((2, 2)))
    with pytest.raises(gv.PortValueError, match="finite"):
        gv.Points3DPort.validate(np.full((1, 3), np.nan))
    cloud = np.array([[1.0, 2.0, 3.5], [-4.0, 0.25, 1e-3]])
    (path,) = gv.Points3DPort.write(cloud, tmp_path / "cloud")
    header, body = path.read_bytes().split(b"end_header\n")
    lines = header.decode("ascii").splitlines()
    assert lines[:3] == ["ply", "format binary_little_endian 1.0", "element vertex 2"]
    np.testing.assert_array_equal(np.frombuffer(body, "<f8").reshape(-1, 3), cloud)


def test_every_built_in_port_type_reads_back_what_it_writes(tmp_path):
    rng = np.random.default_rng(0)
    image = rng.random((5, 7, 3)).astype(np.float32)
    values = [
        (gv.ImagePort, image),
        (gv.GrayImagePort, image[..., 0]),
        (gv.BinaryImagePort, image[..., 0] > 0.5),
        (gv.LabelImagePort, (image[..., 0] * 5).astype(np.int32)),
        (gv.FloatPort, 0.125),
        (gv.IntPort, 24),
        (gv.TextPort, "done"),
        (gv.TablePort, {"label": np.array([1, 2]), "area": np.array([3.5, 4.0])}),
        (gv.Points3DPort, rng.normal(size=(4, 3))),
        (gv.Points2DPort, rng.normal(size=(4, 2))),
        (gv.CameraPort, _camera()),
    ]
    for number, (port, value) in enumerate(values):
        files = port.write(value, tmp_path / f"value{number}")
        back = port.validate(port.read(files))
        if port in (gv.ImagePort, gv.GrayImagePort):  # 8-bit PNG
            np.testing.assert_allclose(back, value, atol=0.5 / 255 + 1e-7)
        elif port is gv.TablePort:
            assert set(back) == set(value)
            for column in value:
                np.testing.assert_array_equal(back[column], value[column])
        elif port is gv.CameraPort:
            np.testing.assert_array_equal(back.P, value.P)
        elif isinstance(value, np.ndarray):
            np.testing.assert_array_equal(back, value)
        else:
            assert back == value


def test_boxes_refuse_a_nan_score_naming_the_row():
    boxes = gv.BoxSet(np.array([[0.0, 0, 2, 2], [1, 1, 3, 4]]), np.array([0.9, np.nan]))
    with pytest.raises(gv.PortValueError, match="box 1 has a NaN score"):
        gv.BoxesPort.validate(boxes)
    gv.BoxesPort.validate(gv.BoxSet(boxes.xyxy, np.array([np.inf, -np.inf])))


@pytest.mark.parametrize(
    ("value", "message"),
    [
        (np.float32(np.nan), r"range \[nan, nan\]"),
        (np.float32(-1e-45), r"range \[-1.4013e-45, -1.4013e-45\]"),
        (np.nextafter(np.float32(1), np.float32(2)), r"range \[1, 1\]"),
        (np.float32(np.inf), r"range \[inf, inf\]"),
    ],
)
def test_an_image_check_in_one_pass_refuses_what_the_minimum_and_maximum_did(value, message):
    image = np.full((4, 5), 0.5, np.float32)
    image[2, 3] = value
    with pytest.raises(gv.PortValueError, match=r"expected GrayImage values in \[0, 1\], got "):
        gv.GrayImagePort.validate(image)
    with pytest.raises(gv.PortValueError, match=message):
        gv.GrayImagePort.validate(np.full((4, 5), value, np.float32))


def test_an_image_check_in_one_pass_takes_zero_one_minus_zero_and_the_smallest_numbers():
    image = np.array([[0.0, -0.0, 1.0], [1e-45, 0.5, np.nextafter(1, 0)]], np.float32)
    assert gv.GrayImagePort.validate(image) is image
    assert gv.ImagePort.validate(image[:, ::-1]) is not None  # a strided view too


def test_a_tables_columns_are_frozen_into_one_buffer_each_aligned_and_read_only():
    from graphvision.execution.inputs import freeze_value
    from graphvision.values.memory import ALIGNMENT

    table = {
        "area": np.array([3, 1, 2], np.int64),
        "name_id": np.array([1, 2, 3], np.int16),
        "score": np.array([0.5, 0.25, 1.0]),
    }
    frozen = freeze_value(gv.TablePort, table)
    roots = set()
    for name, column in frozen.items():
        np.testing.assert_array_equal(column, table[name])
        assert column.dtype == table[name].dtype
        assert column.ctypes.data % ALIGNMENT == 0
        with pytest.raises(ValueError, match="WRITEABLE"):
            column.flags.writeable = True
        root = column
        while isinstance(root, np.ndarray | memoryview):
            root = root.obj if isinstance(root, memoryview) else root.base
        assert isinstance(root, bytes)
        roots.add(id(root))
    assert len(roots) == 1  # one buffer
    again = freeze_value(gv.TablePort, frozen)
    assert all(again[name] is frozen[name] for name in frozen)  # frozen already: kept


def test_a_strided_array_is_frozen_into_one_aligned_c_ordered_copy():
    from graphvision.values.memory import ALIGNMENT, frozen_copies, frozen_copy
    from graphvision.values.ports import is_frozen

    base = np.arange(2 * 5 * 6, dtype=np.float32).reshape(2, 5, 6)
    strided = base[:, ::2, 1::3].transpose(1, 0, 2)  # neither C nor F ordered
    frozen = frozen_copy(strided)
    np.testing.assert_array_equal(frozen, strided)
    assert frozen.flags.c_contiguous and frozen.ctypes.data % ALIGNMENT == 0
    assert is_frozen(frozen) and not frozen.flags.writeable
    columns = frozen_copies([strided, np.array([7, 8, 9], np.int16)[::-1]])
    np.testing.assert_array_equal(columns[0], strided)
    np.testing.assert_array_equal(columns[1], [9, 8, 7])
    assert all(is_frozen(column) for column in columns)


_IMAGE_PORTS = [gv.FloatImagePort, gv.ImagePort, gv.GrayImagePort, gv.ColorImagePort]
_rng = np.random.default_rng(7)
_SAMPLES = {
    "gray": _rng.random((5, 6)).astype(np.float32),
    "rgb": _rng.random((5, 6, 3)).astype(np.float32),
    "rgba": _rng.random((5, 6, 4)).astype(np.float32),
    "one channel": _rng.random((5, 6, 1)).astype(np.float32),
    "response": (_rng.standard_normal((5, 6)) * 40).astype(np.float32),
    "negative zero": np.full((2, 2), -0.0, np.float32),
    "nan": np.array([[0.5, np.nan]], np.float32),
    "inf": np.array([[0.5, np.inf]], np.float32),
    "empty": np.zeros((0, 3), np.float32),
    "float64": _rng.random((5, 6)),
    "uint8": _rng.integers(0, 256, (5, 6), dtype=np.uint8),
    "strided": _rng.random((6, 8)).astype(np.float32)[::2, ::2],
}


@pytest.mark.parametrize("port", _IMAGE_PORTS, ids=lambda p: p.type_name())
@pytest.mark.parametrize("name", list(_SAMPLES))
def test_admitting_a_value_is_the_policy_then_the_checks(port, name):
    value = _SAMPLES[name]
    try:
        expected = port.validate(port.coerce(value, "input 'x'"))
    except gv.PortValueError as error:
        with pytest.raises(gv.PortValueError) as raised:
            port.admit(value, "input 'x'")
        assert str(raised.value) == str(error)
    else:
        got = port.admit(value, "input 'x'")
        assert got.dtype == expected.dtype and np.array_equal(got, expected)


@pytest.mark.parametrize("port", _IMAGE_PORTS, ids=lambda p: p.type_name())
def test_an_image_in_the_convention_is_checked_once(port, monkeypatch):
    def policy_again(value, source):
        raise AssertionError("the dtype policy ran on a float32 image it would keep as it is")

    monkeypatch.setattr(port, "coerce", policy_again)
    value = _SAMPLES["rgb"] if port is gv.ColorImagePort else _SAMPLES["gray"]
    assert port.admit(value, "input 'x'") is value


@pytest.mark.parametrize("port", _IMAGE_PORTS[:2], ids=lambda p: p.type_name())
def test_a_masked_array_is_checked_on_all_its_values(port):
    hidden = np.ma.masked_invalid(np.array([[np.nan, 0.5], [np.inf, 0.2]], np.float32))
    with pytest.raises(gv.PortValueError, match="input 'x' has NaN or infinite values"):
        port.admit(hidden, "input 'x'")


def test_a_masked_value_out_of_range_is_still_out_of_range():
    hidden = np.ma.masked_greater(np.array([[5.0, 0.5]], np.float32), 1.0)
    with pytest.raises(gv.PortValueError, match=r"float values in \[0.5, 5\]"):
        gv.ImagePort.admit(hidden, "input 'x'")


@pytest.mark.parametrize("port", _IMAGE_PORTS[:2], ids=lambda p: p.type_name())
def test_a_finite_float64_beyond_float32_is_refused_as_out_of_range_not_as_infinite(port):
    wide = np.zeros((4, 5, 3))
    wide[2, 3, 1] = -1e300
    wide[0, 0, 0] = 1e299
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # and no NumPy "overflow in cast" warning before it
        with pytest.raises(
            gv.PortValueError,
            match=r"input 'x' has float64 values outside float32's range \(±3\.403e\+38\): "
            r"the largest, -1e\+300, is at row 2, column 3, channel 1",
        ):
            port.admit(wide, "input 'x'")


@pytest.mark.parametrize(
    ("dtype", "name"),
    [
        ("f4", "float32"),
        ("<i4", "int32"),
        ("?", "bool"),
        (">f4", ">f4"),  # swapped: not the native float32's name
        ("M8[s]", "datetime64[s]"),
        ([("a", "<i4")], "[('a', '<i4')]"),
    ],
)
def test_dtype_names_are_numpys_and_stay_apart_for_look_alike_dtypes(dtype, name):
    from graphvision.values.dtype_policy import dtype_name

    for _ in range(2):  # (the second time from what the first kept)
        assert dtype_name(np.dtype(dtype)) == name
    assert gv.ArrayPort.summary(np.zeros((2, 3), np.dtype(dtype))) == f"Array 2×3 {name}"


def test_an_array_summary_follows_its_port_type_shape_and_dtype_each_time():
    """Summaries are kept by port type, shape and dtype: an array of another shape, dtype or
    type, or one reshaped in place, is summarised anew."""
    mask = np.zeros((4, 5), bool)
    for _ in range(2):  # (the second time from what the first kept)
        assert gv.BinaryImagePort.summary(mask) == "BinaryImage 4×5 bool"
        assert gv.ArrayPort.summary(mask) == "Array 4×5 bool"
        assert gv.ArrayPort.summary(mask.astype(">i2")) == "Array 4×5 >i2"
    mask.shape = (5, 4)
    assert gv.BinaryImagePort.summary(mask) == "BinaryImage 5×4 bool"
    assert gv.ArrayPort.summary(np.zeros(0)) == "Array 0 float64"
