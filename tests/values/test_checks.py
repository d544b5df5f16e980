"""A port type's check of a fresh array (graphvision.values.checks): True only where the
type's own validate returns the array as it is; every wrong array it is fed is refused."""

from __future__ import annotations

import numpy as np
import pytest

import graphvision as gv
from graphvision.errors import PortValueError
from graphvision.values.checks import array_check, frozen_fresh_table, is_fresh_table_port
from graphvision.values.ports import is_frozen

BAD = {  # for each port type with a check: arrays its validate refuses, one per condition
    gv.ImagePort: [
        np.zeros((2, 2), np.float64),  # dtype
        np.zeros((2,), np.float32),  # dimensions
        np.zeros((0, 2), np.float32),  # empty
        np.zeros((2, 2, 4), np.float32),  # channels
        np.array([[0.5, 1.5]], np.float32),  # range
        np.array([[-0.5, 0.5]], np.float32),
        np.array([[np.nan, 0.5]], np.float32),
        np.array([[np.inf, 0.5]], np.float32),
    ],
    gv.GrayImagePort: [np.zeros((2, 2, 3), np.float32), np.array([[2.0]], np.float32)],
    gv.ColorImagePort: [np.zeros((2, 2), np.float32), np.full((1, 1, 3), 1.01, np.float32)],
    gv.FloatImagePort: [
        np.array([[np.nan, 2.0]], np.float32),
        np.array([[-np.inf, 2.0]], np.float32),
        np.zeros((2, 2), np.float16),
        np.zeros((2, 2, 2), np.float32),
    ],
    gv.BinaryImagePort: [
        np.zeros((2, 2), np.uint8),
        np.zeros((2, 2, 1), bool),
        np.zeros((0, 0), bool),
    ],
    gv.LabelImagePort: [np.array([[0, -1]], np.int32), np.zeros((2, 2), np.int64)],
    gv.KernelPort: [np.zeros((3, 3), np.float32), np.zeros((3,), np.float64)],
    gv.DescriptorsPort: [np.zeros((2, 4), np.float64), np.zeros((4,), np.float32)],
}

GOOD = {  # arrays each validate returns as they are (edge values of each condition)
    gv.ImagePort: [np.array([[0.0, 1.0]], np.float32), np.ones((2, 2, 3), np.float32)],
    gv.GrayImagePort: [np.zeros((1, 1), np.float32)],
    gv.ColorImagePort: [np.full((2, 2, 3), 0.5, np.float32)],
    gv.FloatImagePort: [np.array([[-3e38, 3e38]], np.float32)],
    gv.BinaryImagePort: [np.eye(3, dtype=bool)],
    gv.LabelImagePort: [np.array([[0, 7]], np.int32)],
    gv.KernelPort: [np.full((3, 3), 1 / 9)],
    gv.DescriptorsPort: [np.zeros((0, 128), np.float32)],  # (may be empty)
    gv.ArrayPort: [np.zeros(0, np.int8)],  # (Array takes any numeric array: no check)
}


@pytest.mark.parametrize(
    ("kind", "value"), [(kind, value) for kind, values in BAD.items() for value in values]
)
def test_a_check_refuses_every_array_its_port_type_refuses(kind, value):
    check = array_check(kind)
    assert check is not None
    assert check(value) is False
    with pytest.raises(PortValueError):
        kind.validate(value)


@pytest.mark.parametrize(
    ("kind", "value"), [(kind, value) for kind, values in GOOD.items() for value in values]
)
def test_a_check_takes_what_its_port_type_returns_as_it_is(kind, value):
    assert kind.validate(value) is value
    check = array_check(kind)
    assert check is None or check(value) is True


def test_negative_zero_is_left_to_validate_which_takes_it():
    image = np.array([[-0.0, 0.5]], np.float32)
    assert array_check(gv.ImagePort)(image) is False  # (one integer maximum cannot say)
    assert gv.ImagePort.validate(image) is image


def test_a_type_that_validates_in_its_own_way_has_no_check():
    class OddPort(gv.ArrayPort):
        ndims = (2,)
        dtypes = (np.float64,)

        @classmethod
        def validate(cls, value):
            value = super().validate(value)
            if value.shape[0] % 2 == 0:
                raise PortValueError("odd rows only")
            return value

    assert array_check(OddPort) is None
    assert array_check(gv.Points2DPort) is None  # (its own validate: x, y columns)
    assert array_check(gv.ArrayPort) is None  # any dtype: validate decides


@pytest.mark.parametrize(
    ("value", "message"),
    [
        (
            np.full((4, 4), 1.5, np.float32),
            r"expected GrayImage values in \[0, 1\], got range \[1.5, 1.5\]",
        ),
        (
            np.full((4, 4), np.nan, np.float32),
            r"expected GrayImage values in \[0, 1\], got range \[nan, nan\]",
        ),
        (np.zeros((4, 4)), r"expected GrayImage \(float32 in \[0, 1\], H×W\)"),
        (np.zeros((4, 4, 3), np.float32), r"expected GrayImage \(float32 in \[0, 1\], H×W\)"),
    ],
)
def test_a_run_refuses_a_node_output_the_check_refuses(registry, value, message):
    from graphvision.execution.accept import accepted

    graph = gv.Graph("darken")
    graph.output("out", graph.add("d", "toy.darken", image=graph.input("image", "GrayImage")))
    step = gv.compile_graph(graph, registry).steps["d"]
    assert step.array_checks == {"out": array_check(gv.GrayImagePort)}
    with pytest.raises(PortValueError, match=rf"invalid output 'out': {message}"):
        accepted(step, value, 1, False)
    good = np.full((4, 4), 0.25, np.float32)
    frozen = accepted(step, good, 1, False)["out"]
    assert not frozen.flags.writeable and np.array_equal(frozen, np.full((4, 4), 0.25))


BAD_TABLES = [  # what TablePort.validate refuses, one per condition
    {1: np.arange(3.0)},
    {"a": [1.0, 2.0]},
    {"a": np.zeros((2, 2))},
    {"a": np.arange(3.0), "b": np.arange(4.0)},
    {"a": np.array([None, 1], dtype=object)},
]


@pytest.mark.parametrize("table", BAD_TABLES)
def test_a_new_table_the_table_type_refuses_is_left_to_its_validate(table):
    assert frozen_fresh_table(table) is None
    with pytest.raises(PortValueError):
        gv.TablePort.validate(table)


def test_a_new_table_is_checked_and_frozen_in_one_buffer():
    table = {"label": np.arange(1, 4, dtype=np.int32), "area": np.array([5.0, 6.5, 7.0])}
    frozen = frozen_fresh_table(table)
    assert list(frozen) == ["label", "area"]
    assert [c.dtype for c in frozen.values()] == [np.int32, np.float64]
    assert frozen["label"].tolist() == [1, 2, 3] and frozen["area"].tolist() == [5.0, 6.5, 7.0]
    assert all(is_frozen(c) for c in frozen.values())
    assert frozen["label"].base is not None and frozen["label"].base is frozen["area"].base
    with pytest.raises(ValueError, match="read-only"):
        frozen["area"][0] = 1.0
    held = {"a": np.arange(3.0)}
    held["a"].flags.writeable = False  # (maybe frozen already: freeze_all decides)
    assert frozen_fresh_table(held) is None and frozen_fresh_table({}) is None


def test_only_types_that_validate_and_encode_tables_as_table_does_take_it():
    class Renamed(gv.TablePort):
        """Same validate and encoding."""

    class Checked(gv.TablePort):
        @classmethod
        def validate(cls, value):
            return super().validate(value)

    assert is_fresh_table_port(gv.TablePort) and is_fresh_table_port(Renamed)
    assert not is_fresh_table_port(Checked) and not is_fresh_table_port(gv.ImagePort)


@pytest.mark.parametrize(
    ("table", "message"),
    [
        ({"a": np.arange(3.0), "b": np.arange(4.0)}, r"columns of equal length, got \[3, 4\]"),
        ({"a": np.zeros((2, 2))}, r"column 'a' to be a 1-D numeric array"),
    ],
)
def test_a_run_refuses_a_new_table_its_type_refuses(registry, table, message):
    from pathlib import Path

    from graphvision.execution.accept import accepted

    coins = Path(__file__).parents[2] / "pipelines" / "coins.yaml"
    step = gv.compile_graph(gv.load_pipeline(coins), registry).steps["measured"]
    assert step.table_ports == {"out"}
    with pytest.raises(PortValueError, match=rf"invalid output 'out': expected Table {message}"):
        accepted(step, table, 1, False)
