"""The output folder's contract against what an adversary planted (session 38's cases).

Bad input gets an error naming what is wrong and where (exit 2, no traceback), no file
is touched that graphvision did not write, nothing is written outside the folder, and no
previous run is replaced without being kept. Each case is tested as a class: every file
a batch or a sweep writes at its folder's top, every place a link can stand on the way
to an item folder, every way ``history/`` or a record can stop a run being kept, every
path option given empty.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import imageio.v3 as iio
import numpy as np
import pytest

import graphvision as gv
from graphvision.cli import main
from graphvision.execution import manifest
from graphvision.execution.batch_files import BATCH_FILES
from graphvision.execution.folders import write_run

from ..conftest import TOY

PIPELINE = """name: small
inputs:
  image: {type: Image}
nodes:
  gray: {op: colour.to_gray, in: {image: image}}
  pixels: {op: toy.count, in: {image: image}}
outputs: {gray: gray, pixels: pixels}
"""


@pytest.fixture
def setup(tmp_path: Path) -> tuple[Path, Path]:
    """The pipeline and a folder of three 6 x 8 pictures."""
    pipeline = tmp_path / "small.yaml"
    pipeline.write_text(PIPELINE)
    photos = tmp_path / "in"
    photos.mkdir()
    for number, name in enumerate(("a.png", "b.png", "c.png")):
        iio.imwrite(photos / name, np.full((6, 8), 40 * number, np.uint8))
    return pipeline, photos


def _batch(pipeline: Path, pattern: str, out: Path, *extra: str) -> int:
    args = ["--plugins", str(TOY), "run", str(pipeline), "--batch", f"image={pattern}"]
    return main([*args, "-d", str(out), "--no-cache", "--executor", "sync", *extra])


def _run(pipeline: Path, image: Path, out: Path) -> int:
    args = ["--plugins", str(TOY), "run", str(pipeline), "-i", f"image={image}"]
    return main([*args, "-d", str(out), "--no-cache", "--executor", "sync"])


def _refused(capsys: pytest.CaptureFixture[str], status: int) -> str:
    err = capsys.readouterr().err
    assert status == 2 and "Traceback" not in err, err
    return err


# -- 1. a batch's (and a sweep's) own files: only those it wrote are replaced ------------


@pytest.mark.parametrize("name", ["batch.csv", "batch.html"])
@pytest.mark.parametrize("planted", ["before", "over", "link"])
def test_a_batch_replaces_only_the_files_at_its_folders_top_that_it_wrote(
    capsys, tmp_path, setup, name, planted
):
    """``before``: the user's file before any batch; ``over``: saved over the batch's own
    after it ran; ``link``: a symbolic link put in its place."""
    pipeline, photos = setup
    out, victim = tmp_path / "out", tmp_path / "victim.txt"
    victim.write_text("the user's")
    if planted != "before":
        assert _batch(pipeline, f"{photos}/*.png", out) == 0
        (out / name).unlink()
    else:
        out.mkdir()
    if planted == "link":
        (out / name).symlink_to(victim)
    else:
        (out / name).write_text("file,status\nmine,ok\n")
    err = _refused(capsys, _batch(pipeline, f"{photos}/*.png", out))
    reason = {
        "before": "and no batch.json says a batch wrote it (an earlier graphvision kept none: "
        "if it is an earlier batch's, delete it and the batch writes it again)",
        "over": "which changed since the batch wrote it",
        "link": f"a symbolic link to {victim}, which no batch wrote",
    }[planted]
    assert f"error: output folder {out} holds {name}, {reason}; the batch would replace it" in err
    assert victim.read_text() == "the user's"
    if planted != "link":
        assert (out / name).read_text() == "file,status\nmine,ok\n"


def test_a_folder_of_a_batch_that_kept_no_manifest_is_taken_by_its_summary_only(
    capsys, tmp_path, setup
):
    """A batch before batch.json: its batch.csv is recognised by its first columns, its
    batch.html (the adversary's case: anyone's page) is not."""
    pipeline, photos = setup
    out = tmp_path / "out"
    assert _batch(pipeline, f"{photos}/*.png", out) == 0
    (out / "batch.json").unlink()
    err = _refused(capsys, _batch(pipeline, f"{photos}/*.png", out))
    assert "holds batch.html, and no batch.json says a batch wrote it (an earlier " in err
    assert "delete it and the batch writes it again" in err  # what the user does
    (out / "batch.html").unlink()
    assert _batch(pipeline, f"{photos}/*.png", out) == 0
    listing = json.loads((out / "batch.json").read_text())["files"]
    assert sorted(listing) == ["batch.csv", "batch.html"]
    capsys.readouterr()


def test_a_batch_killed_while_it_replaces_its_files_leaves_a_folder_the_next_accepts(tmp_path):
    folder = tmp_path / "out"
    manifest.replace_folder_files(folder, BATCH_FILES, {"batch.csv": "file,status\n"})
    real = manifest._published

    def killed_after_one(temp: Path, path: Path) -> None:
        real(temp, path)
        if path.name == "batch.csv":
            raise KeyboardInterrupt  # killed: batch.html and the last manifest not written

    contents = {"batch.csv": "file,status\nx,ok\n", "batch.html": "<p>x</p>"}
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(manifest, "_published", killed_after_one)
        with pytest.raises(KeyboardInterrupt):
            manifest.replace_folder_files(folder, BATCH_FILES, contents)
    assert (folder / "batch.csv").read_text() == "file,status\nx,ok\n"
    written = manifest.replace_folder_files(folder, BATCH_FILES, {"batch.csv": "file,status\n"})
    assert written == [folder / "batch.csv"]
    listing = json.loads((folder / "batch.json").read_text())
    assert listing["graphvision"] == "batch" and list(listing["files"]) == ["batch.csv"]


@pytest.mark.parametrize("content", ["[]", '{"graphvision": "sweep", "files": {}}', "7", "{"])
def test_a_batch_manifest_that_is_not_one_is_refused_in_words(capsys, tmp_path, setup, content):
    pipeline, photos = setup
    out = tmp_path / "out"
    assert _batch(pipeline, f"{photos}/*.png", out) == 0
    (out / "batch.json").write_text(content)
    err = _refused(capsys, _batch(pipeline, f"{photos}/*.png", out))
    assert f"{out / 'batch.json'} is not a graphvision batch manifest (" in err
    assert "object has no attribute" not in err and "'list'" not in err
    assert (out / "batch.json").read_text() == content


def test_a_sweep_manifest_without_digests_is_taken_as_a_list_of_names(tmp_path):
    """What a sweep wrote before digests: its names are its files, whatever they hold."""
    from graphvision.views.sweep_page import SWEEP_FILES

    (tmp_path / "sweep.csv").write_text("a,status\n1,ok\n")
    (tmp_path / "sweep.json").write_text('{"graphvision": "sweep", "files": ["sweep.csv"]}')
    assert manifest.check_folder_files(tmp_path, SWEEP_FILES) == {"sweep.csv": None}
    manifest.replace_folder_files(tmp_path, SWEEP_FILES, {"sweep.html": "<p>x</p>"})
    assert sorted(p.name for p in tmp_path.iterdir()) == ["sweep.html", "sweep.json"]
    (tmp_path / "sweep.json").write_text('{"graphvision": "batch", "files": {}}')
    with pytest.raises(gv.OutputFolderError, match=r"sweep.json is not a graphvision sweep"):
        manifest.check_folder_files(tmp_path, SWEEP_FILES)


def test_a_sweep_replaces_only_the_pages_it_wrote(capsys, tmp_path, setup):
    pipeline, photos = setup
    out = tmp_path / "sweep"
    args = ["--plugins", str(TOY), "sweep", str(pipeline), "-i", f"image={photos}/a.png"]
    args += ["--grid", "gray.method=luminance", "-d", str(out), "--no-cache"]
    assert main(args) == 0
    assert main(args) == 0  # its own files: replaced
    (out / "sweep_run_0001.html").write_text("my notes")
    err = _refused(capsys, main(args))
    assert "holds sweep_run_0001.html, which changed since the sweep wrote it" in err
    assert (out / "sweep_run_0001.html").read_text() == "my notes"
    (out / "sweep_run_0001.html").unlink()
    (out / "sweep_run_2.html").write_text("my page")  # named like a sweep's page, and
    (out / "sweep_mine.svg").write_text("<svg/>")  # like a plot, but this sweep writes neither
    assert main(args) == 0
    assert (out / "sweep_run_2.html").read_text() == "my page"
    assert (out / "sweep_mine.svg").read_text() == "<svg/>"
    (out / "sweep_run_0002.html").write_text("my page")  # the second combination's page
    wider = [*args[:-5], "--grid", "gray.method=luminance,mean", *args[-3:]]
    err = _refused(capsys, main(wider))
    assert "holds sweep_run_0002.html, which no graphvision sweep there wrote" in err
    assert (out / "sweep_run_0002.html").read_text() == "my page"


# -- 2. a batch writes only inside its folder, never through a link -----------------------


@pytest.mark.parametrize("where", ["item", "parent", "dangling"])
def test_a_link_on_the_way_to_an_item_folder_is_refused_and_nothing_is_written_outside(
    capsys, tmp_path, setup, where
):
    pipeline, photos = setup
    (photos / "sub").mkdir()
    iio.imwrite(photos / "sub" / "d.png", np.zeros((6, 8), np.uint8))
    out, outside = tmp_path / "out", tmp_path / "outside"
    out.mkdir()
    outside.mkdir()
    link = {"item": out / "a", "parent": out / "sub", "dangling": out / "b"}[where]
    link.symlink_to(outside / "gone" if where == "dangling" else outside)
    err = _refused(capsys, _batch(pipeline, f"{photos}/**/*.png", out))
    target = outside / "gone" if where == "dangling" else outside
    assert f"error: {link} is a symbolic link to {target}: the batch would write" in err
    assert f"outside its output folder {out}" in err
    assert list(outside.iterdir()) == []
    assert sorted(p.name for p in out.iterdir()) == [link.name]  # nothing written


def test_a_file_where_a_batch_makes_a_folder_is_refused_naming_it(capsys, tmp_path, setup):
    pipeline, photos = setup
    (photos / "sub").mkdir()
    iio.imwrite(photos / "sub" / "d.png", np.zeros((6, 8), np.uint8))
    out = tmp_path / "out"
    out.mkdir()
    (out / "sub").write_text("mine")  # where sub/d.png's folder out/sub/d would be made
    err = _refused(capsys, _batch(pipeline, f"{photos}/**/*.png", out))
    assert f"error: {out / 'sub'} is a file, where the batch makes the folder {out}/sub/d" in err
    assert sorted(p.name for p in out.iterdir()) == ["sub"]
    assert (out / "sub").read_text() == "mine"


@pytest.mark.parametrize("name", ["report.html", "report.md", "record.json"])
def test_report_never_writes_through_a_link_in_a_run_folder(capsys, tmp_path, setup, name):
    pipeline, photos = setup
    out, victim = tmp_path / "out", tmp_path / "victim.txt"
    assert _run(pipeline, photos / "a.png", out) == 0
    victim.write_bytes((out / name).read_bytes())
    (out / name).unlink()
    (out / name).symlink_to(victim)
    err = _refused(capsys, main(["--plugins", str(TOY), "report", str(out)]))
    assert f"error: {out / name} is a symbolic link to {victim}, not a file a run wrote" in err
    assert (out / name).is_symlink() and victim.read_bytes() != b""
    before = victim.read_bytes()
    (out / name).unlink()
    victim.rename(out / name)
    assert main(["--plugins", str(TOY), "report", str(out)]) == 0  # its own pages: replaced
    assert sorted(p.name for p in out.iterdir() if p.name.startswith(".")) == []  # no staging
    if name == "record.json":
        assert (out / name).read_bytes() == before
    capsys.readouterr()


def test_a_link_made_while_an_item_folder_is_written_beside_it_is_not_written_through(
    tmp_path,
):
    outside, folder = tmp_path / "outside", tmp_path / "out" / "a"
    outside.mkdir()
    graph = gv.Graph("value")
    graph.output("value", graph.input("value", "Float"))
    result = gv.run(graph, inputs={"value": 2.5})

    def planting(run: gv.RunResult, directory: Path) -> list[str]:
        folder.symlink_to(outside)  # planted while the folder is written beside its place
        return []

    with pytest.raises(gv.OutputFolderError, match=f"{folder} is a symbolic link to {outside}"):
        write_run(result, folder, [planting], inside=tmp_path / "out")
    assert list(outside.iterdir()) == []


# -- 3. inputs inside the output folder: tests/execution/test_batch.py


# -- 4. a previous run is kept, or the run refused ------------------------------------------


def _plant(folder: Path, where: str, elsewhere: Path) -> None:
    """Something in ``folder`` (after a run) that stops its run being kept in history/."""
    history = folder / "history"
    if where == "history is a link":
        history.symlink_to(elsewhere, target_is_directory=True)
    elif where == "history is a file":
        history.write_text("mine")
    elif where == "history is the user's folder":
        history.mkdir()
        (history / "notes.txt").write_text("mine")
    elif where == "the marker is a link":
        history.mkdir()
        (history / ".graphvision-history").symlink_to(elsewhere / "marker")
    elif where == "the record is a link":
        os.replace(folder / "record.json", elsewhere / "record.json")
        (folder / "record.json").symlink_to(elsewhere / "record.json")
    elif where == "an output is a link":
        (folder / "gray.png").unlink()
        (folder / "gray.png").symlink_to(elsewhere / "record.json")
    else:
        (folder / "gray.png").unlink()
        (folder / "gray.png").mkdir()


UNKEPT = {  # what is planted -> what the refusal says
    "history is a link": "history is a symbolic link to {elsewhere}, so the previous run",
    "history is a file": "history is a file, not graphvision's history folder",
    "history is the user's folder": "history is a folder graphvision did not make",
    "the marker is a link": "history is a folder graphvision did not make (its "
    ".graphvision-history is a symbolic link)",
    "the record is a link": "record.json is a symbolic link to {elsewhere}/record.json",
    "an output is a link": "gray.png is a symbolic link to {elsewhere}/record.json, where the",
    "an output is a folder": "gray.png is a folder, where the previous run wrote a file",
}


@pytest.mark.parametrize("where", sorted(UNKEPT))
def test_a_run_that_could_not_keep_the_previous_one_is_refused(capsys, tmp_path, setup, where):
    pipeline, photos = setup
    out, elsewhere = tmp_path / "out", tmp_path / "elsewhere"
    elsewhere.mkdir()
    (elsewhere / "record.json").write_text("{}")
    assert _run(pipeline, photos / "a.png", out) == 0
    _plant(out, where, elsewhere)
    before = {p.name: p.lstat().st_mtime_ns for p in out.iterdir()}
    err = _refused(capsys, _run(pipeline, photos / "b.png", out))
    assert UNKEPT[where].format(elsewhere=elsewhere) in err
    assert "move it, or choose another --output-dir" in err or "remove it" in err
    assert {p.name: p.lstat().st_mtime_ns for p in out.iterdir()} == before  # untouched
    assert sorted(p.name for p in elsewhere.iterdir()) == ["record.json"]


def test_a_link_named_like_a_kept_run_neither_stands_for_it_nor_is_written_through(
    capsys, tmp_path, setup
):
    import hashlib
    import re

    pipeline, photos = setup
    out, victim = tmp_path / "out", tmp_path / "victim"
    victim.mkdir()
    assert _run(pipeline, photos / "a.png", out) == 0
    raw = (out / "record.json").read_bytes()
    date = re.sub(r"[^0-9TZ.]", "", json.loads(raw)["date"].replace("+00:00", "Z"))
    name = f"000001-{date}-{hashlib.sha256(raw).hexdigest()[:8]}"  # the entry it would get
    (out / "history").mkdir()
    (out / "history" / ".graphvision-history").touch()
    (out / "history" / name).symlink_to(victim, target_is_directory=True)
    assert _run(pipeline, photos / "b.png", out) == 0
    (kept,) = [p for p in (out / "history").glob("0*") if not p.is_symlink()]
    assert kept.name.startswith("000002-") and (kept / "record.json").read_bytes() == raw
    assert list(victim.iterdir()) == []
    capsys.readouterr()


def test_a_batch_item_that_fails_keeps_its_previous_run_in_history(capsys, tmp_path, setup):
    pipeline, photos = setup
    out = tmp_path / "out"
    assert _batch(pipeline, f"{photos}/*.png", out) == 0
    previous = (out / "a" / "record.json").read_bytes()
    (photos / "a.png").write_text("now broken")
    assert _batch(pipeline, f"{photos}/*.png", out) == 1
    assert not (out / "a" / "record.json").exists()  # nothing there looks current
    (kept,) = (out / "a" / "history").glob("0*")
    assert (kept / "record.json").read_bytes() == previous
    capsys.readouterr()


# -- 5. batch.csv shows what a folder holds: tests/execution/test_hostile_batch.py, where a
# failure at every stage of writing a file's folder leaves its values out of batch.csv


def test_a_batch_into_an_empty_output_dir_is_refused_from_python(setup):
    pipeline, photos = setup
    graph = gv.load_pipeline(pipeline)
    with pytest.raises(ValueError, match=r"output_dir is an empty path: give a folder"):
        gv.run_batch(graph, f"{photos}/*.png", input="image", output_dir="")


def test_a_killed_writers_temporary_files_are_removed_by_the_next_batch(capsys, tmp_path, setup):
    """A writer killed between a temporary file and its rename leaves ``.batch.json.PID.TID
    .tmp``; the next batch (another process) removes those of dead processes, and nothing
    else of the user's."""
    import subprocess
    import sys

    pipeline, photos = setup
    out = tmp_path / "out"
    assert _batch(pipeline, f"{photos}/*.png", out) == 0
    gone = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                          capture_output=True, text=True, check=True).stdout.strip()  # fmt: skip
    left = [out / f".batch.json.{gone}.140503779367808.tmp", out / f".batch.csv.{gone}.7.tmp"]
    mine = [out / f".batch.csv.{os.getppid()}.7.tmp", out / ".notes.1.2.tmp", out / ".x.tmp"]
    for path in left + mine:  # (the parent's: a live process; the others: not a batch's)
        path.write_text("half")
    assert _batch(pipeline, f"{photos}/*.png", out) == 0
    assert not any(path.exists() for path in left)
    assert all(path.read_text() == "half" for path in mine)
