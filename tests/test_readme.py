"""The README's "Writing a node" works when followed to the letter: its code, run as written."""

from __future__ import annotations

import os
import re
from pathlib import Path

README = Path(__file__).parent.parent / "README.md"


def _section_code(title: str) -> list[str]:
    text = README.read_text()
    section = text[text.index(f"## {title}\n") :]
    section = section[: section.index("\n## ", 4)]
    return re.findall(r"```python\n(.*?)```", section, flags=re.DOTALL)


def test_the_writing_a_node_example_runs_as_written(tmp_path, monkeypatch):
    plugin, script = _section_code("Writing a node")[:2]
    (tmp_path / "my_nodes.py").write_text(plugin)
    monkeypatch.chdir(tmp_path)
    namespace: dict = {}
    exec(compile(script, "README script", "exec"), namespace)
    result = namespace["result"]
    assert result.outputs["after"] < result.outputs["before"]
    assert os.path.exists("my_nodes.py")


def test_the_example_plugin_passes_check_plugin(tmp_path, monkeypatch):
    import importlib.util

    from graphvision.testing import check_plugin

    plugin = _section_code("Writing a node")[0]
    (tmp_path / "readme_nodes.py").write_text(plugin)
    spec = importlib.util.spec_from_file_location("readme_nodes", tmp_path / "readme_nodes.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    assert set(check_plugin(module).nodes) >= {"mine.vignette", "mine.mean"}


def test_the_python_section_runs_as_written(tmp_path, monkeypatch, capsys):
    build, ports = _section_code("Python")[:2]
    assert "gv.run(" in build and '["descriptors"]' in ports
    monkeypatch.chdir(tmp_path)
    namespace: dict = {}
    exec(compile(build + ports, "README Python section", "exec"), namespace)
    graph, result = namespace["g"], namespace["result"]
    assert result.outputs["blurred"].shape == (512, 512)
    outputs = namespace["gv"].run(graph, cache=None).outputs
    assert len(outputs["keypoints"]) > 100  # SIFT on the astronaut, read by port
    assert "blur" in capsys.readouterr().out  # the record's table was printed
