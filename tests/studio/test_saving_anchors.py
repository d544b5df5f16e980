"""Studio save of parameters a pipeline file shares through YAML anchors and aliases:
a value a node takes through a merge key is written in the node's own mapping, and a
save that would change another node's value through an alias is refused, writing nothing."""

from __future__ import annotations

from pathlib import Path

import pytest

pytest.importorskip("ruamel.yaml")

import graphvision as gv
from graphvision.errors import PipelineError
from graphvision.studio.saving import save_parameters

SHARED = """\
version: 1
name: shared
inputs:
  image: {type: Image, default: "sample:camera"}
nodes:
  gray:   {op: colour.to_gray, in: {image: image}}
  fine:   {op: edges.canny, in: {image: gray},
           params: &canny {sigma: 1.5, low: 0.8, high: 0.9, thresholds: quantile}}
  coarse:
    op: edges.canny
    in: {image: gray}
    params:
      <<: *canny
      sigma: 3.0   # wider
  same:   {op: edges.canny, in: {image: gray}, params: *canny}
outputs:
  fine: fine.edges
  coarse: coarse.edges
  same: same.edges
"""


def _params(path: Path) -> dict[str, dict]:
    graph = gv.load_pipeline(path)
    return {name: dict(node.params) for name, node in graph.nodes.items()}


def test_a_value_taken_through_a_merge_key_is_saved_in_the_nodes_own_mapping(tmp_path):
    source = tmp_path / "shared.yaml"
    source.write_text(SHARED)
    before = _params(source)
    save_parameters(source, {"coarse.low": 0.7})
    after = _params(source)
    assert after["coarse"] == {**before["coarse"], "low": 0.7}
    assert {k: v for k, v in after.items() if k != "coarse"} == {
        k: v for k, v in before.items() if k != "coarse"
    }  # the anchor is left alone: fine and same keep 0.8
    saved = source.read_text()
    assert "&canny" in saved and "<<: *canny" in saved and "*canny}" in saved
    assert "# wider" in saved


@pytest.mark.parametrize(
    ("overrides", "changed"),
    [({"same.low": 0.7}, "fine.low"), ({"fine.high": 0.95}, "coarse.high")],
)
def test_a_save_that_would_change_a_value_shared_through_an_alias_is_refused(
    tmp_path, overrides, changed
):
    source = tmp_path / "shared.yaml"
    source.write_text(SHARED)
    ((key, value),) = overrides.items()
    with pytest.raises(
        PipelineError,
        match=rf"{changed} in .*shared.yaml: saving {key} would change it too "
        rf"\(0\.\d+ → {value}\): the file shares the value through the YAML anchor &canny",
    ):
        save_parameters(source, overrides)
    assert source.read_text() == SHARED  # nothing written


def test_values_shared_through_an_alias_are_saved_when_all_are_set_alike(tmp_path):
    source = tmp_path / "shared.yaml"
    source.write_text(SHARED)
    with pytest.raises(PipelineError, match=r"coarse.low in .*: saving fine.low, same.low would"):
        save_parameters(source, {"fine.low": 0.7, "same.low": 0.7})  # coarse merges it too
    save_parameters(source, {"fine.low": 0.7, "same.low": 0.7, "coarse.low": 0.7})
    params = _params(source)
    assert params["fine"]["low"] == params["same"]["low"] == params["coarse"]["low"] == 0.7


def test_a_new_key_in_a_mapping_shared_through_an_alias_is_refused(tmp_path):
    source = tmp_path / "shared.yaml"
    source.write_text(SHARED)
    with pytest.raises(
        PipelineError,
        match=r"fine.boundary in .*shared.yaml: saving same.boundary would change it too "
        r"\(unset → 'zero'\)",
    ):
        save_parameters(source, {"same.boundary": "zero"})  # added to &canny itself
    assert source.read_text() == SHARED  # nothing written


NODE_ALIAS = """\
version: 1
name: node_alias
inputs:
  image: {type: Image, default: "sample:camera"}
nodes:
  gray: {op: colour.to_gray, in: {image: image}}
  fine: &detector
    op: edges.canny
    in: {image: gray}
    params: {sigma: 1.5, low: 0.8, high: 0.9, thresholds: quantile}
  same: *detector
outputs:
  fine: fine.edges
  same: same.edges
"""


def test_a_refusal_names_the_anchor_on_the_node_when_the_node_itself_is_an_alias(tmp_path):
    source = tmp_path / "node_alias.yaml"
    source.write_text(NODE_ALIAS)
    with pytest.raises(
        PipelineError,
        match=r"fine.low in .*: saving same.low would change it too \(0.8 → 0.7\): the file "
        r"shares the value through the YAML anchor &detector and its aliases; not saved\. "
        r"Set them all to the same value, or give same a node mapping of its own instead of "
        r"the alias \*detector$",
    ):
        save_parameters(source, {"same.low": 0.7})
    assert source.read_text() == NODE_ALIAS  # nothing written
