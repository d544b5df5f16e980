"""A run's provenance hashes each file once while it is unchanged (pipeline file, input files,
local plugin files and folders), and again as soon as it changes."""

from __future__ import annotations

import hashlib
from pathlib import Path

import numpy as np

import graphvision as gv
from graphvision.execution import git_state, provenance

PLUGIN = '''
from graphvision import Image, node

@node("cachedprov.brighter")
def brighter(image: Image, *, amount: float = 0.1) -> Image:
    """The image plus ``amount``, clipped to [0, 1]."""
    return (image + amount).clip(0, 1)
'''


def _pipeline(folder: Path) -> Path:
    path = folder / "p.yaml"
    path.write_text(
        "version: 1\nname: p\ninputs:\n  image: {type: Image}\n"
        "nodes:\n  b: {op: cachedprov.brighter, in: {image: image}}\noutputs:\n  out: b\n"
    )
    return path


def _counting_reads(monkeypatch) -> list[str]:
    read: list[str] = []
    original = provenance.file_sha256

    def counted(path: Path) -> str:
        read.append(Path(path).name)
        return original(path)

    monkeypatch.setattr(provenance, "file_sha256", counted)
    return read


def test_unchanged_files_are_hashed_once_and_again_after_an_edit(tmp_path, monkeypatch):
    plugin = tmp_path / "cachedprov.py"
    plugin.write_text(PLUGIN)
    registry = gv.discover([plugin], entry_points=False)
    pipeline = _pipeline(tmp_path)
    image = np.random.default_rng(0).random((6, 5)).astype(np.float32)
    read = _counting_reads(monkeypatch)
    first = gv.run(gv.load_pipeline(pipeline), registry, inputs={"image": image}).record
    second = gv.run(gv.load_pipeline(pipeline), registry, inputs={"image": image}).record
    assert sorted(read) == ["cachedprov.py", "p.yaml"]  # the second run read neither
    assert second.pipeline_sha256 == first.pipeline_sha256
    plugin_key = f"plugin {plugin}"  # a plugin loaded from a path is named by it
    assert second.versions[plugin_key] == first.versions[plugin_key]
    assert first.versions[plugin_key] == f"sha256 {hashlib.sha256(PLUGIN.encode()).hexdigest()}"
    pipeline.write_text(pipeline.read_text() + "# edited\n")  # another size: another stamp
    third = gv.run(gv.load_pipeline(pipeline), registry, inputs={"image": image}).record
    assert read.count("p.yaml") == 2
    assert third.pipeline_sha256 == hashlib.sha256(pipeline.read_bytes()).hexdigest()
    assert third.pipeline_sha256 != first.pipeline_sha256


def test_a_local_plugin_folder_is_hashed_again_when_a_file_is_added(tmp_path):
    folder = tmp_path / "pkg"
    folder.mkdir()
    (folder / "__init__.py").write_text("A = 1\n")
    before = provenance._plugin_version(str(folder))
    assert provenance._plugin_version(str(folder)) == before
    (folder / "more.py").write_text("B = 2\n")
    after = provenance._plugin_version(str(folder))
    digest = hashlib.sha256()
    for name in ("__init__.py", "more.py"):
        digest.update(name.encode() + b"\0" + (folder / name).read_bytes())
    assert after == f"sha256 {digest.hexdigest()}" != before


def test_the_commit_follows_a_new_branch_and_a_new_commit(tmp_path):
    """``HEAD`` is read again when it changes (another branch checked out), and the branch's
    ref is watched (a new commit on it)."""
    import subprocess

    (tmp_path / "p.yaml").write_text("version: 1\n")
    git = ["git", "-C", str(tmp_path), "-c", "user.name=t", "-c", "user.email=t@t"]

    def commit(message: str) -> str:
        subprocess.run([*git, "commit", "-q", "--allow-empty", "-m", message], check=True)
        return subprocess.run(
            [*git, "rev-parse", "HEAD"], capture_output=True, text=True, check=True
        ).stdout.strip()

    subprocess.run([*git, "init", "-q"], check=True)
    subprocess.run([*git, "add", "p.yaml"], check=True)
    first = commit("first")
    assert provenance.git_state(tmp_path / "p.yaml") == (first, False)
    subprocess.run([*git, "checkout", "-q", "-b", "other"], check=True)
    second = commit("second")
    assert provenance.git_state(tmp_path / "p.yaml") == (second, False)
    third = commit("third")
    assert provenance.git_state(tmp_path / "p.yaml") == (third, False)


def test_the_pipeline_files_resolved_path_follows_a_retargeted_link(tmp_path):
    """The resolved path is kept while the name leads to the same file (a run resolved it
    twice: a system call per folder each time); a link pointed elsewhere is resolved again."""
    plugin = tmp_path / "cachedprov.py"
    plugin.write_text(PLUGIN)
    registry = gv.discover([plugin], entry_points=False)
    first, second = tmp_path / "a", tmp_path / "b"
    first.mkdir(), second.mkdir()
    link = tmp_path / "link.yaml"
    link.symlink_to(_pipeline(first))
    _pipeline(second)
    image = np.zeros((4, 4), np.float32)
    graph = gv.load_pipeline(link)
    before = gv.run(graph, registry, inputs={"image": image}).record.pipeline_file
    link.unlink()
    link.symlink_to(second / "p.yaml")
    after = gv.run(graph, registry, inputs={"image": image}).record.pipeline_file
    assert (before, after) == (str(first.resolve() / "p.yaml"), str(second.resolve() / "p.yaml"))


def test_a_repository_is_found_once_and_its_files_stat_once_per_run(tmp_path, monkeypatch):
    """The walk up to ``.git`` is made again only when ``HEAD`` changes: a run then makes one
    ``os.stat`` per file it watches (the pipeline file, ``HEAD``, the index, the branch's ref),
    and still sees the repository go."""
    import os
    import shutil
    import subprocess

    folder = tmp_path / "deep" / "er"
    folder.mkdir(parents=True)
    (folder / "p.yaml").write_text("version: 1\n")
    git = ["git", "-C", str(tmp_path), "-c", "user.name=t", "-c", "user.email=t@t"]
    subprocess.run([*git, "init", "-q"], check=True)
    subprocess.run([*git, "add", "deep/er/p.yaml"], check=True)
    subprocess.run([*git, "commit", "-q", "-m", "first"], check=True)
    commit = subprocess.run(
        [*git, "rev-parse", "HEAD"], capture_output=True, text=True, check=True
    ).stdout.strip()
    file = (folder / "p.yaml").resolve()
    assert git_state._git_state_of(file) == (commit, False)
    stats: list[str] = []
    real_stat = os.stat
    monkeypatch.setattr(os, "stat", lambda path, *a, **k: stats.append(path) or real_stat(path))
    assert git_state._git_state_of(file) == (commit, False)
    assert len(stats) == 4  # (the walk made 3 more: deep/er/.git, deep/.git, .git/HEAD)
    shutil.rmtree(tmp_path / ".git")
    assert git_state._git_state_of(file) == ("", False)


OTHER = '''
from graphvision import Image, node

@node("otherprov.darker")
def darker(image: Image) -> Image:
    """The image less 0.1, clipped to [0, 1]."""
    return (image - 0.1).clip(0, 1)
'''


def test_the_plugins_listed_follow_the_registry_between_two_runs(tmp_path):
    """The plugins a run lists are worked out once per registry and ops, and again when the
    registry's plugins change (one loaded since, one loaded again from another file)."""
    from graphvision.nodes.plugins import load_path
    from graphvision.nodes.registry import PluginStatus

    plugin, other = tmp_path / "cachedprov.py", tmp_path / "otherprov.py"
    plugin.write_text(PLUGIN)
    other.write_text(OTHER)
    registry = gv.discover([plugin], entry_points=False)
    ops = frozenset({"cachedprov.brighter"})
    first = provenance.package_versions(registry, ops)
    assert [k for k in first if k.startswith("plugin ")] == [f"plugin {plugin}"]
    assert provenance.package_versions(registry, ops) == first
    load_path(registry, other)
    assert [k for k in provenance.package_versions(registry, None) if k.startswith("plugin ")] == (
        sorted([f"plugin {plugin}", f"plugin {other}"])
    )
    with_other = provenance.package_versions(registry, ops | {"otherprov.darker"})
    assert f"plugin {other}" in with_other
    assert provenance.package_versions(registry, ops) == first  # the other provides none
    name = next(n for n in registry.plugins if "cachedprov" in n)  # the same name, another file
    registry.plugins[name] = PluginStatus(name, str(other), ["cachedprov.brighter"])
    assert provenance.package_versions(registry, ops)[f"plugin {name}"] == (
        f"sha256 {hashlib.sha256(OTHER.encode()).hexdigest()}"
    )


def test_a_run_sees_the_pipeline_file_and_its_repository_change_between_two_runs(tmp_path):
    """What a run records of its pipeline file (path, SHA-256, commit, dirty) is kept with the
    stamps of the file and of the repository's files, and worked out again when one of them
    changed: an edit, a commit, a file put in its place, another branch."""
    import subprocess

    plugin = tmp_path / "cachedprov.py"
    plugin.write_text(PLUGIN)
    registry = gv.discover([plugin], entry_points=False)
    pipeline = _pipeline(tmp_path)
    git = ["git", "-C", str(tmp_path), "-c", "user.name=t", "-c", "user.email=t@t"]

    def commit(message: str) -> str:
        subprocess.run([*git, "add", "p.yaml"], check=True)
        subprocess.run([*git, "commit", "-q", "--allow-empty", "-m", message], check=True)
        return subprocess.run(
            [*git, "rev-parse", "HEAD"], capture_output=True, text=True, check=True
        ).stdout.strip()

    def recorded() -> tuple[str, str, str, bool]:
        image = np.zeros((4, 4), np.float32)
        record = gv.run(gv.load_pipeline(pipeline), registry, inputs={"image": image}).record
        return record.pipeline_file, record.pipeline_sha256, record.git_commit, record.git_dirty

    def sha() -> str:
        return hashlib.sha256(pipeline.read_bytes()).hexdigest()

    subprocess.run([*git, "init", "-q"], check=True)
    first = commit("first")
    path = str(pipeline.resolve())
    assert recorded() == recorded() == (path, sha(), first, False)
    pipeline.write_text(pipeline.read_text().replace("p\n", "q\n", 1))  # the same size
    assert recorded() == (path, sha(), first, True)
    second = commit("second")
    assert recorded() == (path, sha(), second, False)
    replaced = tmp_path / "new.yaml"
    replaced.write_text(pipeline.read_text() + "# more\n")
    replaced.replace(pipeline)  # another inode at the same path, not committed
    assert recorded() == (path, sha(), second, True)
    subprocess.run([*git, "checkout", "-q", "-b", "other"], check=True)
    third = commit("third")
    assert recorded() == (path, sha(), third, False)


def test_an_array_input_is_described_by_its_shape_and_dtype_each_run():
    """An array given is described by its type, shape and dtype (the text kept for each shape
    and dtype): arrays of another shape or dtype get their own, anything else its repr."""
    for _ in range(2):  # (the second time from what the first kept)
        assert provenance._describe_input(np.zeros((3, 4), np.float32), "k") == {
            "given": "ndarray (3, 4) float32",
            "key": "k",
        }
        assert provenance._describe_input(np.zeros(2, ">i2"), "k")["given"] == "ndarray (2,) >i2"
        assert provenance._describe_input(3.5, "k")["given"] == "3.5"


def test_runs_of_one_compiled_graph_record_its_pipeline_file_as_the_first_found_it(
    tmp_path, monkeypatch
):
    """The later runs of a compiled graph run it as it was loaded: they record the pipeline
    file (path, SHA-256) as its first run found it, without looking at the file again; a
    graph compiled again from the edited file records the edit."""
    plugin = tmp_path / "cachedprov.py"
    plugin.write_text(PLUGIN)
    registry = gv.discover([plugin], entry_points=False)
    pipeline = _pipeline(tmp_path)
    loaded = hashlib.sha256(pipeline.read_bytes()).hexdigest()
    compiled = gv.compile_graph(gv.load_pipeline(pipeline), registry)
    inputs = {"image": np.zeros((4, 4), np.float32)}
    first = gv.run(compiled, registry, inputs=inputs).record
    assert (first.pipeline_file, first.pipeline_sha256) == (str(pipeline.resolve()), loaded)
    pipeline.write_text(pipeline.read_text() + "# edited after the graph was loaded\n")
    looked: list[str] = []
    original = provenance._file_stat

    def counted(path: str):
        looked.append(path)
        return original(path)

    monkeypatch.setattr(provenance, "_file_stat", counted)
    again = gv.run(compiled, registry, inputs=inputs).record
    assert (again.pipeline_file, again.pipeline_sha256, looked) == (first.pipeline_file, loaded, [])
    anew = gv.run(gv.compile_graph(gv.load_pipeline(pipeline), registry), registry, inputs=inputs)
    assert anew.record.pipeline_sha256 == hashlib.sha256(pipeline.read_bytes()).hexdigest()
    assert anew.record.pipeline_sha256 != loaded and looked == [str(pipeline)]
