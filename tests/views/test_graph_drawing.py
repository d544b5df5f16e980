"""A batch's reports draw one graph again and again: its layout is made once, the nodes'
times written into it, and each drawing is the one ``graph_svg`` makes."""

from __future__ import annotations

from pathlib import Path

import graphvision as gv
from graphvision.graph.svg import graph_svg
from graphvision.views import graph_view
from graphvision.views.graph_view import graph_drawing

PIPELINE = Path(__file__).parents[2] / "pipelines" / "coins.yaml"


def test_each_drawing_is_graph_svgs_own_with_its_times():
    graph_view._DRAWINGS.clear()
    graph = gv.load_pipeline(PIPELINE)
    status = dict.fromkeys(graph.nodes, "computed")
    status["overlay"] = "failed"
    runs = [  # the same label lengths (a kept layout), then longer ones (a new layout)
        {name: 0.0012 * (k + 1) for k, name in enumerate(graph.nodes)},
        {name: 0.0012 * (k + 1) + 0.0001 for k, name in enumerate(graph.nodes)},
        {name: 0.5 + 0.01 * k for k, name in enumerate(graph.nodes)},
        {name: 2.5 for name in list(graph.nodes)[:4]},  # some nodes without a time
    ]
    for seconds in runs:
        assert graph_drawing(graph, status, seconds) == graph_svg(graph, status, seconds)
    assert len(graph_view._DRAWINGS) == 3  # the second run reused the first one's layout
    # another status, or another graph of the same name: drawn anew, as graph_svg draws it
    status["overlay"] = "computed"
    assert graph_drawing(graph, status, runs[1]) == graph_svg(graph, status, runs[1])
    graph.nodes.pop("overlay")
    graph.outputs.pop("overlay")
    assert graph_drawing(graph, status, runs[1]) == graph_svg(graph, status, runs[1])
    assert len(graph_view._DRAWINGS) == 5


def test_the_pages_graph_data_is_jsons_own_text_for_each_run():
    import json
    import math

    from graphvision.compiler.compile import compile_graph
    from graphvision.views.graph_view import graph_data, graph_json

    pipelines = PIPELINE.parent
    compiled = {
        name: compile_graph(graph, gv.discover(graph.plugins))
        for name in ("coins.yaml", "homography.yaml")
        for graph in [gv.load_pipeline(pipelines / name)]
    }
    coins = compiled["coins.yaml"]
    runs = [  # states and times as runs give them: some nodes without one, odd floats
        ({"binary": "computed", "gray": "cached"}, {"binary": 0.25}),
        (dict.fromkeys(coins.steps, "computed"), dict.fromkeys(coins.steps, 1e-7)),
        ({"gray": "failed", "binary": "skipped"}, {"gray": math.nan, "binary": math.inf}),
        ({}, {"gray": 3, "binary": 0.1 + 0.2}),
    ]
    for status, seconds in runs:
        for graph in compiled.values():
            text = graph_json(graph, status, seconds)
            assert text == json.dumps(graph_data(graph, status, seconds))
    text = graph_json(coins, {"gray": "failed"}, {"gray": math.nan, "binary": 0.30000000000000004})
    assert '"id": "gray", "kind": "node", "op": "colour.to_gray", "status": "failed", ' in text
    assert '"seconds": NaN}' in text and '"seconds": 0.30000000000000004}' in text
    assert '"id": "binary", "kind": "node", "op": "threshold.local", "status": "", ' in text
    assert text.startswith('{"nodes": [{"id": "image", "kind": "input", "type": "Image"}, ')
