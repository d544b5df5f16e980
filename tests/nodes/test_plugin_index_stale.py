"""The plugin index is never recorded from modules other than those on disk (found by an
earlier adversary): a plugin imported before its file was edited, then discovered, wrote
the old nodes under the new file's key; a plugin whose nodes live in a second top-level
module of its distribution was keyed by its entry package alone, so an edit of the other
module was served the old index."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
import time
from pathlib import Path

from graphvision.nodes import plugin_modules

from .test_plugin_index import _distribution, _package

NODE = '''
from graphvision import Float, node

__all__ = ["scale"]


@node("fakeplug.scale")
def scale(x: Float, *, factor: float = 2.0) -> Float:
    """First summary of the node.

    Parameters
    ----------
    x : Float
        Value.
    factor : float
        Factor.
    """
    return x * factor
'''


def _environment(tmp_path: Path) -> dict[str, str]:
    return {
        **os.environ,
        "PYTHONPATH": str(tmp_path / "site"),
        "GRAPHVISION_CACHE_DIR": str(tmp_path / "c"),
    }


def _python(tmp_path: Path, *args: str) -> subprocess.CompletedProcess:
    done = subprocess.run(
        [sys.executable, *args],
        env=_environment(tmp_path),
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert done.returncode == 0, done.stderr
    return done


def _nodes(tmp_path: Path) -> str:
    return _python(tmp_path, "-m", "graphvision", "nodes").stdout


def _index_files(tmp_path: Path) -> list[Path]:
    return sorted((tmp_path).glob("c-plugin-index-*.json"))


IMPORT_EDIT_DISCOVER = """
import pathlib, sys
import fakeplug_nodes  # imported before any discovery (a notebook's first cell)
import graphvision as gv
module = pathlib.Path(sys.argv[1])
if sys.argv[2] == "edit":
    module.write_text(module.read_text().replace("First summary", "Other summary"))
registry = gv.discover()
print(registry.nodes["fakeplug.scale"].summary)
"""


def test_a_plugin_imported_before_its_edit_is_never_recorded(tmp_path):
    _distribution(tmp_path / "site")
    module = _package(tmp_path / "site", "First summary of the node.")
    ran = _python(tmp_path, "-c", IMPORT_EDIT_DISCOVER, str(module), "edit")
    assert ran.stdout.strip() == "First summary of the node."  # the module it imported
    assert not _index_files(tmp_path)  # not recorded under the edited file's key
    assert "Other summary of the node." in _nodes(tmp_path)


def test_a_plugin_imported_before_a_discovery_and_not_edited_is_recorded(tmp_path):
    _distribution(tmp_path / "site")
    module = _package(tmp_path / "site", "First summary of the node.")
    time.sleep(0.2)  # its files older than the process by more than the clocks' tick
    ran = _python(tmp_path, "-c", IMPORT_EDIT_DISCOVER, str(module), "keep")
    assert ran.stdout.strip() == "First summary of the node."
    assert len(_index_files(tmp_path)) == 1
    assert "First summary of the node." in _nodes(tmp_path)


def _two_modules(site: Path) -> Path:
    """A distribution whose entry package re-exports a node of a second top-level module."""
    _distribution(site)
    package = site / "fakeplug_nodes"
    package.mkdir()
    (package / "__init__.py").write_text(
        '"""Entry."""\nfrom fakeplug_impl import scale\n\n__all__ = ["scale"]\n'
    )
    (site / "fakeplug_impl.py").write_text(textwrap.dedent(NODE))
    return site / "fakeplug_impl.py"


def test_an_edit_of_another_module_of_the_distribution_shows_at_once(tmp_path):
    other = _two_modules(tmp_path / "site")
    assert "First summary of the node." in _nodes(tmp_path)  # discovered, index written
    [index] = _index_files(tmp_path)
    assert "First summary of the node." in _nodes(tmp_path)  # from the index
    other.write_text(other.read_text().replace("First summary", "Other summary"))
    assert "Other summary of the node." in _nodes(tmp_path)
    assert "Other summary of the node." in _nodes(tmp_path)  # the index written again
    [index] = _index_files(tmp_path)  # which records the other module's digest
    assert '"modules": {"fakeplug_impl": "' in index.read_text()


def test_a_process_start_is_known_and_before_now():
    start = plugin_modules.process_start_ns()
    assert start is not None and 0 < time.time_ns() - start < 86_400 * 10**9
