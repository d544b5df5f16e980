"""What the per-node shortcuts of a run (issue 26 item 4, issue 25 item 5) keep: a scalar is
still checked by its port type, a failed node still records how long it ran, each node's
record counts the bytes of its outputs."""

from __future__ import annotations

import pytest

import graphvision as gv

PLUGIN = '''
import time
from typing import Annotated, NamedTuple
import numpy as np
from graphvision import Array, Float, Int, Table, node
from graphvision.errors import PortValueError
from graphvision.values.scalars import FloatPort

class PositivePort(FloatPort):
    """A float above zero."""

    @classmethod
    def validate(cls, value):
        value = super().validate(value)
        if value <= 0:
            raise PortValueError(f"expected a positive number, got {value}")
        return value

Positive = Annotated[float, PositivePort]

@node("cost.negative")
def negative(*, value: float = -1.0) -> Positive:
    """Returns its value as a Positive."""
    return value

@node("cost.whole")
def whole(*, value: int = 3) -> Float:
    """Returns an int where a Float is declared."""
    return value

class Parts(NamedTuple):
    table: Table
    values: Array
    count: Int

@node("cost.table")
def table(*, rows: int = 5) -> Table:
    """Two columns: int32 and float64."""
    return {"a": np.arange(rows, dtype=np.int32), "b": np.ones(rows)}

@node("cost.parts")
def parts(*, rows: int = 5) -> Parts:
    """A table, an array of 3000 int16 and a count."""
    return Parts(table(rows=rows), np.zeros((30, 100), np.int16), rows)

@node("cost.slow_failure")
def slow_failure(*, seconds: float = 0.05) -> Float:
    """Sleeps, then fails."""
    time.sleep(seconds)
    raise RuntimeError("failed on purpose")
'''


@pytest.fixture(scope="module")
def registry(tmp_path_factory):
    plugin = tmp_path_factory.mktemp("cost") / "cost_plugin.py"
    plugin.write_text(PLUGIN)
    return gv.discover([plugin], entry_points=False)


def one(op: str) -> gv.Graph:
    graph = gv.Graph(op)
    graph.output("out", graph.add("node", op))
    return graph


@pytest.mark.parametrize("executor", ["sync", "threads"])
def test_a_scalar_port_of_a_plugin_still_checks_the_value(registry, executor):
    with pytest.raises(gv.RunError) as raised:
        gv.run(one("cost.negative"), registry, executor=executor)
    assert "expected a positive number, got -1.0" in raised.value.record.nodes[0].error


def test_an_int_for_a_float_port_is_still_a_float(registry):
    value = gv.run(one("cost.whole"), registry, executor="sync").outputs["out"]
    assert value == 3.0 and type(value) is float


def test_a_failed_node_records_how_long_it_ran(registry):
    with pytest.raises(gv.RunError) as raised:
        gv.run(one("cost.slow_failure"), registry, executor="sync")
    node = raised.value.record.nodes[0]
    assert node.status == "failed" and node.seconds >= 0.05  # it slept that long at least


@pytest.mark.parametrize("executor", ["sync", "threads"])
def test_each_node_records_the_bytes_of_its_outputs(registry, executor):
    graph = gv.Graph("sizes")
    graph.output("table", graph.add("table", "cost.table", {"rows": 7}))
    graph.output("parts", graph.add("parts", "cost.parts")["values"])
    nodes = {n.name: n for n in gv.run(graph, registry, executor=executor).record.nodes}
    assert nodes["table"].output_bytes == 7 * 4 + 7 * 8
    assert nodes["parts"].output_bytes == 5 * 4 + 5 * 8 + 3000 * 2  # (the count: none)
