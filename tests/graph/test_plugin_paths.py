"""A loaded pipeline's plugins, those of its file and those added in Python, are read from
the file's folder; a graph built in Python reads its plugins from the working folder."""

from __future__ import annotations

import copy
import pickle
from pathlib import Path

import pytest

import graphvision as gv
from graphvision.graph.plugin_paths import PluginPaths

NODES = '''
from graphvision import Float, node

@node("mine.one")
def one() -> Float:
    """One."""
    return 1.0
'''

PIPELINE = """version: 1
name: p
plugins: [first.py]
nodes:
  z: {op: pyramids.zone_plate}
outputs:
  z: z
"""


@pytest.fixture
def folder(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """tmp/try/ holds p.yaml, first.py and my_nodes.py; the working folder is tmp/."""
    (tmp_path / "try").mkdir()
    (tmp_path / "try" / "p.yaml").write_text(PIPELINE)
    (tmp_path / "try" / "first.py").write_text("")
    (tmp_path / "try" / "my_nodes.py").write_text(NODES)
    monkeypatch.chdir(tmp_path)
    return tmp_path / "try"


def test_a_plugin_added_to_a_loaded_pipeline_is_read_from_its_folder(folder, tmp_path):
    graph = gv.load_pipeline("try/p.yaml")
    graph.plugins.append("my_nodes.py")
    graph.plugins += [str(tmp_path / "abs.py")]  # an absolute path is kept
    graph.plugins.insert(0, "lib")
    assert graph.plugins == ["try/lib", "try/first.py", "try/my_nodes.py", str(tmp_path / "abs.py")]
    graph.plugins[-1] = "second.py"
    assert graph.plugins[-1] == "try/second.py"


def test_a_loaded_pipeline_runs_a_node_of_a_plugin_added_beside_it(folder):
    """It failed: 'plugin path my_nodes.py does not exist' (looked up in the working folder)."""
    graph = gv.load_pipeline("try/p.yaml")
    graph.plugins.append("my_nodes.py")
    graph.output("one", graph.add("one", "mine.one"))
    assert gv.run(graph).outputs["one"] == 1.0


def test_a_graph_built_in_python_reads_its_plugins_from_the_working_folder(folder, tmp_path):
    graph = gv.Graph("built")
    graph.plugins.append("try/my_nodes.py")
    graph.output("one", graph.add("one", "mine.one"))
    assert graph.plugins == ["try/my_nodes.py"]
    assert gv.run(graph).outputs["one"] == 1.0


def test_a_copy_or_a_pickle_of_the_plugins_is_not_placed_twice(folder):
    graph = gv.load_pipeline("try/p.yaml")
    for again in (
        copy.deepcopy(graph),
        pickle.loads(pickle.dumps(graph)),
        graph.with_backends("numpy"),
    ):
        assert again.plugins == ["try/first.py"]
        again.plugins.append("my_nodes.py")  # still placed in the file's folder
        assert again.plugins == ["try/first.py", "try/my_nodes.py"]
    assert copy.copy(PluginPaths(["a.py"], "x")) == ["a.py"]


def test_an_op_of_a_plugin_that_failed_to_load_says_why_in_python(folder):
    """Python prints no warning for a plugin that fails to load: the error pointed at one
    ('its warning says where') that never came (found by the new user)."""
    graph = gv.Graph("built")
    graph.plugins.append("try/missing.py")
    graph.output("one", graph.add("one", "mine.one"))
    with pytest.raises(gv.PipelineError) as caught:
        gv.run(graph)
    said = str(caught.value)
    assert "plugin try/missing.py (plugin path try/missing.py does not exist) failed" in said
    assert "warning" not in said
