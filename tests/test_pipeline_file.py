"""Pipeline files: parsing, located errors, Graph -> YAML -> Graph, schema, builder."""

from __future__ import annotations

import json

import pytest

import graphvision as gv
from graphvision._pipeline_file import graph_to_dict

from .conftest import PIPELINES

GOOD = """\
version: 1
name: tiny
inputs:
  x: {type: Float, default: 2.0}
params:
  shift: 1.5
nodes:
  c:   {op: toy.const, params: {value: 3}}
  sum: {op: toy.add, in: {a: x, b: c}, params: {offset: "${params.shift}"}}
outputs:
  total: sum
"""


def test_parse_builds_the_graph():
    graph = gv.parse_pipeline(GOOD, "tiny.yaml")
    assert graph.nodes["sum"].op == "toy.add"
    assert graph.nodes["sum"].inputs == {"a": gv.Ref("x"), "b": gv.Ref("c")}
    assert graph.outputs == {"total": gv.Ref("sum")}
    assert graph.line_of("nodes.sum.params.offset") == 9


def test_builder_and_yaml_give_the_same_graph():
    built = gv.Graph("tiny")
    x = built.input("x", "Float", default=2.0)
    built.params["shift"] = 1.5
    c = built.add("c", "toy.const", params={"value": 3})
    total = built.add("sum", "toy.add", params={"offset": "${params.shift}"}, a=x, b=c)
    built.output("total", total)
    assert built == gv.parse_pipeline(GOOD)


@pytest.mark.parametrize("path", sorted(PIPELINES.glob("*.yaml")), ids=lambda p: p.name)
def test_every_pipeline_round_trips(path):
    graph = gv.load_pipeline(path)
    again = gv.parse_pipeline(gv.dump_pipeline(graph))
    again.plugins = graph.plugins
    assert again == graph
    assert graph_to_dict(again) == graph_to_dict(graph)


def test_malformed_yaml_names_the_line():
    with pytest.raises(gv.PipelineError, match=r"yaml at bad.yaml:3: malformed YAML: mapping"):
        gv.parse_pipeline("name: x\nnodes: {}\nouputs: a: b\n", "bad.yaml")


def test_not_a_mapping():
    with pytest.raises(gv.PipelineError, match="must be a YAML mapping"):
        gv.parse_pipeline("- just\n- a list\n", "list.yaml")


def test_unknown_keys_are_all_reported_with_lines():
    text = GOOD.replace("  c:   {op: toy.const,", "  c:   {opp: toy.const,").replace(
        "outputs:", "output:\n  z: c\noutputs:"
    )
    with pytest.raises(gv.PipelineError) as info:
        gv.parse_pipeline(text, "keys.yaml")
    message = str(info.value)
    assert "nodes.c.opp at keys.yaml:8: unknown key 'opp' (did you mean 'op'?)" in message
    assert "output at keys.yaml:10: unknown key 'output' (did you mean 'outputs'?)" in message
    assert "nodes.c.op" in message and "missing required key 'op'" in message


def test_duplicate_keys_are_reported():
    text = GOOD.replace("outputs:\n  total: sum", "outputs:\n  total: sum\n  total: c")
    with pytest.raises(gv.PipelineError, match=r"outputs.total at <string>:12: duplicate key"):
        gv.parse_pipeline(text)


def test_node_names_must_be_identifiers():
    text = GOOD.replace("  c:   {op", "  c-1: {op").replace("b: c}", "b: c-1}")
    with pytest.raises(
        gv.PipelineError, match=r"nodes.c-1 at <string>:8: names must be identifiers"
    ):
        gv.parse_pipeline(text)


def test_unreadable_file(tmp_path):
    with pytest.raises(gv.PipelineError, match="cannot read pipeline"):
        gv.load_pipeline(tmp_path / "missing.yaml")


def test_json_schema_accepts_the_pipelines_and_names_sections():
    schema = gv.pipeline_json_schema()
    assert schema["required"] == ["name", "nodes", "outputs"]
    assert schema["additionalProperties"] is False
    assert set(schema["properties"]) >= {"version", "name", "inputs", "params", "nodes", "outputs"}
    assert "in" in schema["$defs"]["NodeModel"]["properties"]
    json.dumps(schema)
