"""One bad file never stops a batch (issue 29, item 5).

Every failure while a file runs or its folder is written (outputs, record, report pages,
thumbnails) fails that file alone, with its reason in ``batch.csv``, and the batch goes
on; a path the pattern matches that cannot be read (a folder named ``x.png``, a dangling
symbolic link, a loop of them, a pipe) is listed as failed, saying why; pictures of any
shape (1 × N, N × 1, one channel, all zeros, empty) have a thumbnail and a PNG.
"""

from __future__ import annotations

import csv
import io
import os
from pathlib import Path

import imageio.v3 as iio
import numpy as np
import pytest
from PIL import Image

from graphvision.cli import main
from graphvision.execution.folders import new_folder
from graphvision.values.pictures import png_bytes, thumbnail

from ..conftest import TOY

PIPELINE = """name: hostile
inputs:
  image: {type: Image}
nodes:
  gray: {op: colour.to_gray, in: {image: image}}
  smooth: {op: filters.gaussian, in: {image: gray}, params: {sigma: 1.0}}
  pixels: {op: toy.count, in: {image: image}}
outputs: {smooth: smooth, pixels: pixels}
"""

RNG = np.random.default_rng(29)
GOOD = {  # name -> image: every one must give an output
    "photo.png": (RNG.random((24, 32)) * 255).astype(np.uint8),
    "strip.png": (RNG.random((1, 4000)) * 255).astype(np.uint8),
    "column.png": (RNG.random((4000, 1)) * 255).astype(np.uint8),
    "black.png": np.zeros((16, 16, 3), np.uint8),
    "one_pixel.png": np.full((1, 1), 200, np.uint8),
}
BAD = {  # name -> what batch.csv says of it
    "text.png": "is not a readable image",
    "empty.png": "is not a readable image",
    "truncated.png": "is not a readable image",
    "folder.png": "is a folder, not a file",
    "dangling.png": "is a symbolic link to",
    "loop.png": "is a symbolic link loop",
    "pipe.png": "is not a regular file",
}


def hostile_folder(folder: Path) -> Path:
    folder.mkdir()
    for name, image in GOOD.items():
        iio.imwrite(folder / name, image)
    (folder / "text.png").write_text("not an image")
    (folder / "empty.png").write_bytes(b"")
    (folder / "truncated.png").write_bytes((folder / "photo.png").read_bytes()[:60])
    (folder / "folder.png").mkdir()
    (folder / "dangling.png").symlink_to(folder / "gone.png")
    (folder / "loop.png").symlink_to(folder / "loop.png")
    os.mkfifo(folder / "pipe.png")
    return folder


@pytest.mark.parametrize("executor", ["threads", "sync", "processes"])
def test_a_batch_over_hostile_files_lists_every_file_and_writes_every_good_one(
    capsys, tmp_path, executor
):
    photos = hostile_folder(tmp_path / "in")
    pipeline = tmp_path / "hostile.yaml"
    pipeline.write_text(PIPELINE)
    out = tmp_path / "out"
    args = ["--plugins", str(TOY), "run", str(pipeline), "--batch", f"image={photos}/*.png"]
    status = main([*args, "-d", str(out), "--no-cache", "--executor", executor])
    err = capsys.readouterr().err
    assert status == 1 and "Traceback" not in err and "internal error" not in err
    rows = {Path(row["file"]).name: row for row in csv.DictReader((out / "batch.csv").open())}
    assert sorted(rows) == sorted([*GOOD, *BAD])
    for name, image in GOOD.items():
        row = rows[name]
        assert row["status"] == "ok", row
        smooth = iio.imread(Path(row["output_dir"]) / "smooth.png")
        assert smooth.shape == image.shape[:2]
        assert int(row["pixels"]) == image.shape[0] * image.shape[1]
        assert (Path(row["output_dir"]) / "report.html").is_file()
    for name, reason in BAD.items():
        assert rows[name]["status"] == "failed" and reason in rows[name]["error"], rows[name]
        assert f"error: {photos / name}" in err  # said as it happens, too
    assert f"{len(GOOD)} of {len(GOOD) + len(BAD)} succeeded" in err


BAD_LEVEL = 7  # bad.png is this gray level all over: its pictures are known by it


def _is_about_bad(value) -> bool:
    """True for the path of bad.png or of its folder (or the hidden one it is written as
    while new), and for a picture of its level."""
    if isinstance(value, (str, Path)):
        parts = Path(value).parts
        return (
            bool({"bad", new_folder(Path("bad")).name} & set(parts))
            or Path(value).name == "bad.png"
        )
    if isinstance(value, dict):
        return any(_is_about_bad(v) for v in value.values())
    if isinstance(value, (list, tuple)):
        return any(_is_about_bad(v) for v in value)
    if isinstance(value, np.ndarray) and value.size and value.dtype.kind == "f":
        return bool(np.allclose(value, BAD_LEVEL / 255, atol=1e-4))
    return False


def _fail_for_bad(name: str, real):
    """``real``, raising ValueError when it is handed anything of bad.png's."""

    def failing(*args, **kwargs):
        if _is_about_bad(list(args)) or _is_about_bad(kwargs):
            raise ValueError(f"{name} broke")
        return real(*args, **kwargs)

    return failing


STAGES = {  # where a failure is injected: module, function
    "the run": ("graphvision.execution.batch_items", "run"),
    "writing the outputs": ("graphvision.execution.folders", "write_outputs"),
    "writing the record": ("graphvision.execution.folders", "file_sha256"),
    "writing a report page": ("graphvision.views.report", "write_report"),
    "drawing a thumbnail": ("graphvision.views.viewers", "picture_html"),
}


@pytest.mark.parametrize("stage", sorted(STAGES))
def test_a_failure_at_any_stage_of_a_file_fails_that_file_alone(
    capsys, tmp_path, monkeypatch, stage
):
    import importlib

    module_name, function = STAGES[stage]
    module = importlib.import_module(module_name)
    monkeypatch.setattr(module, function, _fail_for_bad(function, getattr(module, function)))
    photos = tmp_path / "in"
    photos.mkdir()
    for name in ("a.png", "c.png", "d.png"):
        iio.imwrite(photos / name, (RNG.random((12, 16)) * 255).astype(np.uint8))
    iio.imwrite(photos / "bad.png", np.full((12, 16), BAD_LEVEL, np.uint8))
    pipeline = tmp_path / "p.yaml"
    pipeline.write_text(PIPELINE)
    out = tmp_path / "out"
    args = ["--plugins", str(TOY), "run", str(pipeline), "--batch", f"image={photos}/*.png"]
    status = main([*args, "-d", str(out), "--no-cache", "--executor", "sync"])
    err = capsys.readouterr().err
    assert status == 1 and "Traceback" not in err
    rows = {Path(row["file"]).name: row for row in csv.DictReader((out / "batch.csv").open())}
    assert [rows[name]["status"] for name in ("a.png", "bad.png", "c.png", "d.png")] == [
        "ok",
        "failed",
        "ok",
        "ok",
    ], {name: row["error"] for name, row in rows.items()}
    assert f"ValueError: {function} broke" in rows["bad.png"]["error"]
    assert not (out / "bad" / "record.json").exists()  # nothing there looks like a result
    assert rows["bad.png"]["pixels"] == ""  # nor in batch.csv: its value was never written
    assert [rows[name]["pixels"] for name in ("a.png", "c.png", "d.png")] == ["192"] * 3
    assert all((out / name / "smooth.png").is_file() for name in ("a", "c", "d"))


def test_a_single_run_whose_files_cannot_be_written_fails_with_one_line(
    capsys, tmp_path, monkeypatch
):
    import graphvision.views.report as report

    def broken(*args, **kwargs):
        raise ValueError("cannot write empty image")

    monkeypatch.setattr(report, "write_report", broken)
    image = tmp_path / "photo.png"
    iio.imwrite(image, GOOD["photo.png"])
    pipeline = tmp_path / "p.yaml"
    pipeline.write_text(PIPELINE)
    out = tmp_path / "a" / "b"
    args = ["--plugins", str(TOY), "run", str(pipeline), "-i", f"image={image}", "-d", str(out)]
    status = main([*args, "--no-cache"])
    err = capsys.readouterr().err
    assert status == 1 and "internal error" not in err
    assert err.strip() == (
        f"error: the run's files could not be written to {out} "
        "(ValueError: cannot write empty image)"
    )
    assert not (tmp_path / "a").exists()  # the folders made for it are gone


@pytest.mark.parametrize(
    "shape",
    [(1, 4000), (4000, 1), (1, 1), (64, 64, 1), (3, 5000, 3), (0, 5), (5, 5, 2), (5, 5, 4), (9,)],
)
@pytest.mark.parametrize("fill", [0.0, 1.0, np.nan])
def test_every_picture_has_a_thumbnail_and_a_png(shape, fill):
    picture = np.full(shape, fill, np.float32)
    small = thumbnail(picture)
    assert all(side >= 1 for side in small.shape[:2]) or picture.size == 0 or picture.ndim < 2
    assert max(small.shape[:2], default=0) <= 512
    png = Image.open(io.BytesIO(png_bytes(small)))
    png.load()
    assert min(png.size) >= 1 and max(png.size) <= 2048
    drawn = np.asarray(png)
    expected = 255 if fill == 1.0 and picture.size else 0  # an empty picture: one black pixel
    assert np.all(drawn[..., :3] == expected) if drawn.ndim == 3 else np.all(drawn == expected)


def test_a_thin_strip_is_averaged_along_its_length():
    strip = np.arange(4096, dtype=np.float32)[None, :] / 4096
    small = thumbnail(strip)
    assert small.shape == (1, 512)
    expected = strip.reshape(1, 512, 8).mean(axis=2)
    np.testing.assert_allclose(small, expected, rtol=1e-6)


def test_folders_count_as_matches_only_when_the_pattern_names_a_suffix(tmp_path):
    from graphvision.execution.batch_files import batch_files

    photos = tmp_path / "photos"
    (photos / "sub").mkdir(parents=True)
    (photos / "odd.png").mkdir()
    iio.imwrite(photos / "a.png", GOOD["photo.png"])
    assert batch_files(f"{photos}/*.png")[0] == [photos / "a.png", photos / "odd.png"]
    assert batch_files(f"{photos}/*")[0] == [photos / "a.png"]  # folders searched, not files
