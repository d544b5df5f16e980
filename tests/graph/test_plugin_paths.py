"""A loaded pipeline's plugins, those of its file and those added in Python, are read from
the file's folder; a graph built in Python reads its plugins from the working folder."""

from __future__ import annotations

import copy
import os
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
    placed = [str(folder / name) for name in ("lib", "first.py", "my_nodes.py")]
    assert list(graph.plugins) == [*placed, str(tmp_path / "abs.py")]  # as the process opens
    assert graph.plugins == ["lib", "first.py", "my_nodes.py", str(tmp_path / "abs.py")]
    graph.plugins[-1] = "second.py"
    assert graph.plugins[-1] == str(folder / "second.py")


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
        assert list(again.plugins) == [str(folder / "first.py")]
        again.plugins.append("my_nodes.py")  # still placed in the file's folder
        assert list(again.plugins) == [str(folder / "first.py"), str(folder / "my_nodes.py")]
    assert list(copy.copy(PluginPaths(["a.py"], "x"))) == ["a.py"]


def test_an_op_of_a_plugin_that_failed_to_load_says_why_in_python(folder):
    """The error says why itself: it pointed at a warning ('its warning says where') that
    Python did not print then (found by the new user)."""
    graph = gv.Graph("built")
    graph.plugins.append("try/missing.py")
    graph.output("one", graph.add("one", "mine.one"))
    with pytest.raises(gv.PipelineError) as caught, pytest.warns(UserWarning, match="missing"):
        gv.run(graph)
    said = str(caught.value)
    assert "plugin try/missing.py (plugin path try/missing.py does not exist) failed" in said
    assert "warning" not in said


def test_a_loaded_pipeline_finds_its_plugins_after_the_working_folder_changes(folder):
    """Its folder was kept relative: after os.chdir its plugins were looked up from there."""
    (folder / "p.yaml").write_text(PIPELINE.replace("first.py", "my_nodes.py"))
    graph = gv.load_pipeline("try/p.yaml")
    graph.output("one", graph.add("one", "mine.one"))
    os.chdir(folder.parent.parent)
    assert gv.run(graph, cache=None).outputs["one"] == 1.0


def test_the_text_of_a_loaded_pipeline_names_its_plugins_as_its_file_does(folder):
    """It named them as the process opens them (try/my_nodes.py), so the text written
    beside the pipeline did not load; read back, it still gives an equal graph."""
    graph = gv.load_pipeline("try/p.yaml")
    graph.plugins.append("my_nodes.py")
    graph.plugins.append("/elsewhere/x.py")
    text = gv.dump_pipeline(graph)
    assert "plugins:\n- first.py\n- my_nodes.py\n- /elsewhere/x.py\n" in text
    assert gv.parse_pipeline(text) == graph
    assert graph == gv.parse_pipeline(text)
    graph.plugins.pop()
    (folder / "copy.yaml").write_text(gv.dump_pipeline(graph))
    again = gv.load_pipeline(folder / "copy.yaml")
    assert again == graph and list(again.plugins) == list(graph.plugins)


def test_the_text_for_another_file_names_the_plugins_from_its_folder(folder, tmp_path):
    graph = gv.load_pipeline("try/p.yaml")
    (tmp_path / "other").mkdir()
    for_other = gv.dump_pipeline(graph, path=tmp_path / "other" / "p.yaml")
    assert f"plugins:\n- {folder / 'first.py'}\n" in for_other  # outside its folder
    for_parent = gv.dump_pipeline(graph, path="p.yaml")  # the working folder: tmp
    assert "plugins:\n- try/first.py\n" in for_parent
    (tmp_path / "p.yaml").write_text(for_parent)
    assert list(gv.load_pipeline("p.yaml").plugins) == list(graph.plugins)


def test_a_graph_built_in_python_writes_its_plugins_as_given(folder):
    graph = gv.Graph("built")
    graph.plugins.append("try/my_nodes.py")
    assert "plugins:\n- try/my_nodes.py\n" in gv.dump_pipeline(graph)
    assert "plugins:\n- my_nodes.py\n" in gv.dump_pipeline(graph, path="try/p.yaml")


def test_a_list_given_to_a_loaded_pipeline_is_read_from_its_folder(folder):
    """It stayed a plain list, read from the working folder ('plugin path my_nodes.py does
    not exist'), where appending to it read the path beside the pipeline (found by TRY44)."""
    graph = gv.load_pipeline("try/p.yaml")
    graph.plugins = ["my_nodes.py"]
    assert list(graph.plugins) == [str(folder / "my_nodes.py")]
    graph.output("one", graph.add("one", "mine.one"))
    assert gv.run(graph).outputs["one"] == 1.0


def test_a_path_up_and_back_names_the_plugin_once(folder):
    graph = gv.load_pipeline("try/p.yaml")
    graph.plugins.append("../try/first.py")
    assert list(graph.plugins) == [str(folder / "first.py")] * 2


@pytest.mark.parametrize("given", ["x/nasty.py", Path("x/nasty.py")])
def test_one_path_in_place_of_the_list_is_refused(folder, given):
    """It was taken letter by letter ('.' the pipeline's folder, '/' the root), found by an
    adversary."""
    for graph in (gv.load_pipeline("try/p.yaml"), gv.Graph("built")):
        with pytest.raises(
            TypeError, match=r"graph.plugins takes a list of paths \(\['x/nasty.py'\]\)"
        ):
            graph.plugins = given


ONE_PATH_ADDED = [
    lambda plugins: plugins.__iadd__("a.py"),
    lambda plugins: plugins.extend("a.py"),
    lambda plugins: plugins.__setitem__(slice(None), "a.py"),
]


@pytest.mark.parametrize("adds", ONE_PATH_ADDED, ids=["+=", "extend", "slice"])
def test_one_path_added_in_place_of_a_list_is_refused(folder, adds):
    """``+=``, ``extend`` and a slice took it letter by letter ('.' imported every module
    of the pipeline's folder; found by TRY45), where ``=`` refused it."""
    for graph in (gv.load_pipeline("try/p.yaml"), gv.Graph("built")):
        before = list(graph.plugins)
        with pytest.raises(TypeError, match=r"takes a list of paths \(\['a.py'\]\)"):
            adds(graph.plugins)
        assert list(graph.plugins) == before


@pytest.mark.parametrize(
    ("given", "named"),
    [(1, "int 1"), (["x.py"], "list ['x.py']"), (b"x.py", "bytes b'x.py'")],
)
def test_an_item_that_is_not_a_path_is_refused(folder, given, named):
    """They were written as text ('/try/1', "/try/['x.py']")."""
    graph = gv.load_pipeline("try/p.yaml")
    message = rf"holds paths \(str or pathlib.Path\), not {named}"
    with pytest.raises(TypeError, match=message.replace("[", r"\[").replace("]", r"\]")):
        graph.plugins.append(given)
    with pytest.raises(TypeError, match="holds paths"):
        graph.plugins = [given]
    with pytest.raises(TypeError, match=r"takes a list of paths, not None"):
        graph.plugins = None
    assert list(graph.plugins) == [str(folder / "first.py")]


def test_a_path_as_its_file_names_it_is_found_in_the_list(folder):
    """``in``, ``index``, ``count`` and ``remove`` found only the placed path."""
    graph = gv.load_pipeline("try/p.yaml")
    graph.plugins.append(Path("my_nodes.py"))
    assert "first.py" in graph.plugins and Path("my_nodes.py") in graph.plugins
    assert graph.plugins.index("my_nodes.py") == 1 and graph.plugins.count("first.py") == 1
    graph.plugins.remove("first.py")
    assert list(graph.plugins) == [str(folder / "my_nodes.py")]


def test_a_built_graphs_plugins_are_checked_as_a_loaded_ones(folder):
    graph = gv.Graph("built", plugins=["a.py"])
    assert isinstance(graph.plugins, PluginPaths) and graph.plugins == ["a.py"]
    with pytest.raises(TypeError, match="holds paths"):
        gv.Graph("built", plugins=[3])


def test_a_plugin_that_fails_to_load_is_warned_of_at_the_users_run(folder):
    """From Python a run whose ops were all found went on without a word (the command line
    warned; found by TRY45)."""
    (folder / "bad.py").write_text("raise RuntimeError('boom')\n")
    graph = gv.load_pipeline("try/p.yaml")
    graph.plugins[:] = ["bad.py", "missing.py"]
    with pytest.warns(UserWarning) as warned:
        gv.run(graph)
        gv.sweep(graph, {"z.size": [16, 32]})
    messages = [str(w.message) for w in warned if "failed to load" in str(w.message)]
    assert messages == 2 * [
        f"plugin '{folder / 'bad.py'}' failed to load: RuntimeError: boom ({folder / 'bad.py'}:1)",
        f"plugin '{folder / 'missing.py'}' failed to load: plugin path {folder / 'missing.py'} "
        "does not exist",
    ]
    assert {w.filename for w in warned if "failed to load" in str(w.message)} == {__file__}
