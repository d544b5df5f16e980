"""Validation against the registry: every problem at once, each with file and line."""

from __future__ import annotations

import pytest

import graphvision as gv

from ..conftest import PIPELINES

BROKEN = """\
version: 1
name: broken
inputs:
  x: {type: Float, default: 1.0}
  unused: {type: Float, default: 0.0}
  img: {type: Imagee}
params:
  spare: 3
nodes:
  a:    {op: toy.cnst}
  b:    {op: toy.add, in: {a: x, c: x}, params: {offset: -1, ofset: 2}}
  d:    {op: toy.darken, in: {image: x}, params: {factor: "${params.nope}"}}
  e:    {op: toy.add, in: {a: ghost, b: s.mid}}
  s:    {op: toy.split, in: {x: x}}
  f:    {op: toy.add, in: {a: s, b: x}}
outputs:
  out: b
  missing: zzz
"""


@pytest.fixture
def problems(registry):
    with pytest.raises(gv.PipelineError) as info:
        gv.compile_graph(gv.parse_pipeline(BROKEN, "broken.yaml"), registry)
    return {(p.where, p.line): p.message for p in info.value.problems}, str(info.value)


def test_all_problems_are_reported_sorted_by_line(problems):
    found, text = problems
    lines = [
        int(line.split(":")[1].split(":")[0])
        for line in text.splitlines()[1:]
        if "broken.yaml:" in line
        for line in [line.split("broken.yaml")[1]]
    ]
    assert lines == sorted(lines)
    assert len(found) >= 12


@pytest.mark.parametrize(
    ("where", "line", "message"),
    [
        ("inputs.img.type", 6, "unknown port type 'Imagee' (did you mean 'Image'?)"),
        ("inputs.unused", 5, "unused input 'unused': no node or output reads it"),
        ("params.spare", 8, "unused pipeline param 'spare'"),
        ("nodes.a.op", 10, "unknown op 'toy.cnst' (did you mean 'toy.const'?)"),
        ("nodes.b.in.c", 11, "toy.add has no input port 'c'; inputs: a, b"),
        ("nodes.b.in", 11, "missing input port 'b' of toy.add (Float)"),
        (
            "nodes.b.params.offset",
            11,
            "invalid value -1 for parameter 'offset' of toy.add: "
            "Input should be greater than or equal to 0",
        ),
        (
            "nodes.b.params.ofset",
            11,
            "unknown parameter 'ofset' of toy.add (did you mean 'offset'?)",
        ),
        (
            "nodes.d.in.image",
            12,
            "type mismatch: 'x' gives Float but 'd.image' (toy.darken) takes GrayImage",
        ),
        ("nodes.d.params.factor", 12, "unknown pipeline param '${params.nope}'"),
        ("nodes.e.in.a", 13, "unknown node or input 'ghost'"),
        ("nodes.e.in.b", 13, "node 's' (toy.split) has no output 'mid'; outputs: low, high"),
        ("nodes.f.in.a", 15, "node 's' (toy.split) has outputs low, high; name one"),
        ("outputs.missing", 18, "unknown node or input 'zzz'"),
    ],
)
def test_each_problem_is_named_and_located(problems, where, line, message):
    found, _ = problems
    assert (where, line) in found, sorted(found)
    assert message in found[(where, line)]


def test_cycle_is_printed_as_a_path(registry):
    text = """\
name: loop
nodes:
  a: {op: toy.add, in: {a: b, b: c}}
  b: {op: toy.add, in: {a: a, b: c}}
  c: {op: toy.const}
outputs: {out: a}
"""
    with pytest.raises(gv.PipelineError, match=r"nodes.a at loop.yaml:3: cycle: a -> b -> a"):
        gv.compile_graph(gv.parse_pipeline(text, "loop.yaml"), registry)


def test_missing_input_value_is_reported_for_a_run(registry):
    text = (
        "name: m\ninputs:\n  x: {type: Float}\nnodes:\n"
        "  c: {op: toy.add, in: {a: x, b: x}}\noutputs: {o: c}\n"
    )
    graph = gv.parse_pipeline(text, "m.yaml")
    gv.compile_graph(graph, registry)  # fine for `validate`
    with pytest.raises(gv.PipelineError, match=r"inputs.x at m.yaml:3: missing input 'x'"):
        gv.compile_graph(graph, registry, provided=set())


def test_type_variables_follow_the_connected_type(registry):
    graph = gv.Graph("tv")
    image = graph.input("image", "GrayImage")
    smooth = graph.add("smooth", "filters.gaussian", image=image)
    graph.add("dark", "toy.darken", image=smooth)  # needs GrayImage: gaussian keeps it
    graph.output("out", "dark")
    compiled = gv.compile_graph(graph, registry)
    assert compiled.steps["smooth"].outputs["out"] is gv.GrayImagePort

    colour = gv.Graph("tv2")
    rgb = colour.input("image", "ColorImage")
    colour.add("smooth", "filters.gaussian", image=rgb)
    colour.add("dark", "toy.darken", image="smooth")
    colour.output("out", "dark")
    with pytest.raises(gv.PipelineError, match=r"'smooth' gives ColorImage but 'dark\.image'"):
        gv.compile_graph(colour, registry)


def test_overrides_and_params_substitution(registry):
    text = (
        "name: s\nparams: {k: 2.0}\nnodes:\n"
        "  c: {op: toy.const, params: {value: '${params.k}'}}\noutputs: {o: c}\n"
    )
    graph = gv.parse_pipeline(text)
    assert gv.compile_graph(graph, registry).steps["c"].params == {"value": 2.0}
    changed = graph.with_overrides({"params.k": 5})
    assert changed.params == {"k": 5}
    assert gv.compile_graph(changed, registry).steps["c"].params == {"value": 5.0}
    direct = gv.Graph("d")
    direct.add("c", "toy.const", params={"value": 1})
    direct.output("o", "c")
    assert gv.compile_graph(direct.with_overrides({"c.value": 7}), registry).steps["c"].params == {
        "value": 7.0
    }
    with pytest.raises(KeyError, match="no node 'cc' \\(did you mean 'c'\\?\\)"):
        graph.with_overrides({"cc.value": 1})


CHECKED_PLUGIN = """
from graphvision import Float, node


def _ordered(**params):
    if params["high"] <= params["low"]:
        raise ValueError(f"high ({params['high']:g}) must exceed low ({params['low']:g})")


@node("checked.clip", check=_ordered)
def clip(x: Float, *, low: float = 0.0, high: float = 1.0) -> Float:
    '''x clipped to [low, high].

    Parameters
    ----------
    x : the value
    low, high : the bounds
    '''
    return min(max(x, low), high)
"""


def test_a_nodes_check_of_its_parameters_together_runs_before_anything(tmp_path):
    plugin = tmp_path / "checked.py"
    plugin.write_text(CHECKED_PLUGIN)
    registry = gv.discover([plugin], entry_points=False)
    text = (
        "name: c\ninputs:\n  x: {type: Float, default: 2.0}\nnodes:\n"
        "  c: {op: checked.clip, in: {x: x}, params: {low: 3.0, high: 1.0}}\noutputs: {y: c}\n"
    )
    pipeline = tmp_path / "c.yaml"
    pipeline.write_text(text)
    with pytest.raises(gv.PipelineError) as caught:
        gv.compile_graph(gv.load_pipeline(pipeline), registry)
    (problem,) = caught.value.problems
    assert problem.where == "nodes.c.params" and problem.line == 5
    assert problem.message == "checked.clip: high (1) must exceed low (3)"
    good = gv.load_pipeline(pipeline).with_overrides({"c.high": 5.0})
    assert gv.run(good, registry, cache=None).outputs["y"] == 3.0
    with pytest.raises(gv.PipelineError, match=r"--set c\.low=9\.0: checked\.clip: high"):
        gv.compile_graph(good.with_overrides({"c.low": 9.0}), registry)
    clip = registry.node("checked.clip")
    with pytest.raises(gv.ParameterError, match=r"checked\.clip: high \(1\) must exceed low"):
        clip.check_call((2.0,), {"low": 3.0, "high": 1.0})


def test_a_bad_value_set_on_the_command_line_is_named_as_such_not_as_the_file(tmp_path):
    pipeline = tmp_path / "p.yaml"
    pipeline.write_text(
        "name: p\ninputs:\n  image: {type: Image, default: 'sample:camera'}\nnodes:\n"
        "  g: {op: colour.to_gray, in: {image: image}}\n"
        "  s: {op: filters.gaussian, in: {image: g}, params: {sigma: 2.0}}\noutputs: {s: s}\n"
    )
    graph = gv.load_pipeline(pipeline).with_overrides({"s.sigma": "abc"})
    with pytest.raises(gv.PipelineError) as caught:
        gv.compile_graph(graph, gv.discover())
    (problem,) = caught.value.problems
    assert problem.where == "--set s.sigma='abc'" and problem.line == 0 and not problem.file
    assert "invalid value 'abc' for parameter 'sigma'" in str(caught.value)


@pytest.mark.parametrize(
    ("pipeline", "overrides", "where", "message"),
    [  # a nested value, a pipeline param used by a node, a value that is not a number
        ("reconstruct", {"camera_b.centre": [1, 2]}, "--set camera_b.centre=[1, 2]", "'centre.2'"),
        ("two_view", {"params.seed": "abc"}, "--set params.seed='abc'", "parameter 'seed'"),
        ("reconstruct", {"camera_a.cx": float("nan")}, "--set camera_a.cx=nan", "finite number"),
    ],
)
def test_values_set_from_the_command_line_are_named_however_they_reach_a_node(
    pipeline, overrides, where, message
):
    graph = gv.load_pipeline(PIPELINES / f"{pipeline}.yaml")
    with pytest.raises(gv.PipelineError) as caught:
        gv.compile_graph(graph.with_overrides(overrides), gv.discover())
    (problem,) = caught.value.problems
    assert problem.where == where and problem.line == 0, str(caught.value)
    assert message in problem.message


@pytest.mark.parametrize("value", [float("nan"), float("inf"), -float("inf")])
def test_no_float_parameter_takes_nan_or_infinity(value):
    graph = gv.load_pipeline(PIPELINES / "denoise.yaml")
    key = next(f"{name}.sigma" for name, decl in graph.nodes.items() if "sigma" in decl.params)
    with pytest.raises(gv.PipelineError, match="Input should be a finite number"):
        gv.compile_graph(graph.with_overrides({key: value}), gv.discover())


def test_a_misspelt_op_still_uses_the_params_it_refers_to(registry):
    text = """\
version: 1
name: misspelt
inputs:
  x: {type: Float, default: 1.0}
params:
  offset: 2
nodes:
  a: {op: toy.ad, in: {a: x, b: x}, params: {offset: "${params.offset}"}}
outputs:
  out: a
"""
    with pytest.raises(gv.PipelineError) as info:
        gv.compile_graph(gv.parse_pipeline(text, "misspelt.yaml"), registry)
    messages = [p.message for p in info.value.problems]
    assert len(messages) == 1 and "unknown op 'toy.ad'" in messages[0]


def test_a_misspelt_op_upstream_of_a_generic_node_is_the_only_problem():
    """A generic node fed by an unknown op has outputs of unknown type, not Array."""
    graph = gv.parse_pipeline((PIPELINES / "coins.yaml").read_text(), "coins.yaml")
    graph.nodes["filled"].op = "morphology.fill_hole"
    with pytest.raises(gv.PipelineError) as info:
        gv.compile_graph(graph, gv.discover())
    messages = [p.message for p in info.value.problems]
    assert len(messages) == 1 and "unknown op 'morphology.fill_hole'" in messages[0], messages


@pytest.mark.parametrize(
    ("params", "where"),
    [
        ("{size: '${params.windw}'}", "nodes.blur.params.size"),
        ("{size: 3, boundary: '${params.windw}'}", "nodes.blur.params.boundary"),
        ("{size: '${params.windw}', nope: 1}", None),
    ],
)
def test_a_mistyped_param_reference_is_one_problem(params, where):
    """Not also the value's type (a string where an integer goes), nor the param it
    misspells reported unused (issue 29 item 12)."""
    text = f"""\
version: 1
name: typo
inputs:
  image: {{type: GrayImage, default: "sample:camera"}}
params:
  window: 5
nodes:
  blur: {{op: filters.median, in: {{image: image}}, params: {params}}}
outputs:
  blur: blur
"""
    with pytest.raises(gv.PipelineError) as caught:
        gv.compile_graph(gv.parse_pipeline(text, "typo.yaml"), gv.discover())
    messages = [str(problem) for problem in caught.value.problems]
    typo = [m for m in messages if "unknown pipeline param '${params.windw}'" in m]
    assert len(typo) == 1 and "(did you mean 'window'?)" in typo[0]
    assert not any("unused pipeline param" in m or "valid integer" in m for m in messages)
    if where is not None:
        assert messages == typo and typo[0].startswith(f"{where} at typo.yaml:8")
    else:  # a real second problem is still reported
        assert len(messages) == 2
        assert any("unknown parameter 'nope' of filters.median" in m for m in messages)
