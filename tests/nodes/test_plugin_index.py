"""The plugin index: same listings as a discovery, never stale, lazy parameter models."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
from importlib.metadata import EntryPoint
from pathlib import Path
from typing import Annotated

import pytest
import xxhash
from pydantic import Field

import graphvision as gv
from graphvision.cli import main
from graphvision.nodes import plugin_index as _plugin_index
from graphvision.nodes.signature import build_spec

from ..conftest import TOY


def cli(capsys, *args):
    status = main([str(a) for a in args])
    out, err = capsys.readouterr()
    assert "Traceback" not in err
    return status, out, err


def index_files() -> list[Path]:
    stem = _plugin_index._index_stem()
    return sorted(stem.parent.glob(f"{stem.name}*.json"))


def refuse_discovery(*args, **kwargs):
    raise AssertionError("plugins were discovered although the index matches")


@pytest.mark.parametrize(
    "command",
    [
        ("nodes",),
        ("nodes", "--json"),
        ("describe", "filters.gaussian"),
        ("describe", "geometry.warp"),
    ],
)
def test_the_index_prints_what_a_discovery_prints(capsys, monkeypatch, command):
    assert not index_files()
    status, discovered, _ = cli(capsys, *command)  # no index yet: discovers, writes it
    assert status == 0 and len(index_files()) == 1
    monkeypatch.setattr("graphvision.nodes.plugins.discover", refuse_discovery)
    status, indexed, _ = cli(capsys, *command)
    assert status == 0 and indexed == discovered


def test_an_unknown_op_is_named_from_the_index_as_from_a_discovery(capsys, monkeypatch):
    status, _, first = cli(capsys, "describe", "filters.gausian")
    monkeypatch.setattr("graphvision.nodes.plugins.discover", refuse_discovery)
    status_again, _, again = cli(capsys, "describe", "filters.gausian")
    assert status == status_again == 2 and first == again
    assert "unknown op 'filters.gausian' (did you mean 'filters.gaussian'?)" in again


def test_local_plugins_are_always_discovered(capsys):
    cli(capsys, "nodes")  # writes the index
    status, out, _ = cli(capsys, "--plugins", TOY, "nodes")
    assert status == 0 and "toy." in out


def test_an_unreadable_index_is_rebuilt(capsys):
    _, first, _ = cli(capsys, "nodes")
    [index] = index_files()
    index.write_text("{not json")
    _, again, _ = cli(capsys, "nodes")
    assert again == first
    assert index_files() == [index] and index.read_text().startswith('{"key"')


def test_an_edit_replaces_the_index(capsys, tmp_path, monkeypatch):
    cli(capsys, "nodes")
    [first] = index_files()
    monkeypatch.setattr(_plugin_index, "FORMAT", _plugin_index.FORMAT + 1)  # another key
    cli(capsys, "nodes")
    [second] = index_files()
    assert second != first


def _package(root: Path, summary: str) -> Path:
    package = root / "fakeplug_nodes"
    package.mkdir(exist_ok=True)
    (package / "__init__.py").write_text(
        textwrap.dedent(
            f'''
            """A plugin installed as a distribution."""
            from graphvision import Float, node

            __all__ = ["scale"]


            @node("fakeplug.scale")
            def scale(x: Float, *, factor: float = 2.0) -> Float:
                """{summary}

                Parameters
                ----------
                x : Float
                    Value.
                factor : float
                    Factor.
                """
                return x * factor
            '''
        )
    )
    return package / "__init__.py"


def _edit_keeping_size_and_time(path: Path, old: str, new: str) -> None:
    assert len(old) == len(new)
    before = path.stat()
    path.write_text(path.read_text().replace(old, new))
    os.utime(path, ns=(before.st_atime_ns, before.st_mtime_ns))
    assert path.stat().st_size == before.st_size


def _distribution(site: Path) -> Path:
    """A distribution ``fakeplug`` installed in ``site`` whose entry point is the package
    ``fakeplug_nodes``; its ``entry_points.txt``."""
    dist = site / "fakeplug-1.0.dist-info"
    dist.mkdir(parents=True)
    (dist / "METADATA").write_text("Metadata-Version: 2.1\nName: fakeplug\nVersion: 1.0\n")
    listing = dist / "entry_points.txt"
    listing.write_text("[graphvision.plugins]\nfakeplug = fakeplug_nodes\n")
    return listing


def test_a_plugin_edit_shows_at_once(tmp_path):
    """An installed plugin (an entry point of a distribution) edited between two commands."""
    site = tmp_path / "site"
    _distribution(site)
    module = _package(site, "First summary of the node.")
    env = {**os.environ, "PYTHONPATH": str(site), "GRAPHVISION_CACHE_DIR": str(tmp_path / "c")}

    def nodes() -> subprocess.CompletedProcess:
        command = [sys.executable, "-m", "graphvision", "nodes"]
        return subprocess.run(command, env=env, capture_output=True, text=True, timeout=120)

    assert "First summary of the node." in nodes().stdout  # discovered, index written
    assert "First summary of the node." in nodes().stdout  # from the index
    # the same size and modification time: only the bytes tell
    _edit_keeping_size_and_time(module, "First summary", "Other summary")
    assert "Other summary of the node." in nodes().stdout
    # parameters that cannot be validated are refused although an index exists
    _edit_keeping_size_and_time(module, "float = 2.0", "int = 'two'")
    broken = nodes()
    assert "fakeplug.scale" not in broken.stdout
    assert "plugin 'fakeplug' failed to load" in broken.stderr
    assert "parameters cannot be validated" in broken.stderr
    # a failing plugin is never recorded: it is imported, and reported, every time
    again = nodes()
    assert "parameters cannot be validated" in again.stderr


def test_the_key_changes_with_a_files_bytes_alone(tmp_path, monkeypatch):
    module = _package(tmp_path, "First summary of the node.")
    monkeypatch.syspath_prepend(str(tmp_path))
    entries = [EntryPoint("fakeplug", "fakeplug_nodes", _plugin_index.ENTRY_POINT_GROUP)]
    key = _plugin_index.environment_key(entries)
    assert _plugin_index.environment_key(entries) == key
    _edit_keeping_size_and_time(module, "First summary", "Other summary")
    edited = _plugin_index.environment_key(entries)
    assert edited != key
    (module.parent / "_more.py").write_text("")
    assert _plugin_index.environment_key(entries) not in (key, edited)


def test_a_file_hashed_once_is_hashed_again_when_its_status_changes(tmp_path, monkeypatch):
    """A process keeps a settled file's digest by its status; ctime moves with every write,
    even one that puts back the size and modification time."""
    module = _package(tmp_path, "First summary of the node.")
    name = str(module)
    first = _plugin_index._file_digest(name)
    assert name not in _plugin_index._DIGESTS  # written just now: read every time
    later = _plugin_index.time.time_ns() + 10 * _plugin_index._SETTLED_NS
    monkeypatch.setattr(_plugin_index.time, "time_ns", lambda: later)
    assert _plugin_index._file_digest(name) == first
    assert _plugin_index._DIGESTS[name][1] == first  # settled: kept
    _plugin_index.time.sleep(0.05)  # past the clock's coarse tick, so the ctime differs
    _edit_keeping_size_and_time(module, "First summary", "Other summary")
    edited = _plugin_index._file_digest(name)
    assert edited != first
    assert edited == xxhash.xxh3_128_digest(module.read_bytes())


def test_entry_points_are_listed_again_when_a_path_folder_changes(tmp_path, monkeypatch):
    """A distribution installed into a folder of ``sys.path`` shows in the next listing."""
    site = tmp_path / "site"
    site.mkdir()
    monkeypatch.syspath_prepend(str(site))
    later = _plugin_index.time.time_ns() + 10 * _plugin_index._SETTLED_NS
    monkeypatch.setattr(_plugin_index.time, "time_ns", lambda: later)
    before = {e.name for e in _plugin_index.installed_entry_points()}
    assert _plugin_index._ENTRY_POINTS  # settled folders: the listing is kept
    _plugin_index.time.sleep(0.05)
    _distribution(site)
    assert {e.name for e in _plugin_index.installed_entry_points()} == before | {"fakeplug"}


def test_one_interpreter_spelled_two_ways_has_one_key(monkeypatch):
    entries = _plugin_index.installed_entry_points()
    key = _plugin_index.environment_key(entries)
    folder, name = os.path.split(sys.executable)
    roundabout = os.path.join(folder, "..", os.path.basename(folder), name)
    monkeypatch.setattr(sys, "executable", roundabout)
    assert _plugin_index.environment_key(entries) == key


def test_a_parameter_model_left_to_first_use_is_the_one_registration_builds():
    @gv.node("lazy.scale")
    def scale(x: gv.Float, *, factor: Annotated[float, Field(gt=0)] = 2.0) -> gv.Float:
        """Scale."""
        return x * factor

    eager = build_spec(scale, "eager")
    lazy = build_spec(scale, "lazy", params_checked=True)
    assert "params_model" in eager.__dict__ and "params_model" not in lazy.__dict__
    assert lazy.params_schema() == eager.params_schema()
    assert lazy.validate_params({"factor": 3}) == {"factor": 3.0}
    with pytest.raises(gv.ParameterError, match=r"'factor' of lazy\.scale"):
        lazy.check_call((1.0,), {"factor": -1.0})


# -- importing only the families a pipeline uses ---------------------------------------

SMALL_PIPELINE = """\
version: 1
name: smooth
inputs:
  image: {type: Image, default: "sample:camera"}
nodes:
  gray: {op: colour.to_gray, in: {image: image}}
  smooth: {op: filters.gaussian, in: {image: gray}, params: {sigma: %s}}
outputs:
  smooth: smooth
"""


def test_with_an_index_a_pipeline_imports_only_the_families_it_uses():
    everything = gv.discover()  # no index yet: imports every family and writes the index
    assert index_files() and len(everything.plugins) > 10
    needs = gv.Needs(frozenset({"filters.gaussian", "colour.to_gray"}), frozenset({"Image"}))
    used = gv.discover(needs=needs)
    # the two families, and io, which loads input values (sample:, files)
    assert set(used.plugins) == {"filters", "colour", "io"}
    assert set(used.nodes) == {op for op in everything.nodes if op.split(".")[0] in used.plugins}


def test_a_needed_port_type_brings_the_family_that_defines_it():
    gv.discover()
    used = gv.discover(needs=gv.Needs(frozenset({"filters.gaussian"}), frozenset({"Lines"})))
    assert "Lines" in used.port_types and "hough" in used.plugins


def test_needs_without_an_index_import_everything():
    assert not index_files()
    used = gv.discover(needs=gv.Needs(frozenset({"filters.gaussian"})))
    assert len(used.plugins) > 10 and index_files()


@pytest.mark.parametrize("unknown", ["op", "type"])
def test_a_need_no_family_provides_imports_every_family_to_name_it(unknown):
    gv.discover()
    ops, kinds = {"filters.gaussian"}, set()
    (ops if unknown == "op" else kinds).add("filters.gausian" if unknown == "op" else "Imag")
    used = gv.discover(needs=gv.Needs(frozenset(ops), frozenset(kinds)))
    assert len(used.plugins) > 10


@pytest.mark.parametrize("index_first", [True, False])
def test_a_record_lists_the_families_its_pipeline_uses_whatever_was_imported(
    capsys, tmp_path, index_first
):
    """The first run without an index imports every family; its record says the same."""
    if index_first:
        gv.discover()
    pipeline = tmp_path / "smooth.yaml"
    pipeline.write_text(SMALL_PIPELINE % "1.0")
    status, _, _ = cli(capsys, "run", pipeline, "-d", tmp_path / "out", "--record")
    assert status == 0
    record = json.loads((tmp_path / "out" / "record.json").read_text())
    plugins = {name.removeprefix("plugin ") for name in record["versions"] if " " in name}
    assert plugins == {"filters", "colour", "io"}


def _truncated(data: bytes) -> bytes:
    return data[: len(data) // 2]


def _one_byte_changed(data: bytes) -> bytes:
    middle = len(data) // 2
    return data[:middle] + bytes([data[middle] ^ 0x01]) + data[middle + 1 :]


def _no_sources(data: bytes) -> bytes:  # valid JSON, edited by hand: the digest no longer fits
    assert b'"sources": ["file", "sample"]' in data
    return data.replace(b'"sources": ["file", "sample"]', b'"sources": []')


def _deeply_nested(data: bytes) -> bytes:
    header = data.partition(b"\n")[0]
    return header + b"\n" + b"[" * 200_000 + b"]" * 200_000


def _no_header(data: bytes) -> bytes:
    return data.partition(b"\n")[2]


@pytest.mark.parametrize(
    "damage", [_truncated, _one_byte_changed, _no_sources, _deeply_nested, _no_header]
)
def test_a_damaged_index_is_never_trusted_and_is_written_again(capsys, tmp_path, damage):
    gv.discover()
    [index] = index_files()
    sound = index.read_bytes()
    index.write_bytes(damage(sound))
    pipeline = tmp_path / "smooth.yaml"
    pipeline.write_text(SMALL_PIPELINE % "1.0")
    status, _, err = cli(capsys, "run", pipeline, "-d", tmp_path / "out")
    assert status == 0 and "error" not in err
    assert index_files() == [index] and index.read_bytes() == sound  # replaced, sound again
    status, listed, _ = cli(capsys, "nodes")
    assert status == 0 and "filters.gaussian" in listed


def test_a_misspelt_op_is_named_with_every_familys_ops_to_choose_from(capsys, tmp_path):
    gv.discover()
    pipeline = tmp_path / "smooth.yaml"
    pipeline.write_text((SMALL_PIPELINE % "1.0").replace("filters.gaussian", "filters.gausian"))
    status, _, err = cli(capsys, "validate", pipeline)
    assert status == 2
    assert "unknown op 'filters.gausian' (did you mean 'filters.gaussian'?)" in err
    assert "smooth.yaml" in err


CLIENT_AND_WORKER = """
import multiprocessing, os, sys
sys.path.insert(0, os.path.dirname(os.path.dirname(__file__)))  # as run_all.py does
from graphvision.nodes import plugin_index

def key():
    return plugin_index.environment_key(plugin_index.installed_entry_points())

if __name__ == "__main__":
    with multiprocessing.get_context(sys.argv[1]).Pool(1) as pool:
        print(pool.apply(key) == key())
"""


@pytest.mark.parametrize("method", ["spawn", "forkserver"])
def test_a_worker_process_finds_its_clients_index(tmp_path, method):
    """A worker started by multiprocessing from a script that put a folder first on its path
    has its script's folder on sys.path twice; the key hashed that as another folder, so every
    worker of a batch missed the client's index and discovered the plugins again (seconds per
    worker)."""
    (tmp_path / "scripts").mkdir()
    script = tmp_path / "scripts" / "client.py"
    script.write_text(CLIENT_AND_WORKER)
    done = subprocess.run(
        [sys.executable, str(script), method], capture_output=True, text=True, timeout=120
    )
    assert done.stdout.strip() == "True", done.stderr[-2000:]


def test_a_process_that_loaded_a_plugin_before_its_edit_never_records_it(tmp_path):
    """One process discovers, the plugin is edited, the same process discovers again (a
    notebook or the studio open while the user edits): its registry holds the old code, so
    no index is written under the new key, and a fresh `nodes` shows the edit."""
    site = tmp_path / "site"
    _distribution(site)
    module = _package(site, "First summary of the node.")
    env = {**os.environ, "PYTHONPATH": str(site), "GRAPHVISION_CACHE_DIR": str(tmp_path / "c")}
    script = textwrap.dedent(
        f"""
        import pathlib, graphvision as gv
        gv.discover()
        module = pathlib.Path({str(module)!r})
        module.write_text(module.read_text().replace("First summary", "Other summary"))
        gv.discover()
        """
    )
    ran = subprocess.run(
        [sys.executable, "-c", script], env=env, capture_output=True, text=True, timeout=120
    )
    assert ran.returncode == 0, ran.stderr
    command = [sys.executable, "-m", "graphvision", "nodes"]
    listed = subprocess.run(command, env=env, capture_output=True, text=True, timeout=120)
    assert "Other summary of the node." in listed.stdout


def test_entry_points_are_listed_again_when_a_distributions_file_is_edited_in_place(
    tmp_path, monkeypatch
):
    """A distribution's entry_points.txt rewritten where it is (its folder unchanged):
    the next listing in the same process reads it."""
    site = tmp_path / "site"
    listing = _distribution(site)
    monkeypatch.syspath_prepend(str(site))
    later = _plugin_index.time.time_ns() + 10 * _plugin_index._SETTLED_NS
    monkeypatch.setattr(_plugin_index.time, "time_ns", lambda: later)
    values = {e.name: e.value for e in _plugin_index.installed_entry_points()}
    assert values["fakeplug"] == "fakeplug_nodes" and _plugin_index._ENTRY_POINTS
    _plugin_index.time.sleep(0.05)
    listing.write_text("[graphvision.plugins]\nfakeplug = fakeplug_other\n")
    values = {e.name: e.value for e in _plugin_index.installed_entry_points()}
    assert values["fakeplug"] == "fakeplug_other"


def test_a_pipe_at_the_index_path_is_no_index_not_a_wait(tmp_path):
    site = tmp_path / "site"
    _distribution(site)
    _package(site, "First summary of the node.")
    env = {**os.environ, "PYTHONPATH": str(site), "GRAPHVISION_CACHE_DIR": str(tmp_path / "c")}
    command = [sys.executable, "-m", "graphvision", "nodes"]
    subprocess.run(command, env=env, capture_output=True, text=True, timeout=120, check=True)
    (index,) = [p for p in (tmp_path / "c").parent.rglob("*.json") if "index" in p.name]
    index.unlink()
    os.mkfifo(index)  # opened plainly, the read waits for a writer for ever
    done = subprocess.run(command, env=env, capture_output=True, text=True, timeout=120)
    assert done.returncode == 0 and "First summary of the node." in done.stdout, done.stderr
