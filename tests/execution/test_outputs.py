"""What a run leaves behind and takes in: the dtype policy of graph inputs, the
writer and report for every port type, the record, stale outputs, metrics at
the real image size."""

from __future__ import annotations

import dataclasses
import json
import re
from pathlib import Path

import imageio.v3 as iio
import numpy as np
import pytest

import graphvision as gv
from graphvision.cli import main
from graphvision.execution.folders import write_outputs
from graphvision.execution.provenance import file_sha256
from graphvision.views.report import write_report

from ..conftest import PIPELINES

RNG = np.random.default_rng(7)


def identity_graph(kind: str) -> gv.Graph:
    """A graph whose one output is its one input: what comes out is what the input became."""
    graph = gv.Graph("identity")
    graph.input("value", kind)
    graph.output("value", "value")
    return graph


def resolved(kind: str, value: object) -> object:
    return gv.run(identity_graph(kind), inputs={"value": value}).outputs["value"]


# -- item 15: arrays people have go through the dtype policy of files -----------------

PHOTO_U8 = RNG.integers(0, 256, (6, 7, 3), dtype=np.uint8)
PHOTO_U16 = RNG.integers(0, 65536, (6, 7), dtype=np.uint16)


@pytest.mark.parametrize(
    ("array", "expected"),
    [
        (PHOTO_U8, PHOTO_U8 / 255.0),  # cv2.imread, imageio.imread
        (PHOTO_U16, PHOTO_U16 / 65535.0),  # 16-bit PNG or TIFF
        (PHOTO_U8[..., 0] > 127, PHOTO_U8[..., 0] > 127),  # a thresholded mask
        (PHOTO_U8 / 255.0, PHOTO_U8 / 255.0),  # skimage.img_as_float: float64
        (np.dstack([PHOTO_U8, np.full((6, 7), 255, np.uint8)]), PHOTO_U8 / 255.0),  # RGBA
        (PHOTO_U16[..., None], PHOTO_U16 / 65535.0),  # one channel kept as an axis
    ],
    ids=["uint8", "uint16", "bool", "float64", "rgba", "h-w-1"],
)
def test_arrays_given_to_the_api_follow_the_dtype_policy_of_files(tmp_path, array, expected):
    from_array = resolved("Image", array)
    assert from_array.dtype == np.float32
    np.testing.assert_allclose(from_array, expected, atol=1e-6)
    stored = tmp_path / "same.npy"
    np.save(stored, array)
    np.testing.assert_array_equal(resolved("Image", str(stored)), from_array)
    if array.dtype.kind == "u" and array.shape[-1] != 1:  # what PNG can store
        iio.imwrite(tmp_path / "same.png", array)
        np.testing.assert_array_equal(resolved("Image", str(tmp_path / "same.png")), from_array)


def test_masks_labels_and_points_from_the_arrays_people_have(tmp_path):
    mask = RNG.random((5, 6)) > 0.5
    np.save(tmp_path / "mask.npy", mask)
    loaded = resolved("BinaryImage", str(tmp_path / "mask.npy"))
    assert loaded.dtype == np.bool_
    np.testing.assert_array_equal(loaded, mask)
    iio.imwrite(tmp_path / "mask.png", mask.astype(np.uint8) * 255)  # as a mask is written
    np.testing.assert_array_equal(resolved("BinaryImage", str(tmp_path / "mask.png")), mask)
    labels = np.arange(30, dtype=np.int64).reshape(5, 6)  # skimage.measure.label gives int64
    assert resolved("LabelImage", labels).dtype == np.int32
    points = resolved("Points2D", np.array([[1, 2], [3, 4]]))
    assert points.dtype == np.float64
    np.testing.assert_array_equal(points, [[1, 2], [3, 4]])


def test_arrays_the_policy_refuses_are_named():
    with pytest.raises(gv.InputError, match=r"input 'value': .* float values in \[0, 255\]"):
        resolved("Image", np.linspace(0, 255, 12).reshape(3, 4))
    with pytest.raises(gv.InputError, match=r"not a mask: .* values 0, 1, 2"):
        resolved("BinaryImage", np.arange(3).repeat(4).reshape(3, 4))
    with pytest.raises(gv.InputError, match=r"labels in \[-1, 2\]"):
        resolved("LabelImage", np.array([[-1, 2]]))
    with pytest.raises(gv.InputError, match=r"dtype int16; expected unsigned"):
        resolved("Image", np.zeros((2, 2), np.int16))


# -- item 16: the writer and the report take every value of every port type -------------


def values_of_every_builtin_type() -> dict[type[gv.PortType], list[object]]:
    """Values of each built-in port type, with the small and odd ones that broke the report."""
    keypoints = gv.KeypointSet(
        np.array([[1.0, 2.0], [3.0, 4.0]]), np.ones(2), np.zeros(2), np.ones(2)
    )
    camera = gv.PinholeCamera(
        np.array([[100.0, 0, 5], [0, 100, 4], [0, 0, 1]]), size=np.array([10, 8])
    )
    return {
        gv.ArrayPort: [np.ones((2, 2), bool), np.array([1 + 2j, 3j]), np.arange(40)],
        gv.FloatImagePort: [np.array([[-1.5, 2.0]], np.float32)],
        gv.ImagePort: [np.ones((1, 1), np.float32), RNG.random((9, 9, 3)).astype(np.float32)],
        gv.GrayImagePort: [np.zeros((4, 4), np.float32)],
        gv.ColorImagePort: [np.ones((2, 2, 3), np.float32)],
        gv.BinaryImagePort: [np.eye(4, dtype=bool), RNG.random((9, 9)) > 0.5],
        gv.LabelImagePort: [np.array([[0, 1], [2, 2]], np.int32)],
        gv.KernelPort: [np.full((3, 3), 1 / 9)],
        gv.Points2DPort: [np.zeros((0, 2)), RNG.random((20, 2))],
        gv.Points3DPort: [np.array([[0.0, 1.0, 2.0]])],
        gv.DescriptorsPort: [np.zeros((0, 128), np.float32), np.ones((2, 4), np.float32)],
        gv.HomographyPort: [np.eye(3)],
        gv.KeypointsPort: [gv.KeypointSet.empty(), keypoints],
        gv.MatchesPort: [gv.MatchSet(np.array([[0, 1]]), np.array([0.5]))],
        gv.CameraPort: [camera],
        gv.BoxesPort: [
            gv.BoxSet(np.zeros((0, 4)), np.zeros(0)),
            gv.BoxSet(np.array([[1.0, 2.0, 5.0, 7.0]]), np.array([0.9])),
        ],
        gv.FloatPort: [float("inf"), float("nan"), 0.25],
        gv.IntPort: [3],
        gv.BoolPort: [True],
        gv.TextPort: ["a | b\nc"],
        gv.TablePort: [{"x": np.arange(3.0), "ok": np.array([True, False, True])}, {}],
    }


def test_every_builtin_port_type_is_written_and_reported(tmp_path):
    from graphvision.values.builtin import builtin_port_types

    samples = values_of_every_builtin_type()
    assert set(builtin_port_types()) == set(samples), "a port type without a sample value"
    graph = gv.Graph("every-type")
    given = {}
    for kind, values in samples.items():
        for number, value in enumerate(values):
            name = f"{kind.type_name().lower()}_{number}"
            graph.input(name, kind.type_name())
            graph.output(name, name)
            given[name] = value
    result = gv.run(graph, inputs=given)
    files = write_outputs(result.compiled, result.outputs, tmp_path)
    report = write_report(result.compiled, result.outputs, files, result.record, tmp_path)
    rows = [line for line in report.read_text().splitlines() if line.startswith("| ")]
    assert len(rows) == 2 + len(given)  # header, rule and one row per output, each one line
    assert all(len(re.findall(r"(?<!\\)\|", line)) == 4 for line in rows)  # no cell broke it
    for name, value in given.items():
        assert files[name] and all((tmp_path / f).is_file() for f in files[name])
        if isinstance(value, np.ndarray) and files[name][0].endswith(".npy"):
            np.testing.assert_array_equal(np.load(tmp_path / files[name][0]), value)
    assert "`[[true, false, false, false]," in report.read_text()  # the 4×4 mask by value
    json.loads(result.record.to_json())


# -- item 16: a pipeline's metric uses the geometry of its input ---------------------------


def corners_mean_error(estimated: np.ndarray, truth: np.ndarray, width: int, height: int) -> float:
    w, h = width - 1, height - 1
    corners = np.array([[0, 0, 1], [w, 0, 1], [w, h, 1], [0, h, 1]])
    a, b = corners @ estimated.T, corners @ truth.T
    return float(np.linalg.norm(a[:, :2] / a[:, 2:] - b[:, :2] / b[:, 2:], axis=1).mean())


def test_corner_error_is_measured_at_the_image_size():
    from graphvision_plugins import geometry

    scale = np.diag([1.01, 1.01, 1.0])  # corner (x, y) moves by 0.01 (x, y)
    image = np.zeros((172, 448), np.float32)
    expected = 0.01 * (447 + 171 + np.hypot(447, 171)) / 4
    assert geometry.corner_error(scale, np.eye(3), image) == pytest.approx(expected)
    assert geometry.corner_error(scale, np.eye(3), width=448, height=172) == pytest.approx(expected)
    with pytest.raises(ValueError, match="connect it to input 'image', or set both"):
        geometry.corner_error(scale, np.eye(3))
    with pytest.raises(ValueError, match="500×172 disagrees with the connected image"):
        geometry.corner_error(scale, np.eye(3), image, width=500, height=172)


def test_homography_pipeline_reports_the_error_of_its_own_input(tmp_path):
    import skimage.data

    crop = skimage.data.astronaut()[:172, 32:480]  # 172×448: not the 512×512 default
    iio.imwrite(tmp_path / "crop.png", crop)
    out = gv.run(
        gv.load_pipeline(PIPELINES / "homography.yaml"),
        inputs={"image": str(tmp_path / "crop.png")},
        outputs=["homography", "true_homography", "corner_error"],
    ).outputs
    truth = corners_mean_error(out["homography"], out["true_homography"], 448, 172)
    assert out["corner_error"] == pytest.approx(truth, rel=1e-9)


def test_cli_writes_a_bool_output_of_a_few_pixels(capsys, tmp_path):
    pipeline = tmp_path / "tiny.yaml"
    pipeline.write_text(
        "version: 1\nname: tiny\ninputs:\n  image: {type: GrayImage}\n"
        "nodes:\n  mask: {op: threshold.otsu, in: {image: image}}\n"
        "outputs:\n  mask: mask.mask\n"
    )
    np.save(tmp_path / "img.npy", np.array([[0, 0], [1, 1]], np.uint8) * 255)
    status = main(
        ["run", str(pipeline), "-i", f"image={tmp_path / 'img.npy'}", "-d", str(tmp_path / "o")]
    )
    err = capsys.readouterr().err
    assert status == 0, err
    assert "[[false, false], [true, true]]" in (tmp_path / "o" / "report.md").read_text()


# -- item 13: an output folder holds one run, and its record says how to reproduce it --------

DEMO = PIPELINES / "denoise.yaml"


def run_cli(capsys, *args):
    status = main([str(a) for a in args])
    err = capsys.readouterr().err
    assert "Traceback" not in err
    return status, err


def test_a_rerun_removes_the_previous_runs_outputs_and_only_those(capsys, tmp_path):
    out = tmp_path / "out"
    assert run_cli(capsys, "run", DEMO, "-d", out)[0] == 0
    first = {p.name for p in out.iterdir()}
    assert "median_on_salt_pepper.png" in first
    (out / "notes.txt").write_text("mine")
    (out / "sub").mkdir()
    (out / "sub" / "median_on_salt_pepper.png").write_text("mine too")
    assert run_cli(capsys, "run", DEMO, "-d", out, "-o", "psnr_noisy_gaussian")[0] == 0
    left = {p.name for p in out.iterdir()}
    assert left == {
        "psnr_noisy_gaussian.json",
        "record.json",
        "report.md",
        "report.html",
        "notes.txt",
        "sub",
        "history",  # the previous run, kept whole in history/<entry>/
    }
    (kept,) = [p for p in (out / "history").iterdir() if p.is_dir()]
    assert {p.name for p in kept.iterdir()} == first
    assert (out / "sub" / "median_on_salt_pepper.png").read_text() == "mine too"
    record = json.loads((out / "record.json").read_text())
    assert record["files"] == {"psnr_noisy_gaussian": ["psnr_noisy_gaussian.json"]}


def test_a_folder_with_files_graphvision_did_not_write_is_refused_before_running(capsys, tmp_path):
    (tmp_path / "report.md").write_text("my thesis notes")
    status, err = run_cli(capsys, "run", DEMO, "-d", tmp_path, "--progress")
    assert status == 2
    assert re.search(r"output folder .* holds report.md, which no graphvision record", err)
    assert "running" not in err  # refused before anything ran
    assert (tmp_path / "report.md").read_text() == "my thesis notes"
    (tmp_path / "report.md").unlink()
    (tmp_path / "psnr_noisy_gaussian.json").write_text("{}")  # an output's name, not ours
    status, err = run_cli(capsys, "run", DEMO, "-d", tmp_path, "-o", "psnr_noisy_gaussian")
    assert status == 2 and "holds psnr_noisy_gaussian.json" in err
    (tmp_path / "psnr_noisy_gaussian.json").unlink()
    (tmp_path / "record.json").write_text('{"files": {"x": ["../escape.txt"]}}')
    status, err = run_cli(capsys, "run", DEMO, "-d", tmp_path, "-o", "psnr_noisy_gaussian")
    assert status == 2 and "is not a graphvision record listing its files" in err


def test_the_record_holds_what_reproducing_the_run_needs(capsys, tmp_path):
    import hashlib
    import shutil
    import subprocess

    repo = tmp_path / "repo"
    repo.mkdir()
    pipeline = Path(shutil.copy(DEMO, repo / "denoise.yaml"))
    git = ["git", "-C", str(repo), "-c", "user.name=t", "-c", "user.email=t@t"]
    subprocess.run([*git, "init", "-q"], check=True)
    subprocess.run([*git, "add", "denoise.yaml"], check=True)
    subprocess.run([*git, "commit", "-qm", "pipeline"], check=True)
    head = subprocess.run([*git, "rev-parse", "HEAD"], capture_output=True, text=True).stdout
    image = tmp_path / "photo.png"
    iio.imwrite(image, (np.random.default_rng(0).random((20, 24)) * 255).astype(np.uint8))
    cache, out = tmp_path / "cache", tmp_path / "out"
    args = ["run", pipeline, "-i", f"image={image}", "-s", "median_on_sp.size=5", "-d", out]
    assert run_cli(capsys, *args, "--cache-dir", cache)[0] == 0
    first = json.loads((out / "record.json").read_text())
    assert first["pipeline_file"] == str(pipeline.resolve())
    assert first["pipeline_sha256"] == hashlib.sha256(pipeline.read_bytes()).hexdigest()
    assert first["git_commit"] == head.strip() and first["git_dirty"] is False
    assert first["inputs"]["image"]["sha256"] == hashlib.sha256(image.read_bytes()).hexdigest()
    assert first["inputs"]["image"]["path"] == str(image.resolve())
    assert first["overrides"] == {"median_on_sp.size": 5}
    assert first["params"] == {"seed": 0}
    assert {"python", "graphvision", "numpy", "scipy", "plugin filters"} <= set(first["versions"])
    assert first["date"].endswith("+00:00")
    report = (out / "report.md").read_text()
    assert f"SHA-256 {first['pipeline_sha256'][:12]}, git {head[:12]})" in report
    assert (
        f"input `image`: `{image.resolve()}` (SHA-256 {first['inputs']['image']['sha256'][:12]})"
        in report
    )
    nodes = {n["name"]: n for n in first["nodes"]}
    assert nodes["median_on_sp"]["params"]["size"] == 5
    assert all(n["keys"] and n["status"] == "computed" for n in nodes.values())
    assert run_cli(capsys, *args, "--cache-dir", cache)[0] == 0  # all from the cache
    again = {n["name"]: n for n in json.loads((out / "record.json").read_text())["nodes"]}
    cached = [name for name, node in again.items() if node["status"] == "cached"]
    assert cached and all(again[name]["keys"] == nodes[name]["keys"] for name in cached)
    images = [name for name in cached if name.startswith(("noisy", "gaussian", "median"))]
    assert images and all(again[name]["output_bytes"] == 20 * 24 * 4 for name in images)


def test_an_output_named_record_is_refused_and_leftover_staging_is_cleared(capsys, tmp_path):
    pipeline = tmp_path / "p.yaml"
    pipeline.write_text(DEMO.read_text().replace("psnr_noisy_gaussian:", "record:"))
    status, err = run_cli(capsys, "run", pipeline, "-d", tmp_path / "o", "-o", "record")
    assert status == 2 and "output 'record' cannot be written to an output folder" in err
    out = tmp_path / "out"
    (out / ".graphvision-writing-x1").mkdir(parents=True)  # a run killed while writing
    assert run_cli(capsys, "run", DEMO, "-d", out, "-o", "psnr_noisy_gaussian")[0] == 0
    assert not (out / ".graphvision-writing-x1").exists()


def test_the_git_state_follows_edits_and_commits_within_one_process(tmp_path):
    import subprocess

    from graphvision.execution.provenance import git_state

    repo = tmp_path / "repo"
    repo.mkdir()
    pipeline = repo / "p.yaml"
    pipeline.write_text("version: 1\n")
    git = ["git", "-C", str(repo), "-c", "user.name=t", "-c", "user.email=t@t"]
    subprocess.run([*git, "init", "-q"], check=True)
    subprocess.run([*git, "add", "p.yaml"], check=True)
    subprocess.run([*git, "commit", "-qm", "one"], check=True)

    def head() -> str:
        return subprocess.run([*git, "rev-parse", "HEAD"], capture_output=True, text=True).stdout

    first = head().strip()
    assert git_state(pipeline) == (first, False)
    assert git_state(pipeline) == (first, False)  # asked again: the kept answer
    pipeline.write_text("version: 1\nname: edited\n")
    assert git_state(pipeline) == (first, True)
    subprocess.run([*git, "commit", "-qam", "two"], check=True)
    assert git_state(pipeline) == (head().strip(), False) != (first, False)
    assert git_state(tmp_path / "elsewhere.yaml") == ("", False)


def test_report_writes_a_run_folders_pages_again_and_names_what_is_gone(capsys, tmp_path):
    import shutil

    pipeline = Path(shutil.copy(DEMO, tmp_path / "denoise.yaml"))
    out = tmp_path / "out"
    assert run_cli(capsys, "run", pipeline, "-d", out, "--no-cache")[0] == 0
    page = (out / "report.html").read_text()
    (out / "report.html").unlink()
    (out / "report.md").unlink()
    status, err = run_cli(capsys, "report", out)
    assert status == 0, err
    again = (out / "report.html").read_text()
    assert again.count("<img") == page.count("<img") > 3  # every picture is back
    assert "psnr_noisy_gaussian" in (out / "report.md").read_text()
    record = json.loads((out / "record.json").read_text())
    gone = record["files"]["noisy_gaussian"][0]
    (out / gone).unlink()
    status, err = run_cli(capsys, "report", out)
    assert status == 2 and f"output 'noisy_gaussian' of the run in {out} is gone ({gone})" in err
    pipeline.unlink()
    status, err = run_cli(capsys, "report", out)
    assert status == 2 and "the pipeline file of the run" in err and "is gone" in err
    status, err = run_cli(capsys, "report", tmp_path)
    assert status == 2 and "has no record.json: it is not a graphvision run folder" in err
    status, err = run_cli(capsys, "report", tmp_path / "nowhere")
    assert status == 2 and "nowhere: no such folder (give a run's -d folder)" in err
    record["files"]["noisy_gaussian"] = ["../../elsewhere.png"]
    (out / "record.json").write_text(json.dumps(record))
    status, err = run_cli(capsys, "report", out)
    assert status == 2 and "lists a file outside its folder" in err


def test_the_markdown_report_shows_a_pipelines_markup_as_text(capsys, tmp_path):
    text = DEMO.read_text()
    name = next(line for line in text.splitlines() if line.startswith("name:"))
    hostile = text.replace(name, 'name: "<script>alert(1)</script>"', 1)
    hostile = hostile.replace("description:", 'description: <img src=x onerror="alert(2)"> ', 1)
    pipeline = tmp_path / "hostile.yaml"
    pipeline.write_text(hostile)
    status, err = run_cli(capsys, "run", pipeline, "--no-cache", "-d", tmp_path / "o")
    assert status == 0, err
    report = (tmp_path / "o" / "report.md").read_text()
    assert "<script>" not in report and "<img" not in report
    assert "# &lt;script&gt;alert(1)&lt;/script&gt;" in report


@pytest.fixture(scope="module")
def run_folder(tmp_path_factory):
    """A run of the denoise demo, with its pipeline copied beside it."""
    import shutil

    from graphvision.cli import main

    folder = tmp_path_factory.mktemp("run")
    pipeline = Path(shutil.copy(DEMO, folder / "denoise.yaml"))
    assert main(["run", str(pipeline), "-d", str(folder / "out"), "--no-cache"]) == 0
    return folder


def _damaged(record: dict, case: int) -> object:
    """The record with one field of the wrong kind, case by case (every field, four kinds)."""
    fields = [*record, "nodes.0.name", "nodes.0.seconds", "files.noisy_gaussian"]
    key, wrong = fields[case // 4], [None, [], "x", 5][case % 4]
    damaged = json.loads(json.dumps(record))
    target, name = damaged, key
    for part in key.split(".")[:-1]:
        target = target[int(part)] if part.isdigit() else target[part]
        name = key.split(".")[-1]
    target[name] = wrong
    return damaged


@pytest.mark.parametrize("case", range(4 * (len(dataclasses.fields(gv.RunRecord)) + 3)))
def test_report_refuses_a_damaged_record_naming_it(capsys, run_folder, tmp_path, case):
    import shutil

    out = Path(shutil.copytree(run_folder / "out", tmp_path / "out"))
    record = json.loads((out / "record.json").read_text())
    damaged = _damaged(record, case)
    (out / "record.json").write_text(json.dumps(damaged))
    status, err = run_cli(capsys, "report", out)
    if status == 0:  # the wrong value was one the record may hold (an empty list of files)
        return
    assert status == 2, err
    assert err.startswith("error: ") and len(err.strip().splitlines()) == 1, err
    assert "internal error" not in err


@pytest.mark.parametrize("content", ["[]", "5", '"text"', "{", ""])
def test_report_refuses_a_record_that_is_not_an_object(capsys, run_folder, tmp_path, content):
    import shutil

    out = Path(shutil.copytree(run_folder / "out", tmp_path / "out"))
    (out / "record.json").write_text(content)
    status, err = run_cli(capsys, "report", out)
    assert status == 2 and "is not a graphvision run record" in err, err


def test_report_after_the_pipeline_changed_warns_or_refuses(capsys, run_folder, tmp_path):
    import shutil

    out = Path(shutil.copytree(run_folder / "out", tmp_path / "out"))
    pipeline = run_folder / "denoise.yaml"
    original = pipeline.read_text()
    try:
        pipeline.write_text(original + "\n# a comment added after the run\n")
        status, err = run_cli(capsys, "report", out)
        assert status == 0 and "changed since the run" in err
        output = next(line for line in original.splitlines() if "psnr_noisy_gaussian:" in line)
        pipeline.write_text(original.replace(output, "  psnr_noisy_gaussian: noisy_gauss"))
        status, err = run_cli(capsys, "report", out)
        assert status == 2 and "output 'psnr_noisy_gaussian' was Float and is now" in err, err
    finally:
        pipeline.write_text(original)


def test_a_rerun_keeps_output_files_whose_value_and_bytes_are_unchanged(capsys, tmp_path):
    """Same value (cache key) and untouched bytes (SHA-256 as recorded): the file is kept,
    not encoded again; an edited file or a new value is written again."""
    import os

    out = tmp_path / "o"
    args = ["run", DEMO, "-d", out, "--cache-dir", tmp_path / "cache"]
    assert run_cli(capsys, *args)[0] == 0
    record = json.loads((out / "record.json").read_text())
    picture = out / record["files"]["noisy_gaussian"][0]
    assert record["file_sha256"][picture.name] == file_sha256(picture)
    os.utime(picture, (1, 1))  # a time no writer would give it
    assert run_cli(capsys, *args)[0] == 0
    assert picture.stat().st_mtime == 1  # kept as it was
    assert json.loads((out / "record.json").read_text())["file_sha256"] == record["file_sha256"]
    picture.write_bytes(picture.read_bytes()[:-1])  # edited by hand
    status, err = run_cli(capsys, "report", out)
    assert status == 0 and f"output 'noisy_gaussian' in {out} was edited since the run" in err
    assert run_cli(capsys, *args)[0] == 0
    assert file_sha256(picture) == record["file_sha256"][picture.name]  # written again
    os.utime(picture, (1, 1))
    assert run_cli(capsys, *args, "-s", "noisy_gauss.sigma=0.2")[0] == 0
    assert picture.stat().st_mtime != 1  # a new value: a new file
    assert file_sha256(picture) != record["file_sha256"][picture.name]
