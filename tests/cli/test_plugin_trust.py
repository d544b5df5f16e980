"""Drawing or describing a pipeline never runs its code (issue 29 B): graph lists the local
plugins a pipeline names without importing them; run and validate (which checks what run
would run) import only plugins inside the pipeline's folder, unless
--allow-outside-plugins, and say which files they load."""

from __future__ import annotations

from pathlib import Path

import pytest

import graphvision as gv
from graphvision.cli import main

EVIL = """
from pathlib import Path
Path({marker!r}).write_text("ran")
from graphvision import Float, node

@node("evil.one")
def one() -> Float:
    '''One.'''
    return 1.0
"""

PIPELINE = """version: 1
name: trust
plugins:
  - {plugin}
nodes:
  n: {{op: {op}}}
outputs:
  value: n
"""


def setup(tmp_path: Path, plugin_at: str, op: str = "evil.one") -> tuple[Path, Path]:
    """A pipeline in tmp/p/ naming a plugin at ``plugin_at`` (relative to tmp/p/)."""
    marker = tmp_path / "marker"
    folder = tmp_path / "p"
    folder.mkdir()
    plugin = (folder / plugin_at).resolve()
    plugin.parent.mkdir(parents=True, exist_ok=True)
    plugin.write_text(EVIL.format(marker=str(marker)))
    pipeline = folder / "p.yaml"
    pipeline.write_text(PIPELINE.format(plugin=plugin_at, op=op))
    return pipeline, marker


def run_cli(capsys, *args) -> tuple[int, str, str]:
    status = main([str(a) for a in args])
    out, err = capsys.readouterr()
    assert "Traceback" not in err
    return status, out, err


def test_drawing_a_pipeline_imports_none_of_its_plugins(capsys, tmp_path):
    pipeline, marker = setup(tmp_path, "evil.py")
    status, _, err = run_cli(capsys, "graph", pipeline)
    assert not marker.exists()
    assert "names local plugins" in err and "evil.py" in err and "not imported" in err
    assert status == 2 and "unknown op 'evil.one'" in err  # its ops cannot be checked
    assert f"the pipeline's plugins ({pipeline.parent / 'evil.py'}) are not imported" in err
    assert "`plugins: [PATH]` in the pipeline file" not in err  # (it has them already)
    status, _, err = run_cli(capsys, "graph", pipeline, "--plugins", pipeline.parent / "evil.py")
    assert status == 0 and marker.exists()  # asked for by name: loaded and checked
    assert "names local plugins" not in err and "pass --plugins" not in err


def test_validate_loads_a_pipelines_plugins_as_run_does(capsys, tmp_path):
    """A pipeline run accepts is not refused by validate for an op of its own plugins
    (validate refused every op of them: it did not import them)."""
    pipeline, marker = setup(tmp_path, "lib/evil.py")
    status, out, err = run_cli(capsys, "validate", pipeline)
    assert status == 0 and out == f"{pipeline}: ok\n" and marker.exists()
    assert f"loading local plugins: {pipeline.parent / 'lib/evil.py'}" in err
    assert "not imported" not in err


@pytest.mark.parametrize(
    ("code", "line", "error"),
    [
        ("x = 1\ndef f(:\n    pass\n", 2, "SyntaxError: invalid syntax"),
        ("x = 1\nimport graphvision_no_such_module\n", 2, "ModuleNotFoundError: No module"),
        ("import numpy\n\nnumpy.zeros(-1)\n", 3, "ValueError: negative dimensions"),
        ("import sys\nsys.exit(3)\n", 2, "it called sys.exit(3) while being imported"),
        # a traceback, the command ended (found by TRY45b)
        ("class B(BaseException):\n    pass\nraise B('at import')\n", 3, "B: at import"),
        ("raise GeneratorExit('closed')\n", 1, "GeneratorExit: closed"),
    ],
)
@pytest.mark.parametrize("command", ["validate", "run"])
def test_a_plugin_that_fails_to_load_is_named_with_its_file_and_line(
    capsys, tmp_path, code, line, error, command
):
    """The place is the plugin's line (a syntax error was placed in importlib, a library's
    error in the library), and the op it should have given says the plugin failed; a plugin
    calling sys.exit() at import ended the command with its status and not a word."""
    pipeline, _marker = setup(tmp_path, "evil.py")
    plugin = pipeline.parent / "evil.py"
    plugin.write_text(code)
    extra = ["--no-cache"] if command == "run" else []
    status, _, err = run_cli(capsys, command, pipeline, *extra)
    assert status == 2
    assert f"warning: plugin '{plugin}' failed to load: {error}" in err
    assert f"({plugin}:{line})" in err
    assert f"'evil', and plugin {plugin} ({error}" in err  # why, in the error itself


@pytest.mark.parametrize("command", ["graph"])
def test_the_unread_plugins_note_names_only_plugins_not_given_with_plugins(
    capsys, tmp_path, monkeypatch, command
):
    pipeline, _marker = setup(tmp_path, "evil.py", op="pyramids.zone_plate")
    other = pipeline.parent / "other.py"
    other.write_text("")
    pipeline.write_text(pipeline.read_text().replace("  - evil.py", "  - evil.py\n  - other.py"))
    monkeypatch.chdir(tmp_path)  # the same file spelled relative to the working folder
    _status, _, err = run_cli(capsys, command, pipeline, "--plugins", "p/./evil.py")
    assert "names local plugins" in err and "other.py" in err and "evil.py" not in err


def test_a_pipeline_that_uses_no_op_of_its_plugins_draws_without_them(capsys, tmp_path):
    pipeline, marker = setup(tmp_path, "evil.py", op="pyramids.zone_plate")
    status, out, _err = run_cli(capsys, "graph", pipeline, "--format", "dot")
    assert status == 0 and "digraph" in out and not marker.exists()


def test_run_loads_a_plugin_beside_its_pipeline_and_says_so(capsys, tmp_path):
    pipeline, marker = setup(tmp_path, "lib/evil.py")
    status, _out, err = run_cli(capsys, "run", pipeline, "--no-cache")
    assert status == 0 and marker.exists()
    assert f"loading local plugins: {pipeline.parent / 'lib/evil.py'}" in err


@pytest.mark.parametrize("where", ["../elsewhere/evil.py", "ABSOLUTE", "link.py"])
def test_run_refuses_a_plugin_outside_its_pipelines_folder(capsys, tmp_path, where):
    outside = tmp_path / "elsewhere" / "evil.py"
    if where == "ABSOLUTE":
        where = str(outside)
    pipeline, marker = setup(tmp_path, "../elsewhere/evil.py")
    if where == "link.py":
        (pipeline.parent / "link.py").symlink_to(outside)  # inside by name, outside in fact
    pipeline.write_text(PIPELINE.format(plugin=where, op="evil.one"))
    for command in ("run", "validate", "graph"):
        status, _, err = run_cli(capsys, command, pipeline)
        assert status == 2, err
        assert f"{pipeline}:4" in err and "is outside the pipeline's folder" in err
        assert "--allow-outside-plugins" in err
    assert not marker.exists()
    status, _, err = run_cli(capsys, "run", pipeline, "--allow-outside-plugins", "--no-cache")
    assert status == 0 and marker.exists() and "loading local plugins" in err


@pytest.mark.parametrize("empty", ['""', "' '"])
def test_an_empty_plugin_path_is_refused_not_read_as_the_pipelines_folder(capsys, tmp_path, empty):
    """``Path("")`` is the current folder: an empty ``plugins:`` entry would import every
    file beside the pipeline (a tryer's own scripts ran)."""
    pipeline, marker = setup(tmp_path, "evil.py")  # beside the pipeline: run if the folder is
    pipeline.write_text(PIPELINE.format(plugin=empty, op="evil.one"))
    for command in ("run", "validate", "graph"):
        status, _, err = run_cli(capsys, command, pipeline, "--allow-outside-plugins")
        assert status == 2, err
        assert f"plugins.0 at {pipeline}:4: the plugin path is empty" in err
    assert not marker.exists()


def test_an_empty_plugin_path_given_to_discover_is_a_failed_plugin_not_this_folder(
    tmp_path, monkeypatch
):
    (tmp_path / "evil.py").write_text(EVIL.format(marker=str(tmp_path / "marker")))
    monkeypatch.chdir(tmp_path)
    registry = gv.discover([""], entry_points=False)
    assert [p.error for p in registry.failed_plugins()] == [
        "the plugin path is empty: name a file or folder"
    ]
    assert not (tmp_path / "marker").exists()
