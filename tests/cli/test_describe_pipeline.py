"""``graphvision describe PIPELINE.yaml`` (issue 29, item 11): a pipeline's inputs (types,
defaults), parameters (defaults, bounds where they are used), outputs and the families of
its nodes, without importing the pipeline's own plugins; ``describe OP`` is unchanged."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from graphvision.cli import main

from ..conftest import PIPELINES

PLUGIN = '''
from pathlib import Path
from typing import Annotated, Literal

from pydantic import Field

from graphvision import Float, Int, node

Path(__file__).with_name("imported").write_text("yes")


@node("shapes.scale")
def scale(x: Float, *, factor: Annotated[int, Field(ge=3, le=99)] = 5,
          mode: Literal["up", "down"] = "up") -> Float:
    """x times factor."""
    return x * factor


@node("shapes.count")
def count(x: Float, *, limit: Annotated[float, Field(gt=0)] = 1.0) -> Int:
    """A count."""
    return 1
'''

PIPELINE = """version: 1
name: shapes
description: >
  Scale a value.
{plugins}inputs:
  x: {{type: Float, default: 2.5}}
  y: {{type: Float}}
params:
  factor: 7
  mode: down
  spare: 1
nodes:
  big: {{op: shapes.scale, in: {{x: x}},
        params: {{factor: "${{params.factor}}", mode: "${{params.mode}}"}}}}
  n: {{op: shapes.count, in: {{x: y}}}}
outputs:
  scaled: big
  number: n
"""


def cli(capsys, *args) -> tuple[int, str, str]:
    status = main([str(a) for a in args])
    out, err = capsys.readouterr()
    assert "Traceback" not in err
    return status, out, err


def setup(tmp_path: Path, named_in_pipeline: bool) -> tuple[Path, Path]:
    plugin = tmp_path / "shapes.py"
    plugin.write_text(PLUGIN)
    pipeline = tmp_path / "shapes.yaml"
    plugins = "plugins: [shapes.py]\n" if named_in_pipeline else ""
    pipeline.write_text(PIPELINE.format(plugins=plugins))
    return pipeline, plugin


def test_describe_lists_inputs_parameters_with_bounds_outputs_and_families(capsys, tmp_path):
    pipeline, plugin = setup(tmp_path, named_in_pipeline=False)
    status, out, err = cli(capsys, "--plugins", plugin, "describe", pipeline)
    assert status == 0, err
    lines = out.splitlines()
    assert lines[0] == f"shapes ({pipeline})" and lines[1] == "  Scale a value."
    expected = [
        "inputs (-i NAME=VALUE):",
        "  x: Float, default 2.5",
        "  y: Float, required",
        "",
        "parameters (-s params.NAME=VALUE):",
        "  factor: default 7",
        "    used by big.factor (shapes.scale): integer from 3 to 99",
        '  mode: default "down"',
        "    used by big.mode (shapes.scale): one of: up, down",
        "  spare: default 1",
        "    used by no node",
        "",
        "outputs (-o NAME):",
        "  scaled: Float, from big",
        "  number: Int, from n",
        "",
        "nodes (2) by family:",
    ]
    start = lines.index("inputs (-i NAME=VALUE):")
    assert lines[start : start + len(expected)] == expected
    families = " ".join(line.strip() for line in lines[start + len(expected) :])
    assert families == f"shapes (plugin {plugin}): big (shapes.scale), n (shapes.count)"
    assert f"note: {pipeline} is not valid as it stands (1 problem(s))" in err  # spare is unused


def test_describe_json_holds_the_same_description(capsys, tmp_path):
    pipeline, plugin = setup(tmp_path, named_in_pipeline=False)
    status, out, _ = cli(capsys, "--plugins", plugin, "describe", pipeline, "--json")
    info = json.loads(out)
    assert status == 0 and info["name"] == "shapes"
    assert [p.split(": ", 1)[1] for p in info["problems"]] == [
        "unused pipeline param 'spare': no node refers to ${params.spare}"
    ]
    assert info["inputs"]["x"] == {
        "type": "Float",
        "default": 2.5,
        "description": "",
        "truth_of": [],
    }
    assert info["params"]["factor"]["used_by"] == [
        {"param": "big.factor", "op": "shapes.scale", "accepts": "integer from 3 to 99"}
    ]
    assert info["outputs"]["number"] == {"type": "Int", "from": "n"}
    assert info["families"]["shapes"]["nodes"] == {"big": "shapes.scale", "n": "shapes.count"}


def test_describing_a_pipeline_never_imports_its_plugins(capsys, tmp_path):
    pipeline, _ = setup(tmp_path, named_in_pipeline=True)
    status, out, err = cli(capsys, "describe", pipeline)
    assert status == 0 and not (tmp_path / "imported").exists()
    assert "  x: Float, default 2.5" in out and "  factor: default 7" in out
    assert "  scaled: unknown (its op is not loaded), from big" in out
    assert "  shapes (not loaded): big (shapes.scale), n (shapes.count)" in out
    assert f"local plugins (listed, not imported): {tmp_path / 'shapes.py'}" in out
    assert f"note: {pipeline} is not valid as it stands" in err
    assert f"`graphvision validate {pipeline}` lists them" in err


@pytest.mark.parametrize("pipeline", sorted(PIPELINES.glob("*.yaml")), ids=lambda p: p.stem)
def test_every_shipped_pipeline_is_described_whole(capsys, pipeline):
    from graphvision.graph.pipeline_file import load_pipeline

    graph = load_pipeline(pipeline)
    status, out, err = cli(capsys, "describe", pipeline, "--json")
    info = json.loads(out)
    assert status == 0 and info["problems"] == [] and "note:" not in err
    assert list(info["inputs"]) == list(graph.inputs)
    assert list(info["params"]) == list(graph.params)
    assert list(info["outputs"]) == list(graph.outputs)
    assert all("unknown" not in entry["type"] for entry in info["outputs"].values())
    assert sum(len(f["nodes"]) for f in info["families"].values()) == len(graph.nodes)


def test_a_file_without_a_yaml_suffix_is_a_pipeline_and_an_op_is_still_an_op(capsys, tmp_path):
    pipeline, plugin = setup(tmp_path, named_in_pipeline=False)
    renamed = pipeline.rename(tmp_path / "shapes")
    status, out, _ = cli(capsys, "--plugins", plugin, "describe", renamed)
    assert status == 0 and "  number: Int, from n" in out
    status, out, _ = cli(capsys, "describe", "filters.median")
    assert status == 0 and out.startswith("filters.median (version")
    status, _, err = cli(capsys, "describe", tmp_path / "missing.yaml")
    assert status == 2 and f"cannot read pipeline {tmp_path / 'missing.yaml'}" in err
