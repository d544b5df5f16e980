"""A problem with a node, input or output added in Python to a loaded pipeline is placed
at the call that added it, named so, not at the pipeline's ``nodes:`` line."""

from __future__ import annotations

import inspect

import pytest

import graphvision as gv

PIPELINE = """version: 1
name: p
inputs:
  image: {type: Image, default: "sample:camera"}
nodes:
  gray: {op: colour.to_gray, in: {image: image}}
  blur: {op: filters.gaussian, in: {image: gray}, params: {sigma: -1}}
outputs:
  blur: blur
"""


def here() -> int:
    """The line of the caller."""
    frame = inspect.currentframe()
    assert frame is not None and frame.f_back is not None
    return frame.f_back.f_lineno


def test_problems_of_nodes_added_in_python_are_placed_at_the_call(tmp_path):
    path = tmp_path / "p.yaml"
    path.write_text(PIPELINE)
    graph = gv.load_pipeline(path)
    line = here() + 1
    graph.add("bad", "filters.median", image="nowhere", params={"size": -3})
    graph.add("typo", "filters.medain", image="gray")
    graph.output("late", "missing")
    with pytest.raises(gv.PipelineError) as caught:
        gv.compile_graph(graph, gv.discover())
    problems = [str(p) for p in caught.value.problems]
    place = f"at {__file__}:{{}} (added in Python)"
    assert f"nodes.bad.in.image {place.format(line)}: unknown node or input 'nowhere'" in problems
    assert any(
        p.startswith(f"nodes.bad.params.size {place.format(line)}: invalid value -3")
        for p in problems
    )
    assert any(
        p.startswith(f"nodes.typo.op {place.format(line + 1)}: unknown op") for p in problems
    )
    assert any(p.startswith(f"outputs.late {place.format(line + 2)}: ") for p in problems)
    # the file's own node keeps its line; nothing is placed at the nodes: line (5)
    assert any(p.startswith(f"nodes.blur.params.sigma at {path}:7: ") for p in problems)
    assert not any(f"{path}:5" in p for p in problems)
    assert len(problems) == 5


def test_a_graph_built_in_python_places_its_problems_at_its_calls():
    graph = gv.Graph("built")
    line = here() + 1
    image = graph.input("image", "Image", default="sample:camera")
    graph.output("out", graph.add("blur", "filters.gaussian", image=image, params={"sigma": 0}))
    with pytest.raises(gv.PipelineError) as caught:
        gv.compile_graph(graph, gv.discover())
    (problem,) = caught.value.problems
    assert str(problem).startswith(
        f"nodes.blur.params.sigma at {__file__}:{line + 1} (added in Python): invalid value 0"
    )


def test_a_script_in_a_folder_named_like_the_package_is_the_callers_place():
    """graphvision_examples/script.py began with the package's folder name and was taken
    for the engine's own: its problems had no place (found by the tryer)."""
    from pathlib import Path

    root = Path(gv.__file__).resolve().parent
    script = str(root.parent / f"{root.name}_examples" / "script.py")
    graph = gv.Graph("built")
    exec(compile('graph.add("blur", "filters.gaussian")\n', script, "exec"), {"graph": graph})
    assert graph.added_in_python["nodes.blur"] == (script, 1)


def smooth(graph: gv.Graph, name: str, sigma: float) -> gv.Ref:
    """A helper the graph is passed to: its nodes are placed where it is called."""
    return graph.add(name, "filters.gaussian", image="gray", params={"sigma": sigma})


def two_blurs() -> gv.Graph:
    """A builder that makes its graph: its nodes are placed at its own calls."""
    graph = gv.parse_pipeline(PIPELINE.replace("sigma: -1", "sigma: 1"), "p.yaml")
    graph.add("own", "filters.gaussian", image="gray", params={"sigma": -2})
    return graph


def test_a_node_a_helper_adds_is_placed_where_the_helper_is_called():
    """It was placed at the helper's line, the same for every node it adds."""
    graph = gv.parse_pipeline(PIPELINE.replace("sigma: -1", "sigma: 1"), "p.yaml")
    first = here() + 1
    smooth(graph, "one", -1.0)
    smooth(graph, "two", -2.0)
    with pytest.raises(gv.PipelineError) as caught:
        gv.compile_graph(graph, gv.discover())
    places = {p.where: (p.file, p.line) for p in caught.value.problems}
    assert places["nodes.one.params.sigma"] == (__file__, first)
    assert places["nodes.two.params.sigma"] == (__file__, first + 1)


def test_a_node_a_builder_adds_to_its_own_graph_is_placed_at_its_add():
    with pytest.raises(gv.PipelineError) as caught:
        gv.compile_graph(two_blurs(), gv.discover())
    (problem,) = caught.value.problems
    line = two_blurs.__code__.co_firstlineno + 3
    assert (problem.where, problem.file, problem.line) == ("nodes.own.params.sigma", __file__, line)
