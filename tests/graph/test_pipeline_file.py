"""Pipeline files: parsing, located errors, Graph -> YAML -> Graph, schema, builder."""

from __future__ import annotations

import json

import pytest

import graphvision as gv
from graphvision.graph.pipeline_file import graph_to_dict

from ..conftest import PIPELINES

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


@pytest.mark.parametrize("bad", ["c</script>", "c d"])
def test_a_bad_output_name_and_a_bad_reference_are_each_listed_once_for_what_they_are(bad):
    text = GOOD.replace("  c:   {op", f'  "{bad}": {{op').replace("b: c}", f'b: "{bad}"}}')
    text = text.replace("  total: sum", f'  "{bad}": "{bad}"\n  fine: "{bad}"')
    with pytest.raises(gv.PipelineError) as info:
        gv.parse_pipeline(text)
    message = str(info.value)
    assert message.count(f"output name '{bad}' must be a plain name") == 1
    assert (
        message.count(f"a reference must be 'node' or 'node.port' (identifiers), got '{bad}'") == 3
    )
    assert "output name 'fine'" not in message  # its value is wrong, not its name


def test_unreadable_file(tmp_path):
    with pytest.raises(
        gv.PipelineError, match=r"^cannot read pipeline .*missing.yaml: No such file"
    ):
        gv.load_pipeline(tmp_path / "missing.yaml")
    (tmp_path / "binary.yaml").write_bytes(b"\xff\xfe\x00")
    with pytest.raises(gv.PipelineError, match=r"^cannot read pipeline .*binary.yaml: 'utf-8'"):
        gv.load_pipeline(tmp_path / "binary.yaml")


def test_json_schema_accepts_the_pipelines_and_names_sections():
    schema = gv.pipeline_json_schema()
    assert schema["required"] == ["name", "nodes", "outputs"]
    assert schema["additionalProperties"] is False
    assert set(schema["properties"]) >= {"version", "name", "inputs", "params", "nodes", "outputs"}
    assert "in" in schema["$defs"]["NodeModel"]["properties"]
    json.dumps(schema)


def test_json_schema_states_the_name_and_reference_rules():
    schema = gv.pipeline_json_schema()
    for section in ("nodes", "inputs", "outputs"):  # output names name files: plain names too
        assert list(schema["properties"][section]["patternProperties"]) == [gv.NAME_PATTERN]
        assert schema["properties"][section]["additionalProperties"] is False
    outputs = schema["properties"]["outputs"]["patternProperties"][gv.NAME_PATTERN]
    assert outputs["pattern"] == gv.REF_PATTERN


LAUGHS = """\
name: lol
params:
  a: &a ["lol", "lol", "lol", "lol", "lol", "lol", "lol", "lol", "lol", "lol"]
  b: &b [*a, *a, *a, *a, *a, *a, *a, *a, *a, *a]
  c: &c [*b, *b, *b, *b, *b, *b, *b, *b, *b, *b]
  d: &d [*c, *c, *c, *c, *c, *c, *c, *c, *c, *c]
  e: &e [*d, *d, *d, *d, *d, *d, *d, *d, *d, *d]
  f: &f [*e, *e, *e, *e, *e, *e, *e, *e, *e, *e]
  g: &g [*f, *f, *f, *f, *f, *f, *f, *f, *f, *f]
  h: &h [*g, *g, *g, *g, *g, *g, *g, *g, *g, *g]
  i: &i [*h, *h, *h, *h, *h, *h, *h, *h, *h, *h]
nodes:
  n: {op: toy.const, params: {value: PARAM}}
outputs: {o: n}
"""


@pytest.mark.parametrize(
    "text",
    [
        LAUGHS.replace("PARAM", "1"),  # inside params:
        LAUGHS.replace("PARAM", "*i").replace("  i: &i", "  i: &i"),  # from a node parameter
        "top: &t ["
        + ", ".join(["x"] * 10)
        + "]\n"
        + "".join(
            f"l{k}: &l{k} [" + ", ".join([f"*{'t' if k == 0 else f'l{k - 1}'}"] * 10) + "]\n"
            for k in range(9)
        )
        + "name: x\nnodes: {}\noutputs: {}\n",  # at top level
    ],
    ids=["params", "node-parameter", "top-level"],
)
def test_a_billion_laughs_is_refused_at_once_naming_a_line(text):
    with pytest.raises(
        gv.PipelineError, match=r"yaml at <string>:\d+: the file expands to too many"
    ):
        gv.parse_pipeline(text)


def test_a_recursive_alias_is_refused():
    text = "name: r\nparams:\n  loop: &loop [1, *loop]\nnodes: {}\noutputs: {}\n"
    with pytest.raises(
        gv.PipelineError, match=r"yaml at <string>:3: alias \*loop refers to itself"
    ):
        gv.parse_pipeline(text)


@pytest.mark.parametrize("depth", [100, 5000, 100_000])
def test_deep_nesting_is_refused_without_a_recursion_error(depth):
    text = "name: d\nparams:\n  deep: " + "[" * depth + "]" * depth + "\nnodes: {}\noutputs: {}\n"
    with pytest.raises(gv.PipelineError, match=r"yaml at <string>:3: nested deeper than 64 levels"):
        gv.parse_pipeline(text)


@pytest.mark.parametrize(
    ("value", "said"),
    [
        ("9" * 5000, r"9{20}\.\.\. \(5000 characters\) cannot be read: Exceeds the limit"),
        ("2024-13-45", r"2024-13-45 cannot be read: month must be in 1\.\.12"),
    ],
)
def test_a_scalar_python_cannot_convert_is_a_problem_at_its_line(value, said):
    text = f"name: n\nparams:\n  big: {value}\nnodes: {{}}\noutputs: {{}}\n"
    with pytest.raises(gv.PipelineError, match=rf"yaml at <string>:3: {said}"):
        gv.parse_pipeline(text)


def test_merge_keys_and_aliases_within_the_budget_work():
    text = (
        "name: m\nparams:\n  base: &base {value: 2, unused: 0}\n"
        "nodes:\n  n: {op: toy.const, params: {<<: *base, value: 3}}\noutputs: {o: n}\n"
    )
    graph = gv.parse_pipeline(text)
    assert graph.nodes["n"].params == {"value": 3, "unused": 0}


def test_one_document_per_file():
    with pytest.raises(gv.PipelineError, match=r"yaml at <string>:12: a pipeline file holds one"):
        gv.parse_pipeline(GOOD + "---\nname: second\n")


def test_a_pipeline_file_is_read_as_utf8_under_an_ascii_locale(tmp_path):
    """coins.yaml's description holds '·': under LC_ALL=C (no UTF-8 mode) it was read in the
    locale's encoding and refused."""
    import os
    import subprocess
    import sys

    coins = PIPELINES / "coins.yaml"
    assert "·" in coins.read_text(encoding="utf-8")
    environment = {**os.environ, "LC_ALL": "C", "PYTHONUTF8": "0", "PYTHONCOERCECLOCALE": "0"}
    done = subprocess.run(
        [sys.executable, "-m", "graphvision", "validate", str(coins)],
        capture_output=True, text=True, env=environment, timeout=120,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip().endswith(": ok")
