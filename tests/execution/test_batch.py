"""Batch runs: one folder per input file whatever the names, recursion, the summary
table, and the image files that used to be misread (CMYK JPEG, animated GIF)."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import imageio.v3 as iio
import numpy as np
import pytest

import graphvision as gv
from graphvision.cli import main
from graphvision.errors import OutputFolderError
from graphvision.execution.batch_files import checked_folders, output_folders, pattern_root

from ..conftest import PIPELINES

DEMO = PIPELINES / "denoise.yaml"
PSNR = "psnr_noisy_gaussian"


def photo(path: Path, level: int) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    iio.imwrite(path, np.full((12, 16), level, np.uint8))
    return path


def test_same_file_names_in_different_folders_get_their_own_folders(capsys, tmp_path):
    photos = tmp_path / "photos"
    levels = {"a/img.png": 200, "b/img.png": 60, "a/deep/img.png": 120, "img.png": 30}
    for name, level in levels.items():
        photo(photos / name, level)
    out = tmp_path / "out"
    pattern = f"image={photos}/**/*.png"
    status = main(
        ["run", str(DEMO), "--no-cache", "--batch", pattern, "-d", str(out), "-o", "noisy_gaussian"]
    )
    assert status == 0, capsys.readouterr().err
    rows = list(csv.DictReader((out / "batch.csv").open()))
    assert sorted(Path(r["file"]).relative_to(photos).as_posix() for r in rows) == sorted(levels)
    assert len({r["output_dir"] for r in rows}) == len(levels)
    for row in rows:  # each folder holds the output of its own file, not of a namesake
        level = levels[Path(row["file"]).relative_to(photos).as_posix()]
        noisy = iio.imread(Path(row["output_dir"]) / "noisy_gaussian.png")
        assert abs(float(np.median(noisy)) - level) < 8
        assert row["status"] == "ok" and row["error"] == ""
    assert (out / "a" / "deep" / "img" / "record.json").is_file()


@pytest.mark.parametrize("seed", range(5))
def test_output_folders_are_distinct_for_any_set_of_paths(seed):
    rng = np.random.default_rng(seed)
    folders = ["", "a", "b", "a/b", "img", "batch.csv"]
    stems = ["img", "img_png", "img-2", "batch", "x.y", ".", "..", "_.", ".graphvision-new-a"]
    suffixes = [".png", ".jpg", ".PNG", ""]
    chosen = {
        Path("root", rng.choice(folders), f"{rng.choice(stems)}{rng.choice(suffixes)}")
        for _ in range(40)
    }
    files = sorted(chosen)
    named = output_folders(files, Path("root"), Path("out"))
    assert len(set(named)) == len(files)
    assert Path("out/batch.csv") not in named
    assert all(".." not in p.parts and p.parts[0] == "out" and len(p.parts) > 1 for p in named)
    assert not any(part.startswith(".graphvision") for p in named for part in p.parts)


def test_files_named_dot_dot_png_get_folders_of_their_own_below_the_output_folder(capsys, tmp_path):
    photos = tmp_path / "photos"
    levels = {"..png": 200, "...png": 60, "a/..png": 120}
    for name, level in levels.items():
        photo(photos / name, level)
    out = tmp_path / "batches" / "out"
    pattern = f"image={photos}/**/.*.png"  # (each a hidden file: a plain * skips them)
    status = main(
        ["run", str(DEMO), "--no-cache", "--batch", pattern, "-d", str(out), "-o", "noisy_gaussian"]
    )
    assert status == 0, capsys.readouterr().err
    rows = list(csv.DictReader((out / "batch.csv").open()))
    folders = {Path(r["file"]).relative_to(photos).as_posix(): r["output_dir"] for r in rows}
    assert folders == {
        "..png": str(out / "_."),
        "...png": str(out / "_.."),
        "a/..png": str(out / "a" / "_."),
    }
    assert sorted(p.name for p in (tmp_path / "batches").iterdir()) == ["out"]  # nothing above
    assert not (out / "record.json").exists()  # nothing in the batch's own folder
    for name, folder in folders.items():
        noisy = iio.imread(Path(folder) / "noisy_gaussian.png")
        assert abs(float(np.median(noisy)) - levels[name]) < 8


def test_a_folder_outside_the_output_folder_is_refused(tmp_path):
    out = tmp_path / "out"
    for folder in (out / ".." / "x", out, tmp_path / "elsewhere"):
        with pytest.raises(OutputFolderError, match="is not a folder below"):
            checked_folders(out, [folder], ["count"])


def test_pattern_root_is_the_part_before_the_first_wildcard():
    assert pattern_root("photos/**/*.png") == Path("photos")
    assert pattern_root("/data/x/*.jpg") == Path("/data/x")
    assert pattern_root("*.png") == Path()
    assert pattern_root("photos/one.png") == Path("photos")


def test_batch_csv_names_the_folder_and_the_error(capsys, tmp_path):
    photo(tmp_path / "in" / "good.png", 100)
    (tmp_path / "in" / "bad.png").write_text("not an image")
    out = tmp_path / "out"
    pattern = f"image={tmp_path}/in/*.png"
    status = main(["run", str(DEMO), "--no-cache", "--batch", pattern, "-d", str(out), "-o", PSNR])
    err = capsys.readouterr().err
    assert status == 1 and "Traceback" not in err
    rows = {Path(r["file"]).name: r for r in csv.DictReader((out / "batch.csv").open())}
    assert rows["bad.png"]["status"] == "failed"
    assert "bad.png is not a readable image" in rows["bad.png"]["error"]
    assert rows["good.png"]["output_dir"] == str(out / "good")
    assert float(rows["good.png"][PSNR]) > 15
    # a file that could not be read has no folder: none is named (out/bad was)
    assert rows["bad.png"]["output_dir"] == "" and not (out / "bad").exists()
    assert f"{tmp_path}/in/bad.png FAILED" in err and f"-> {out / 'bad'}" not in err
    assert f"{tmp_path}/in/good.png -> {out / 'good'} ok" in err


def test_batch_csv_names_the_folder_of_a_failed_file_that_keeps_its_last_run(tmp_path):
    """A file that failed keeps its previous run in history/: its folder is there, named."""
    good, out = photo(tmp_path / "in" / "a.png", 100), tmp_path / "out"
    graph = gv.load_pipeline(DEMO)
    assert gv.run_batch(graph, [good], input="image", output_dir=out).items[0].status == "ok"
    good.write_text("not an image any more")
    (item,) = gv.run_batch(graph, [good], input="image", output_dir=out).items
    rows = list(csv.DictReader((out / "batch.csv").open()))
    assert item.status == "failed" and (out / "a" / "history").is_dir()
    assert rows[0]["output_dir"] == str(out / "a") and item.output_dir == out / "a"


@pytest.mark.parametrize("executor", ["sync", "processes"])
def test_an_item_without_a_folder_names_none_as_batch_csv_does(tmp_path, executor):
    """A file that could not be read, or that failed with no earlier run: its item's
    ``output_dir`` is None, where it named a folder that is not there (batch.csv: empty)."""
    good = photo(tmp_path / "in" / "good.png", 100)
    (tmp_path / "in" / "bad.png").write_text("not an image")
    (tmp_path / "in" / "gone.png").symlink_to(tmp_path / "nowhere.png")
    out = tmp_path / "out"
    batch = gv.run_batch(DEMO, f"{tmp_path}/in/*.png", input="image", output_dir=out,
                         executor=executor)  # fmt: skip
    folders = {item.file.name: item.output_dir for item in batch.items}
    assert folders == {"bad.png": None, "gone.png": None, "good.png": out / "good"}
    rows = {
        Path(r["file"]).name: r["output_dir"] for r in csv.DictReader((out / "batch.csv").open())
    }
    assert rows == {"bad.png": "", "gone.png": "", "good.png": str(out / "good")}
    assert good.is_file()


def test_run_batch_from_python(tmp_path):
    files = [photo(tmp_path / "x" / "img.png", 50), photo(tmp_path / "y" / "img.png", 150)]
    batch = gv.run_batch(
        gv.load_pipeline(DEMO),
        files,
        input="image",
        output_dir=tmp_path / "out",
        outputs=[PSNR],
    )
    assert [item.output_dir for item in batch.items] == [
        tmp_path / "out" / "x" / "img",
        tmp_path / "out" / "y" / "img",
    ]
    assert batch.failed == 0 and all(PSNR in item.scalars for item in batch.items)
    record = json.loads((tmp_path / "out" / "y" / "img" / "record.json").read_text())
    assert record["inputs"]["image"]["path"] == str(files[1].resolve())


def test_batch_folder_of_a_failed_item_keeps_no_stale_outputs(capsys, tmp_path):
    image = photo(tmp_path / "in" / "img.png", 100)
    out = tmp_path / "out"
    pattern = f"image={image.parent}/*.png"
    args = ["run", str(DEMO), "--no-cache", "--batch", pattern, "-d", str(out)]
    assert main([*args, "-o", PSNR]) == 0
    assert (out / "img" / f"{PSNR}.json").is_file()
    image.write_text("now broken")
    assert main([*args, "-o", PSNR]) == 1
    assert not (out / "img" / f"{PSNR}.json").exists()
    assert not (out / "img" / "record.json").exists()
    capsys.readouterr()


def test_a_glob_matching_nothing_is_a_usage_error(capsys, tmp_path):
    status = main(["run", str(DEMO), "--batch", f"image={tmp_path}/*.png", "-d", str(tmp_path)])
    assert status == 2 and "no file matches" in capsys.readouterr().err


def test_file_names_that_are_not_utf8_are_refused_before_anything_runs(capsys, tmp_path):
    """A name with a Latin-1 byte (\\xe9) could not go into batch.csv: the batch ended with
    an internal error after writing the other files, and wrote no summary."""
    import os

    photos = tmp_path / "photos"
    photos.mkdir()
    photo(photos / "ok.png", 100)
    latin = os.fsdecode(bytes(photos) + b"/caf\xe9.png")
    photo(Path(latin), 120)
    out = tmp_path / "out"
    args = ["run", str(DEMO), "--no-cache", "-d", str(out), "-o", PSNR]
    assert main([*args, "--batch", f"image={photos}/*.png"]) == 2
    err = capsys.readouterr().err
    assert f"1 file name(s) are not UTF-8 (such as {photos}/caf\\xe9.png)" in err, err
    assert "internal error" not in err
    assert not out.exists()
    with pytest.raises(gv.InputError, match="are not UTF-8"):  # files given as a list too
        gv.run_batch(gv.load_pipeline(DEMO), [latin], input="image", output_dir=out)
    assert not out.exists()


@pytest.mark.parametrize("batch", [True, False])
def test_an_output_folder_whose_name_is_not_utf8_is_refused_naming_it(capsys, tmp_path, batch):
    """A batch into out\\xff ended every file with an internal error (UnicodeEncodeError)."""
    import os

    good = photo(tmp_path / "photos" / "ok.png", 100)
    out = Path(os.fsdecode(bytes(tmp_path) + b"/out\xff/sub"))
    given = ["--batch", f"image={good}"] if batch else ["-i", f"image={good}"]
    assert main(["run", str(DEMO), "--no-cache", "-d", str(out), *given]) == 2
    err = capsys.readouterr().err
    assert f"error: --output-dir {tmp_path}/out\\xff/sub: its name is not UTF-8;" in err, err
    assert "Traceback" not in err and "internal error" not in err
    assert not out.parent.exists()  # nothing made
    with pytest.raises(gv.OutputFolderError, match=r"out\\xff/sub: its name is not UTF-8"):
        gv.run_batch(gv.load_pipeline(DEMO), [good], input="image", output_dir=out)
    assert not out.parent.exists()


def test_a_pattern_whose_files_are_all_in_the_output_folder_says_so(capsys, tmp_path):
    """Not 'no file matches': they do, and are left out because a batch never reads its
    output folder (an adversary's case)."""
    photos = tmp_path / "photos"
    for name in ("a.png", "b.png"):
        photo(photos / name, 100)
    args = ["run", str(DEMO), "--no-cache", "-d", str(photos), "-o", PSNR]
    assert main([*args, "--batch", f"image={photos}/*.png"]) == 2
    assert (
        f"error: --batch image={photos}/*.png: batch input 'image': every file "
        f"'{photos}/*.png' matches (2, such as {photos}/a.png) is inside the output folder "
        f"{photos}, and a batch never reads its output folder (its own outputs would become "
        "its inputs): move the files out of it, or choose another --output-dir"
    ) in capsys.readouterr().err
    assert sorted(p.name for p in photos.iterdir()) == ["a.png", "b.png"]  # nothing written
    assert main([*args, "--batch", f"image={photos}/*.jpg"]) == 2
    assert f"no file matches '{photos}/*.jpg'" in capsys.readouterr().err  # none at all


def test_files_a_pattern_matches_inside_the_output_folder_are_named_when_others_run(
    capsys, tmp_path
):
    photos, out = tmp_path / "photos", tmp_path / "photos" / "out"
    photo(photos / "a.png", 100)
    photo(out / "b.png", 100)  # left there by hand, or by an earlier step
    args = ["run", str(DEMO), "--no-cache", "-d", str(out), "-o", PSNR]
    assert main([*args, "--batch", f"image={photos}/**/*.png"]) == 0
    err = capsys.readouterr().err
    assert (
        f"warning: batch input 'image': 1 file(s) '{photos}/**/*.png' matches (such as "
        f"{out}/b.png) lie inside the output folder {out} and are left out"
    ) in err
    with pytest.warns(UserWarning, match="lie inside the output folder"):
        gv.run_batch(DEMO, f"{photos}/**/*.png", input="image", output_dir=out, outputs=[PSNR])


# -- image files that were misread -----------------------------------------------------------


def resolved_image(path: Path) -> np.ndarray:
    graph = gv.Graph("identity")
    graph.input("image", "Image")
    graph.output("image", "image")
    return gv.run(graph, inputs={"image": str(path)}).outputs["image"]


def test_a_cmyk_jpeg_reads_as_its_rgb_colours(tmp_path):
    from PIL import Image as PILImage

    rows, cols = np.mgrid[0:32, 0:48]
    rgb = np.dstack([rows * 8, cols * 5, 255 - rows * 8]).astype(np.uint8)  # smooth: JPEG-friendly
    PILImage.fromarray(rgb).convert("CMYK").save(tmp_path / "print.jpg", quality=98)
    image = resolved_image(tmp_path / "print.jpg")
    assert image.shape == (32, 48, 3)
    assert np.abs(image * 255 - rgb).mean() < 3  # JPEG loss only; as RGBA it is off by ~100


def test_a_cmyk_jpeg_with_a_profile_that_cannot_apply_is_refused_by_name(tmp_path):
    from PIL import Image as PILImage
    from PIL import ImageCms

    rgb_profile = ImageCms.ImageCmsProfile(ImageCms.createProfile("sRGB")).tobytes()
    cmyk = PILImage.fromarray(np.zeros((4, 4, 3), np.uint8)).convert("CMYK")
    cmyk.save(tmp_path / "print.jpg", icc_profile=rgb_profile)  # an RGB profile on CMYK data
    with pytest.raises(gv.InputError, match=r"print.jpg is a CMYK image whose embedded colour"):
        resolved_image(tmp_path / "print.jpg")


def test_an_animated_gif_says_what_to_do(tmp_path):
    from PIL import Image as PILImage

    frames = [PILImage.fromarray(np.full((6, 7, 3), 40 * i, np.uint8)) for i in range(3)]
    frames[0].save(tmp_path / "anim.gif", save_all=True, append_images=frames[1:])
    with pytest.raises(gv.InputError, match=r"anim.gif holds 3 frames .* save the frame you want"):
        resolved_image(tmp_path / "anim.gif")


def test_a_file_dropped_from_the_batch_leaves_no_current_looking_folder(capsys, tmp_path):
    photo(tmp_path / "in" / "a.png", 100)
    dropped = photo(tmp_path / "in" / "b.png", 50)
    out = tmp_path / "out"
    args = ["run", str(DEMO), "--no-cache", "--batch", f"image={tmp_path}/in/*.png", "-d", str(out)]
    assert main([*args, "-o", PSNR]) == 0
    (out / "b" / "mine.txt").write_text("kept")
    dropped.unlink()
    capsys.readouterr()
    assert main([*args, "-o", PSNR]) == 0
    assert (  # (said: batch.csv has no row for it)
        f"warning: 1 folder(s) of files no longer in the batch (such as {out / 'b'}) are "
        "emptied: each one's last run is kept in its history/"
    ) in capsys.readouterr().err
    assert {p.name for p in (out / "b").iterdir()} == {"mine.txt", "history"}
    (kept,) = [p for p in (out / "b" / "history").iterdir() if not p.name.startswith(".")]
    assert {p.name for p in kept.iterdir()} >= {"record.json", f"{PSNR}.json"}  # kept, not lost
    assert (out / "a" / "record.json").is_file()
    (out / "batch.csv").write_text("name,score\nx,1\n")  # the user's own table
    assert main([*args, "-o", PSNR]) == 2
    assert "holds batch.csv, which changed since the batch wrote it" in capsys.readouterr().err
    assert (out / "batch.csv").read_text() == "name,score\nx,1\n"


def test_a_batch_never_reads_its_own_outputs(capsys, tmp_path):
    photo(tmp_path / "photos" / "a.png", 100)
    out = tmp_path / "photos" / "out"  # inside the searched folders
    args = ["run", str(DEMO), "--no-cache", "--batch", f"image={tmp_path}/photos/**/*.png"]
    for _ in range(2):
        assert main([*args, "-d", str(out), "-o", "noisy_gaussian"]) == 0
        rows = list(csv.DictReader((out / "batch.csv").open()))
        assert [Path(r["file"]).name for r in rows] == ["a.png"]
    capsys.readouterr()


COUNTING_PLUGIN = '''
import threading
import time
from pathlib import Path

import numpy as np

from graphvision import Float, Image, node

_LOCK = threading.Lock()


def _log(path: str, line: str) -> None:
    with _LOCK, open(path, "a") as handle:
        handle.write(line + "\\n")


@node("counting.model")
def model(*, log: str = "") -> Float:
    """A stand-in for a trained model: every file's run needs it.

    Parameters
    ----------
    log : a file that gets one line each time this runs
    """
    _log(log, "model")
    return 2.0


@node("counting.score")
def score(image: Image, weight: Float, *, log: str = "") -> Float:
    """weight × mean(image), slowly, noting when it starts and ends.

    Parameters
    ----------
    image : the file's image
    weight : the shared model
    log : a file that gets a start and an end line per run
    """
    _log(log, f"start {time.monotonic()}")
    time.sleep(0.3)
    _log(log, f"end {time.monotonic()}")
    return float(weight * image.mean())
'''


def _counting_graph(tmp_path: Path):
    plugin = tmp_path / "counting.py"
    plugin.write_text(COUNTING_PLUGIN)
    registry = gv.discover([plugin])
    log = str(tmp_path / "log.txt")
    graph = gv.Graph("counting")
    image = graph.input("image", "Image")
    weight = graph.add("model", "counting.model", params={"log": log})
    graph.output(
        "score",
        graph.add("score", "counting.score", image=image, weight=weight, params={"log": log}),
    )
    return graph, registry, Path(log)


def test_a_batch_computes_shared_nodes_once_and_runs_files_at_once(tmp_path):
    graph, registry, log = _counting_graph(tmp_path)
    levels = [10, 60, 110, 160, 210, 250]
    files = [photo(tmp_path / "in" / f"{k}.png", level) for k, level in enumerate(levels)]
    seen = []
    batch = gv.run_batch(
        graph,
        [str(f) for f in files],
        input="image",
        output_dir=tmp_path / "out",
        registry=registry,
        cache=gv.Cache.at(tmp_path / "cache"),
        executor="threads",
        workers=3,
        on_item=lambda number, total, item: seen.append((number, total)),
    )
    lines = log.read_text().splitlines()
    assert lines.count("model") == 1  # the shared node ran for the first file only
    assert [item.status for item in batch.items] == ["ok"] * len(files)
    for item, level in zip(batch.items, levels, strict=True):  # results in file order
        assert item.scalars["score"] == pytest.approx(2.0 * level / 255.0, abs=1e-6)
    assert seen == [(n, len(files)) for n in range(1, len(files) + 1)]
    running = most = 0
    for line in lines:  # the log is in time order
        running += {"start": 1, "end": -1}.get(line.split()[0], 0)
        most = max(most, running)
    assert most >= 2  # several files were in flight together


def test_files_at_once_1_runs_files_one_after_another(tmp_path):
    graph, registry, log = _counting_graph(tmp_path)
    files = [photo(tmp_path / "in" / f"{k}.png", 50 + k) for k in range(3)]
    gv.run_batch(
        graph,
        [str(f) for f in files],
        input="image",
        output_dir=tmp_path / "out",
        registry=registry,
        cache=None,
        files_at_once=1,
    )
    lines = [x.split()[0] for x in log.read_text().splitlines() if x != "model"]
    assert lines == ["start", "end"] * 3


def test_on_processes_further_files_go_in_tasks_with_the_shared_values_sent(tmp_path):
    from graphvision.execution.file_task import shared_steps

    graph, registry, log = _counting_graph(tmp_path)
    compiled = gv.compile_graph(graph, registry, provided={"image"})
    assert shared_steps(compiled, "image") == ["model"]
    levels = [10, 60, 110, 160, 210]
    files = [photo(tmp_path / "in" / f"{k}.png", level) for k, level in enumerate(levels)]
    batch = gv.run_batch(
        graph,
        [str(f) for f in files],
        input="image",
        output_dir=tmp_path / "out",
        registry=registry,
        cache=None,
        executor="processes",
        workers=2,
    )
    assert [item.status for item in batch.items] == ["ok"] * len(files), batch.items
    for item, level in zip(batch.items, levels, strict=True):
        assert item.scalars["score"] == pytest.approx(2.0 * level / 255.0, abs=1e-6)
        record = json.loads((item.output_dir / "record.json").read_text())
        assert record["outputs"]["score"].startswith("Float")
    assert log.read_text().splitlines().count("model") == 1  # seeded, never recomputed
    later = json.loads((batch.items[-1].output_dir / "record.json").read_text())
    assert later["executor"] == "processes, up to 8 files a task"
    statuses = {node["name"]: node["status"] for node in later["nodes"]}
    assert statuses == {"model": "cached", "score": "computed"}


@pytest.mark.parametrize("executor", ["threads", "processes"])
def test_a_batch_where_every_file_fails_exits_1_and_still_writes_its_pages(
    capsys, tmp_path, executor
):
    for name in ("a.png", "b.png", "c.png"):
        (tmp_path / "in").mkdir(exist_ok=True)
        (tmp_path / "in" / name).write_text("not an image")
    out = tmp_path / "out"
    pattern = f"image={tmp_path}/in/*.png"
    args = ["run", str(DEMO), "--no-cache", "--batch", pattern, "-d", str(out), "-o", PSNR]
    status = main([*args, "--executor", executor, "--workers", "2"])
    err = capsys.readouterr().err
    assert status == 1 and "Traceback" not in err and "0 of 3 succeeded" in err
    rows = list(csv.DictReader((out / "batch.csv").open()))
    assert [r["status"] for r in rows] == ["failed"] * 3
    assert all("is not a readable image" in r["error"] for r in rows)
    assert (out / "batch.html").read_text().count("failed") >= 3


def test_a_batch_run_again_on_processes_loads_every_file_from_the_cache(tmp_path):
    graph, registry, log = _counting_graph(tmp_path)
    files = [photo(tmp_path / "in" / f"{k}.png", 40 + 50 * k) for k in range(4)]
    options = {
        "input": "image",
        "output_dir": tmp_path / "out",
        "registry": registry,
        "cache": gv.Cache.at(tmp_path / "cache"),
        "executor": "processes",
        "workers": 2,
    }
    first = gv.run_batch(graph, [str(f) for f in files], **options)
    runs = log.read_text().count("start")
    assert runs == len(files)
    later = json.loads((first.items[-1].output_dir / "record.json").read_text())
    assert later["executor"] == "processes, up to 8 files a task"
    again = gv.run_batch(graph, [str(f) for f in files], **options)
    assert log.read_text().count("start") == runs  # nothing computed the second time
    assert [i.scalars for i in again.items] == [i.scalars for i in first.items]
    for item in again.items:
        record = json.loads((item.output_dir / "record.json").read_text())
        assert {n["status"] for n in record["nodes"]} - {"unneeded"} == {"cached"}


def test_an_input_given_by_the_batch_and_by_i_is_refused(capsys, tmp_path):
    photo(tmp_path / "in" / "a.png", 100)
    args = ["run", str(DEMO), "--batch", f"image={tmp_path}/in/*.png", "-d", str(tmp_path / "out")]
    assert main([*args, "-i", "image=sample:coins"]) == 2
    assert "input 'image' is given twice" in capsys.readouterr().err
    assert not any((tmp_path / "out").rglob("*"))  # nothing ran


def test_an_interrupted_batch_still_writes_its_summary(tmp_path):
    for number in range(4):
        photo(tmp_path / "in" / f"p{number}.png", 40 * number + 20)
    out = tmp_path / "out"

    def stop_after_two(done, total, item):
        if done == 2:
            raise KeyboardInterrupt

    graph = gv.load_pipeline(DEMO)
    with pytest.raises(KeyboardInterrupt):
        gv.run_batch(
            graph,
            f"{tmp_path}/in/*.png",
            input="image",
            output_dir=out,
            outputs=[PSNR],
            executor="sync",
            on_item=stop_after_two,
        )
    rows = list(csv.DictReader((out / "batch.csv").open()))
    assert [Path(r["file"]).name for r in rows] == [f"p{n}.png" for n in range(4)]
    assert [r["status"] for r in rows] == ["ok", "ok", "not run", "not run"]
    assert float(rows[0][PSNR]) > 0 and rows[2][PSNR] == ""
    assert "not run" in (out / "batch.html").read_text()
    assert not list(out.glob(".*.tmp"))


def test_files_running_when_a_batch_stops_are_interrupted_not_unrun():
    from graphvision.execution.batch import _not_run
    from graphvision.execution.batch_files import BatchItem

    paths = [Path(f"p{n}.png") for n in range(3)]
    folders = [Path(f"out/p{n}") for n in range(3)]
    done = BatchItem(paths[0], folders[0])
    marked = _not_run([done, None, None], paths, folders, started={0, 1})
    assert [item.status for item in marked] == ["ok", "interrupted", "not run"]
    assert "while this file ran" in marked[1].error and "before this file" in marked[2].error


def test_a_file_reached_through_folder_links_is_taken_once(tmp_path):
    from graphvision.execution.batch_files import batch_files

    photos = tmp_path / "photos"
    photo(photos / "a.png", 10)
    photo(photos / "sub" / "b.png", 20)
    (photos / "sub" / "up").symlink_to(photos, target_is_directory=True)  # a loop
    (tmp_path / "alias").symlink_to(photos, target_is_directory=True)
    with pytest.warns(UserWarning) as warned:
        found = batch_files(f"{photos}/**/*.png")[0]
    assert found == [photos / "a.png", photos / "sub" / "b.png"]
    (said,) = [str(w.message) for w in warned]  # one line for the batch, not one a file
    up = photos / "sub" / "up"
    assert said == (
        f"batch '{photos}/**/*.png': {photos / 'a.png'} is also reached as {up / 'a.png'} "
        f"(symbolic links): taken once, as {photos / 'a.png'}"
    )  # the loop's folder is searched once: up/sub/up/a.png and deeper are not listed


def test_a_file_reached_as_long_through_a_link_is_taken_by_its_real_folder(tmp_path, monkeypatch):
    """``alias -> photos`` sorts first: the batch took alias/a.png, its folder named after
    the link, where photos/a.png is the file's own path (found by TRY44)."""
    from graphvision.execution.batch_files import batch_files

    photo(tmp_path / "photos" / "a.png", 10)
    (tmp_path / "alias").symlink_to("photos", target_is_directory=True)
    monkeypatch.chdir(tmp_path)
    with pytest.warns(UserWarning, match=r"also reached as alias/a.png .* taken once, as photos"):
        assert batch_files("**/a.png")[0] == [Path("photos/a.png")]


def test_folders_reached_by_several_links_are_searched_once(tmp_path):
    """A link back up the tree and a second link aliasing a folder made Python's recursive
    glob list paths by the hundred thousand (gigabytes, never a file run): each real folder
    is now searched once, by its shortest path, and each file found once."""
    from graphvision.execution.batch_files import batch_files

    photos = tmp_path / "photos"
    for name, level in [("a.png", 10), ("sub/b.png", 20), ("sub/deep/c.png", 30)]:
        photo(photos / name, level)
    (photos / "sub" / "up").symlink_to("..", target_is_directory=True)
    (photos / "sub2").symlink_to("sub", target_is_directory=True)
    (photos / "sub" / "deep" / "top").symlink_to("../..", target_is_directory=True)
    with pytest.warns(UserWarning, match="1 more file"):
        found = batch_files(f"{photos}/**/*.png")[0]
    assert found == [photos / "a.png", photos / "sub" / "b.png", photos / "sub/deep/c.png"]


def test_a_file_reached_through_a_link_is_named_with_the_path_kept(capsys, tmp_path):
    """Taken once without a word, a user whose photos/best.png links to a.png saw one
    folder for two names; now a warning names both (and a batch with no link says nothing)."""
    photos = tmp_path / "photos"
    photo(photos / "a.png", 10)
    photo(photos / "c.png", 30)
    args = ["run", str(DEMO), "--no-cache", "-o", PSNR, "--batch", f"image={photos}/*.png"]
    assert main([*args, "-d", str(tmp_path / "out1")]) == 0
    assert "reached as" not in capsys.readouterr().err
    (photos / "best.png").symlink_to("a.png")
    assert main([*args, "-d", str(tmp_path / "out2")]) == 0
    err = capsys.readouterr().err
    assert (
        f"warning: batch '{photos}/*.png': {photos / 'a.png'} is also reached as "
        f"{photos / 'best.png'} (symbolic links): taken once, as {photos / 'a.png'}\n"
    ) in err
    assert sorted(p.name for p in (tmp_path / "out2").iterdir() if p.is_dir()) == ["a", "c"]


def test_no_item_folder_takes_the_name_of_a_file_the_batch_writes_beside_them(tmp_path):
    """Files named ``batch.json.png`` or ``.graphvision-lock.png`` (an adversary's): their
    folders took the manifest's, the page's or the lock's name, and the batch could not
    write its own files there, again and again."""
    names = ["batch.csv.png", "batch.json.png", "batch.html.png", ".graphvision-lock.png",
             ".graphvision-new-a.png", "a.png"]  # fmt: skip
    out = tmp_path / "out"
    folders = output_folders([tmp_path / n for n in names], tmp_path, out)
    assert [f.name for f in folders] == [
        "batch.csv-2", "batch.json-2", "batch.html-2", "_.graphvision-lock",
        "_.graphvision-new-a", "a",
    ]  # fmt: skip


def test_an_unknown_input_is_named_before_a_missing_one(tmp_path):
    """``--batch nope=…`` (or ``-i nope=…``) on a pipeline whose input has no default said
    only that 'image' was missing."""
    graph = gv.Graph("gray")
    graph.input("image", "Image")
    graph.add("gray", "colour.to_gray", image="image")
    graph.output("gray", "gray")
    with pytest.raises(gv.UnknownNameError, match=r"unknown input 'nope'; inputs: image"):
        gv.run(graph, inputs={"nope": np.zeros((4, 4), np.float32)})
    photo(tmp_path / "a.png", 100)
    with pytest.raises(gv.UnknownNameError, match=r"unknown input 'nope'; inputs: image"):
        gv.run_batch(graph, f"{tmp_path}/*.png", input="nope", output_dir=tmp_path / "out")
