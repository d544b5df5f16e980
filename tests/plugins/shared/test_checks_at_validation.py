"""Every check a node makes on its parameters alone is made at validation (issue 29 item 8).

A registry-wide sweep derives, from each node's parameter model, values its constraints
refuse (below a minimum, above a maximum, even for an odd-only side, outside a choice) and
checks that the refusal names the node and the parameter; the checks that relate two
parameters, moved out of node bodies, are listed with a refused combination; and on the
command line ``-s disk.size=4`` exits 2 before anything runs."""

from __future__ import annotations

import re
from typing import Any

import pydantic
import pytest

import graphvision as gv
from graphvision.cli import main
from graphvision_plugins.shared.params import odd

from ...conftest import PIPELINES

REGISTRY = gv.discover()
SPECS = [spec for specs in REGISTRY.families().values() for spec in specs]


def _numeric_branch(schema: dict[str, Any]) -> dict[str, Any] | None:
    """The integer or number part of a parameter's schema (an optional one is anyOf)."""
    for branch in [schema, *schema.get("anyOf", [])]:
        if branch.get("type") in ("integer", "number"):
            return branch
    return None


def _refusable(spec: gv.NodeSpec) -> list[tuple[str, Any, str]]:
    """(parameter, a value its model must refuse, why) derived from the model alone."""
    cases = []
    fields = spec.params_model.model_fields
    for name, schema in spec.params_schema().get("properties", {}).items():
        number = _numeric_branch(schema)
        if number is not None:
            step = 1 if number["type"] == "integer" else 0.5
            for key, sign in (("minimum", -1), ("exclusiveMinimum", 0), ("maximum", 1),
                              ("exclusiveMaximum", 0)):  # fmt: skip
                if key in number:
                    value = number[key] + sign * step
                    cases.append((name, int(value) if step == 1 else value, key))
        if "enum" in schema:
            cases.append((name, "no-such-choice", "enum"))
        validators = [getattr(m, "func", None) for m in fields[name].metadata]
        if odd in validators and isinstance(fields[name].default, int):
            cases.append((name, fields[name].default + 1, "odd"))
    return cases


CASES = [
    pytest.param(spec, name, value, id=f"{spec.id}.{name}:{why}")
    for spec in SPECS
    for name, value, why in _refusable(spec)
]


def test_the_sweep_covers_every_family_and_the_odd_sides():
    families = {case.values[0].family for case in CASES}
    assert families >= set(REGISTRY.families()) - {"io", "metrics"}  # those have no bounds
    assert any(case.id == "morphology.footprint.size:odd" for case in CASES)
    assert len(CASES) > 300


@pytest.mark.parametrize(("spec", "name", "value"), CASES)
def test_a_value_the_model_refuses_names_the_node_and_parameter(spec, name, value):
    with pytest.raises(pydantic.ValidationError) as caught:
        spec.validate_params({name: value})
    problems = spec.param_problems(caught.value)
    assert [param for param, _ in problems] == [name]
    assert f"parameter '{name}' of {spec.id}" in problems[0][1]


@pytest.mark.parametrize(
    ("op", "params", "match"),
    [
        ("morphology.footprint", {"shape": "disk", "size": 4},
         r"invalid value 4 for parameter 'size' of morphology.footprint: must be odd"),
        ("morphology.footprint", {"shape": "rectangle", "height": 2},
         r"parameter 'height' of morphology.footprint: must be odd"),
        ("edges.canny", {"low": 0.5, "high": 2.0, "thresholds": "quantile"},
         r"edges.canny: quantile thresholds lie in \[0, 1\], got high=2"),
        ("synthetic.digit_scenes", {"size": 20, "min_scale": 8, "max_scale": 28},
         r"synthetic.digit_scenes: max_scale \(28\) must be at most the scene's size \(20\)"),
        ("recognition.box_iou", {"truth": [10, 0, 5, 8]},
         r"parameter 'truth' of recognition.box_iou: must be \(x0, y0, x1, y1\) with x0 < x1"),
        ("recognition.texture_patches", {"textures": ["brick", "brick"]},
         r"parameter 'textures' of recognition.texture_patches: needs two or more distinct"),
    ],
)  # fmt: skip
def test_checks_moved_out_of_node_bodies_refuse_at_validation(op, params, match):
    spec = REGISTRY.node(op)
    with pytest.raises(pydantic.ValidationError) as caught:
        spec.validate_params(params)
    messages = [message for _, message in spec.param_problems(caught.value)]
    assert len(messages) == 1
    assert re.search(match, messages[0]), messages


def test_an_even_disk_from_the_command_line_exits_2_before_anything_runs(capsys, tmp_path):
    out = tmp_path / "out"
    status = main(["run", str(PIPELINES / "coins.yaml"), "-s", "disk.size=4", "-d", str(out)])
    err = capsys.readouterr().err
    assert status == 2, err
    assert "--set disk.size=4: invalid value 4 for parameter 'size' of morphology.footprint" in err
    assert not out.exists()  # nothing ran, nothing was written
