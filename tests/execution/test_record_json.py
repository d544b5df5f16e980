"""``record.json``'s text: built field by field, it is what ``dataclasses.asdict`` and
``json.dumps(indent=2)`` made of the record (issue 26 item 1: asdict deep-copied every
value, half the record's cost per batch file)."""

from __future__ import annotations

import dataclasses
import enum
import json
from pathlib import Path

import numpy as np
import pytest

from graphvision.execution.record import NodeRecord, RunRecord, _indented, _json_default


@dataclasses.dataclass
class _Window:
    """A parameter value that is itself a dataclass (a plugin's typed option)."""

    size: tuple[int, int]
    where: Path


def _record() -> RunRecord:
    params = {
        "k": np.float32(0.25),
        "kernel": np.array([[1, 0], [0, 1]], dtype=np.uint8),
        "sizes": (3, 5.5, None),
        "path": Path("in/coins.png"),
        "window": _Window((2, 3), Path("a")),
        "nested": {"flag": True, "values": [float("nan"), float("inf")], "empty": {}},
        "text": 'é "quoted"\nline',
    }
    nodes = [
        NodeRecord("gray", "colour.to_gray", "computed", 0.5, 12, params=params, keys={"out": "k"}),
        NodeRecord("count", "regions.count", "failed", error="ValueError: no", backend="numba"),
    ]
    return RunRecord(
        "coins",
        "sync",
        1.25,
        nodes,
        outputs={"count": "int"},
        inputs={"image": {"path": "a.png", "sha256": "ab"}},
        overrides={"gray.method": "mean"},
        files={"count": ["count.json"]},
        file_sha256={"count.json": "cd"},
    )


def test_the_record_is_asdicts_json_byte_for_byte():
    record = _record()
    expected = json.dumps(dataclasses.asdict(record), indent=2, default=_json_default)
    assert record.to_json() == expected


class _Level(enum.IntEnum):
    LOW = 1


@pytest.mark.parametrize(
    "value",
    [
        {1.5: [], 2: {}, None: [[]], True: [{}], False: (), "é\u2028": '\x00\t"\\'},
        [np.float64(0.1), np.int64(-3), np.bool_(True), _Level.LOW, 1e300, -0.0, 10**30],
        {"nan": float("nan"), "inf": [float("inf"), float("-inf")], "deep": [[[1], {"a": ()}]]},
        ({"a": (Path("p"), _Window((0, 1), Path("w")))}, "x", None, False, 7),
        "a string alone",
    ],
)
def test_the_indenting_writer_is_jsons_indent_2_to_the_byte(value):
    assert _indented(value) == json.dumps(value, indent=2, default=_json_default)


def test_a_key_json_refuses_is_refused_as_json_does():
    with pytest.raises(TypeError, match="keys must be str, int, float, bool or None, not tuple"):
        _indented({(1, 2): 3})


def test_the_records_json_holds_each_value_as_written_by_hand():
    data = json.loads(_record().to_json())
    assert list(data) == [
        "pipeline", "executor", "seconds", "nodes", "outputs", "date", "pipeline_file",
        "pipeline_sha256", "git_commit", "git_dirty", "inputs", "params", "overrides",
        "versions", "files", "file_sha256",
    ]  # fmt: skip
    assert list(data["nodes"][1]) == [
        "name", "op", "status", "seconds", "output_bytes", "error", "params", "keys", "backend",
    ]  # fmt: skip
    params = data["nodes"][0]["params"]
    assert params["k"] == 0.25 and params["kernel"] == [[1, 0], [0, 1]]
    assert params["sizes"] == [3, 5.5, None] and params["path"] == "in/coins.png"
    assert params["window"] == {"size": [2, 3], "where": "a"}
    assert params["text"] == 'é "quoted"\nline'
    assert data["nodes"][1]["error"] == "ValueError: no" and data["nodes"][1]["backend"] == "numba"
    assert '\n      "params": {\n        "k": 0.25,\n' in _record().to_json()  # indented by 2
