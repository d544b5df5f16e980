"""The command line: exit codes, messages without tracebacks, outputs and reports."""

from __future__ import annotations

import json
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from graphvision.cli import main

from ..conftest import PIPELINES, TOY, write

DEMO = PIPELINES / "denoise.yaml"


def cli(capsys, *args):
    status = main([str(a) for a in args])
    out, err = capsys.readouterr()
    assert "Traceback" not in err
    return status, out, err


def test_run_writes_outputs_record_and_report(capsys, tmp_path):
    status, _, err = cli(capsys, "run", DEMO, "--output-dir", tmp_path, "--record", "--no-progress")
    assert status == 0, err
    names = {p.name for p in tmp_path.iterdir()}
    assert {
        "median_on_salt_pepper.png",
        "psnr_median_on_salt_pepper.json",
        "record.json",
        "report.md",
    } <= names
    record = json.loads((tmp_path / "record.json").read_text())
    assert {n["status"] for n in record["nodes"]} == {"computed"}
    report = (tmp_path / "report.md").read_text()
    assert "## Run record" in report and "median_on_salt_pepper.png" in report


def test_rerun_with_a_changed_parameter_uses_the_disk_cache(capsys, tmp_path):
    cache = tmp_path / "c"
    cli(capsys, "run", DEMO, "--cache-dir", cache, "-o", "psnr_median_on_salt_pepper")
    status, out, _ = cli(
        capsys,
        "run",
        DEMO,
        "--cache-dir",
        cache,
        "--record",
        "-o",
        "psnr_median_on_salt_pepper",
        "--set",
        "median_on_sp.size=5",
    )
    assert status == 0
    table = out.splitlines()[
        out.splitlines().index(next(x for x in out.splitlines() if x.startswith("node "))) :
    ]
    rows = {line.split()[0]: line.split()[2] for line in table[1:-1]}
    assert rows == {
        "gray": "cached",
        "noisy_sp": "cached",
        "median_on_sp": "computed",
        "psnr_median_on_sp": "computed",
    }


def test_input_from_a_file(capsys, tmp_path):
    image = tmp_path / "img.npy"
    np.save(image, np.full((16, 16), 0.5, np.float32))
    status, out, err = cli(
        capsys, "run", DEMO, "--no-cache", "-i", f"image={image}", "-o", "psnr_noisy_gaussian"
    )
    assert status == 0, err
    assert out.startswith("psnr_noisy_gaussian: Float ")


@pytest.mark.parametrize(
    ("make", "message"),
    [
        (lambda d: d / "missing.png", "input 'image': no such file: .*missing.png$"),
        (lambda d: Path("/dev/zero"), "/dev/zero is not a regular file"),
        (lambda d: write(d, "text.png", "not a png"), "text.png is not a readable image"),
        (lambda d: _npy(d, np.zeros((0, 5), np.float32)), "is empty"),
        (
            lambda d: _npy(d, np.zeros((2, 3, 4, 5), np.float32)),
            r"must be H×W .* got shape \(2, 3, 4, 5\)",
        ),
        (lambda d: _npy(d, np.full((4, 4), 3.0)), r"float values in \[3, 3\]; expected \[0, 1\]"),
    ],
)
def test_bad_input_files_exit_2_with_a_message(capsys, tmp_path, make, message):
    status, _, err = cli(capsys, "run", DEMO, "--no-cache", "-i", f"image={make(tmp_path)}")
    assert status == 2
    assert pytest.importorskip("re").search(message, err), err


def _npy(folder, array):
    path = folder / "a.npy"
    np.save(path, array)
    return path


def test_unreadable_input_path(capsys, tmp_path):
    folder = tmp_path / "photo.png"
    folder.mkdir()
    status, _, err = cli(capsys, "run", DEMO, "--no-cache", "-i", f"image={folder}")
    assert status == 2 and "photo.png is a folder, not an image file" in err


def test_unknown_sample(capsys):
    status, _, err = cli(capsys, "run", DEMO, "--no-cache", "-i", "image=sample:camra")
    assert status == 2
    assert "unknown sample image 'camra' (did you mean 'camera'?)" in err


def test_invalid_pipeline_exits_2_listing_problems(capsys, tmp_path):
    path = write(
        tmp_path, "bad.yaml", "name: bad\nnodes:\n  a: {op: filters.gausian}\noutputs: {o: a}\n"
    )
    status, _, err = cli(capsys, "run", path)
    assert status == 2
    assert f"nodes.a.op at {path}:3: unknown op 'filters.gausian' (did you mean" in err
    status, _, err = cli(capsys, "validate", path)
    assert status == 2 and "unknown op" in err


def test_bad_parameter_from_the_command_line(capsys):
    status, _, err = cli(capsys, "run", DEMO, "--set", "median_on_sp.size=4")
    assert status == 2
    assert "invalid value 4 for parameter 'size' of filters.median" in err
    assert "of filters.median: must be odd so the window is centred on a pixel, got 4" in err
    status, _, err = cli(capsys, "run", DEMO, "--set", "nosuch.size=4")
    assert status == 2 and "no node 'nosuch'" in err
    status, _, err = cli(capsys, "run", DEMO, "--set", "oops")
    assert status == 2 and "--set expects NAME=VALUE, got 'oops'" in err


def test_a_failing_node_exits_1_and_keeps_other_outputs(capsys, tmp_path):
    path = write(
        tmp_path,
        "f.yaml",
        "name: f\ninputs: {x: {type: Float, default: 1.0}}\nnodes:\n"
        "  bad: {op: toy.fail, in: {x: x}}\n  ok: {op: toy.add, in: {a: x, b: x}}\n"
        "outputs: {bad: bad, ok: ok}\n",
    )
    status, _, err = cli(
        capsys, "run", path, "--plugins", TOY, "--keep-going", "-d", tmp_path / "o"
    )
    assert status == 1
    assert "node 'bad' (op toy.fail) failed: RuntimeError: boom" in err
    assert (tmp_path / "o" / "ok.json").read_text().strip() == "2.0"
    assert "| bad | not produced |" in (tmp_path / "o" / "report.md").read_text()
    status = main(["run", str(path), "--plugins", str(TOY), "--debug"])
    err = capsys.readouterr().err
    assert status == 1 and "Traceback" in err and "raise RuntimeError(message)" in err


def test_usage_errors_exit_2(capsys):
    assert cli(capsys, "frobnicate")[0] == 2
    assert cli(capsys, "run")[0] == 2
    status, _, err = cli(capsys, "describe", "filters.gausian")
    assert status == 2 and "did you mean 'filters.gaussian'" in err


def test_nodes_and_describe(capsys):
    status, out, _ = cli(capsys, "nodes")
    assert status == 0 and "filters\n" in out and "filters.median" in out
    status, out, _ = cli(capsys, "describe", "filters.median")
    assert "size: " in out and "inputs:\n  image: Image" in out
    status, out, _ = cli(capsys, "describe", "filters.median", "--json")
    info = json.loads(out)
    assert info["params"]["properties"]["size"]["maximum"] == 31
    status, out, _ = cli(capsys, "nodes", "--json")
    assert "metrics.psnr" in json.loads(out)


def test_schema_and_graph(capsys):
    _, out, _ = cli(capsys, "schema")
    assert json.loads(out)["title"] == "graphvision pipeline"
    _, out, _ = cli(capsys, "graph", DEMO)
    assert out.startswith("digraph pipeline {") and "gray -> noisy_gauss" in out
    _, out, _ = cli(capsys, "graph", DEMO, "--format", "mermaid")
    assert out.startswith("flowchart LR")


def test_cache_commands(capsys, tmp_path):
    cache = tmp_path / "c"
    cli(capsys, "run", DEMO, "--cache-dir", cache, "-o", "psnr_noisy_gaussian")
    status, out, _ = cli(capsys, "cache", "info", "--cache-dir", cache)
    assert status == 0 and "entries:   3" in out
    status, out, _ = cli(capsys, "cache", "prune", "--cache-dir", cache, "--max-bytes", "1M")
    assert "freed" in out
    status, out, _ = cli(capsys, "cache", "clear", "--cache-dir", cache)
    assert out.startswith("removed ")
    assert "entries:   0" in cli(capsys, "cache", "info", "--cache-dir", cache)[1]


@pytest.mark.parametrize("command", [["run", DEMO], ["cache", "clear"], ["cache", "prune"]])
def test_a_folder_of_user_files_is_never_used_as_a_cache(capsys, tmp_path, command):
    thesis = tmp_path / "thesis"
    (thesis / "chapter1").mkdir(parents=True)
    write(thesis / "chapter1", "figure.png", "png")
    write(thesis, "thesis.tex", "tex")
    before = sorted(p.relative_to(thesis) for p in thesis.rglob("*"))
    status, _, err = cli(capsys, *command, "--cache-dir", thesis)
    assert status == 2
    assert err.count("\n") == 1 and "is not a graphvision cache: it holds 'chapter1'" in err
    assert sorted(p.relative_to(thesis) for p in thesis.rglob("*")) == before


@pytest.mark.parametrize("size", ["0", "-1", "-2G"])
def test_a_cache_size_must_be_positive(capsys, tmp_path, size):
    status, _, err = cli(capsys, "run", DEMO, f"--cache-max-bytes={size}", "--cache-dir", tmp_path)
    assert status == 2 and "a size must be positive" in err and err.count("\n") == 1


def test_unwritable_cache_dir_warns_and_the_run_goes_on(capsys, tmp_path):
    blocker = write(tmp_path, "file", "x")
    status, _, err = cli(
        capsys, "run", DEMO, "--cache-dir", blocker / "c", "-o", "psnr_noisy_gaussian"
    )
    assert status == 0
    assert "warning: cache directory" in err and "running without the disk cache" in err


def test_batch_runs_each_file_and_keeps_going(capsys, tmp_path):
    import csv

    import imageio.v3 as iio

    photos = tmp_path / "photos"
    photos.mkdir()
    iio.imwrite(photos / "a.png", np.full((20, 30), 128, np.uint8))
    iio.imwrite(photos / "b.png", np.full((25, 20), 64, np.uint8))
    (photos / "c.png").write_text("not an image")
    out = tmp_path / "out"
    status, _, err = cli(
        capsys,
        "run",
        DEMO,
        "--no-cache",
        "--batch",
        f"image={photos}/*.png",
        "-d",
        out,
        "-o",
        "psnr_noisy_gaussian",
    )
    assert status == 1  # one file failed, the others finished
    rows = list(csv.DictReader((out / "batch.csv").open()))
    assert [r["status"] for r in rows] == ["ok", "ok", "failed"]
    assert float(rows[0]["psnr_noisy_gaussian"]) > 15
    assert (out / "a" / "psnr_noisy_gaussian.json").exists() and (out / "b" / "report.md").exists()
    assert "c.png is not a readable image" in err and "2 of 3 succeeded" in err


def test_batch_usage_errors(capsys, tmp_path):
    status, _, err = cli(capsys, "run", DEMO, "--batch", f"image={tmp_path}/*.png", "-d", tmp_path)
    assert status == 2 and "no file matches" in err
    status, _, err = cli(capsys, "run", DEMO, "--batch", f"image={tmp_path}/*.png")
    assert status == 2 and "--batch needs --output-dir" in err


# -- the command line as a Unix tool (issue 7, items 7-12) -----------------------------

PSNR_OUT = "psnr_noisy_gaussian"


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["-s", "gauss_on_gauss.sigma=[1,"], r"--set gauss_on_gauss.sigma=\[1,: .*malformed YAML"),
        (["--workers", "0"], r"--workers: must be at least 1, got 0"),
        (["--workers=-2"], r"--workers: must be at least 1, got -2"),
        (
            ["-s", "gauss_on_gaus.sigma=2"],
            r"no node 'gauss_on_gaus' \(did you mean 'gauss_on_gauss'",
        ),
        (
            ["-s", "gauss_on_gauss.sgma=2"],
            r"filters.gaussian has no parameter 'sgma' \(did you mean",
        ),
        (["-s", "params.sed=2"], r"--set params.sed=2: the pipeline has no param 'sed' \(did you"),
    ],
)
def test_malformed_command_line_values_are_refused_before_running(capsys, tmp_path, extra, message):
    status, _, err = cli(capsys, "run", DEMO, "-d", tmp_path / "out", "--no-cache", *extra)
    assert status == 2 and err.count("\n") == 1
    assert re.search(message, err), err
    assert not (tmp_path / "out" / "record.json").exists()


def test_every_override_that_names_nothing_is_refused_at_once(capsys, tmp_path):
    args = ["-s", "gauss_on_gaus.sigma=2", "-s", "gauss_on_gauss.sgma=2", "-s", "params.sed=2"]
    status, _, err = cli(capsys, "run", DEMO, "-d", tmp_path / "out", "--no-cache", *args)
    assert status == 2 and "3 overrides name nothing in the pipeline:" in err, err
    assert "  - --set gauss_on_gaus.sigma=2: the pipeline has no node 'gauss_on_gaus'" in err
    assert "  - --set gauss_on_gauss.sgma=2: filters.gaussian has no parameter 'sgma'" in err
    assert "  - --set params.sed=2: the pipeline has no param 'sed'" in err


def test_output_dir_that_is_a_file_or_cannot_be_made(capsys, tmp_path):
    blocker = write(tmp_path, "blocker", "x")
    status, _, err = cli(capsys, "run", DEMO, "-d", blocker, "--no-cache")
    assert status == 2 and "is a file, not a folder" in err
    status, _, err = cli(capsys, "run", DEMO, "-d", blocker / "sub", "--no-cache")
    assert status == 2 and "cannot be made" in err


def test_a_param_set_from_pipeline_params_can_be_overridden(capsys):
    status, _, err = cli(
        capsys, "run", DEMO, "--no-cache", "-o", PSNR_OUT, "-s", "noisy_gauss.seed=3"
    )
    assert status == 0, err


@pytest.mark.parametrize("where", ["before", "after"])
def test_global_options_go_before_or_after_the_command(capsys, where):
    args = (
        ["--plugins", str(TOY), "nodes"] if where == "before" else ["nodes", "--plugins", str(TOY)]
    )
    status, out, _ = cli(capsys, *args)
    assert status == 0 and "toy.add" in out


def test_a_plugins_path_that_does_not_exist_is_a_usage_error(capsys, tmp_path):
    status, _, err = cli(capsys, "nodes", "--plugins", tmp_path / "nope.py")
    assert status == 2 and "no such file or folder" in err


def test_environment_errors_are_one_line_exit_1(capsys, tmp_path, monkeypatch):
    import errno

    import graphvision.execution.folders as report

    def full(*args, **kwargs):
        raise OSError(errno.ENOSPC, "No space left on device", str(tmp_path / "out" / "x.png"))

    monkeypatch.setattr(report, "write_run", full)
    status, _, err = cli(capsys, "run", DEMO, "--no-cache", "-o", PSNR_OUT, "-d", tmp_path / "out")
    assert status == 1
    assert err.strip().endswith(f"error: No space left on device: {tmp_path / 'out' / 'x.png'}")


def test_a_closed_pipe_ends_quietly():
    command = f"{sys.executable} -m graphvision nodes | head -1"
    done = subprocess.run(command, shell=True, capture_output=True, text=True, timeout=60)
    assert done.returncode == 0 and done.stdout.strip()
    assert "Traceback" not in done.stderr and "BrokenPipe" not in done.stderr


def test_version_bare_usage_and_python_m(capsys):
    assert cli(capsys, "--version")[0] == 0
    status, _, err = cli(capsys)
    assert status == 2 and err.startswith("usage: graphvision") and "commands: run, sweep" in err
    done = subprocess.run(
        [sys.executable, "-m", "graphvision", "--version"], capture_output=True, text=True
    )
    assert done.returncode == 0 and done.stdout.startswith("graphvision ")


def test_every_option_has_help_and_node_summaries_are_plain_text(capsys):
    import argparse

    from graphvision.cli.parser import build_parser

    parser = build_parser()
    subparsers = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    for name, sub in [("graphvision", parser), *subparsers.choices.items()]:
        for action in sub._actions:
            if not isinstance(action, argparse._HelpAction | argparse._SubParsersAction):
                assert action.help, f"{name} {action.dest} has no help"
    status, out, _ = cli(capsys, "nodes")
    assert status == 0 and "``" not in out and ":math:" not in out and ":func:" not in out


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--workers", "100000"], "at most 256, got 100000"),
        (["-d", ""], "argument --output-dir/-d: is empty"),
        (["--executor", "dask", "--scheduler", "garbage"], "cannot reach the Dask scheduler at"),
    ],
)
def test_command_line_values_out_of_reach_are_usage_errors(capsys, extra, message):
    if "dask" in extra:
        pytest.importorskip("distributed")
    status, _, err = cli(capsys, "run", DEMO, "--no-cache", *extra)
    assert status == 2 and message in err, err
    assert len(err.strip().splitlines()) == 1


WARNING_PLUGIN = '''
import numpy as np
from graphvision import Float, node


@node("noisy.divide")
def divide(x: Float) -> Float:
    """x / 0 in numpy: a RuntimeWarning, and infinity.

    Parameters
    ----------
    x : the numerator
    """
    return float(np.float64(x) / np.float64(0.0) * 0.0)
'''


@pytest.mark.parametrize("executor", ["threads", "processes"])
def test_a_warning_inside_a_node_names_the_node(capsys, tmp_path, executor):
    plugin = tmp_path / "noisy.py"
    plugin.write_text(WARNING_PLUGIN)
    pipeline = tmp_path / "p.yaml"
    pipeline.write_text(
        "name: p\ninputs:\n  x: {type: Float, default: 1.0}\n"
        "nodes:\n  d: {op: noisy.divide, in: {x: x}}\noutputs: {d: d}\n"
    )
    command = [sys.executable, "-m", "graphvision", "run", str(pipeline), "--plugins", str(plugin)]
    done = subprocess.run(
        [*command, "--no-cache", "--executor", executor], capture_output=True, text=True
    )
    assert "warning: noisy.divide: divide by zero encountered" in done.stderr, done.stderr
    assert "RuntimeWarning" not in done.stderr and ".py:" not in done.stderr


@pytest.mark.parametrize("command", ["run", "sweep"])
def test_overrides_naming_nothing_and_values_refused_are_named_at_once(capsys, tmp_path, command):
    flag = "-s" if command == "run" else "--grid"
    given = ["gauss_on_gaus.sigma=2", "gauss_on_gauss.sigma=-1", "params.sed=2"]
    args = [part for value in given for part in (flag, value)]
    status, _, err = cli(capsys, command, DEMO, "-d", tmp_path / "out", "--no-cache", *args)
    shown = "--set" if command == "run" else "--grid"
    assert status == 2 and "3 overrides are refused:" in err, err
    assert f"  - {shown} gauss_on_gaus.sigma=" in err and "no node 'gauss_on_gaus'" in err
    assert f"  - {shown} gauss_on_gauss.sigma=-1: invalid value -1 for parameter 'sigma'" in err
    assert f"  - {shown} params.sed=" in err and "the pipeline has no param 'sed'" in err
    assert not (tmp_path / "out").exists()


GAUSS_AND_MEDIAN = """version: 1
name: two
inputs:
  image: {type: Image, default: "sample:camera"}
params:
  s: 1.0
nodes:
  gray: {op: colour.to_gray, in: {image: image}}
  blur: {op: filters.gaussian, in: {image: gray}, params: {sigma: "${params.s}"}}
  med: {op: filters.median, in: {image: gray}, params: {size: "${params.s}"}}
outputs: {b: blur, m: med}
"""


@pytest.mark.parametrize(
    ("args", "headline", "lines"),
    [
        (["-s", "params.s=-1"], "1 override is refused (2 problems):", 2),
        (["--grid", "blur.sigma=-1,-2"], "1 override is refused (2 problems):", 2),
        (["-s", "params.s=-1", "-s", "gray.x=1"], "2 overrides are refused (3 problems):", 3),
        (["-s", "blur.sigma=-1", "-s", "med.size=0"], "2 overrides are refused:", 2),
    ],
)
def test_the_headline_counts_the_overrides_and_the_problems_listed(
    capsys, tmp_path, args, headline, lines
):
    """One value two nodes refuse (params.s is blur.sigma and med.size), or a --grid's two
    refused values: the headline said '1 override is refused:' above two lines."""
    pipeline = tmp_path / "two.yaml"
    pipeline.write_text(GAUSS_AND_MEDIAN)
    command = "sweep" if args[0] == "--grid" else "run"
    status, _, err = cli(capsys, command, pipeline, "-d", tmp_path / "out", "--no-cache", *args)
    assert status == 2 and f"error: {headline}\n" in err, err
    assert err.count("\n  - ") == lines, err


def test_a_refused_value_inside_a_parameter_is_named_with_the_others(capsys, tmp_path):
    coins = PIPELINES / "coins.yaml"
    args = ["-s", "coins.ranges={area: [400]}", "-s", "disk.size=4x"]
    status, _, err = cli(capsys, "run", coins, "-d", tmp_path / "out", "--no-cache", *args)
    assert status == 2 and "2 overrides are refused:" in err, err
    assert "parameter 'ranges.area' of regions.filter: List should have at least 2 items" in err
    assert "invalid value '4x' for parameter 'size' of morphology.footprint" in err


def test_a_pipeline_param_value_its_node_refuses_is_named_with_the_others(capsys, tmp_path):
    """coins.yaml's binary.window is "${params.window}": a value threshold.local refuses is
    named at once, beside another refused override, with the node parameter it stands for."""
    coins = PIPELINES / "coins.yaml"
    args = ["-s", "params.window=abc", "-s", "binary.k=xyz"]
    status, _, err = cli(capsys, "run", coins, "-d", tmp_path / "out", "--no-cache", *args)
    assert status == 2 and "2 overrides are refused:" in err, err
    assert (
        "--set params.window='abc': invalid value 'abc' for parameter 'window' of "
        "threshold.local" in err
    )
    assert "(as binary.window)" in err
    assert "--set binary.k='xyz': invalid value 'xyz'" in err
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("command", ["run", "sweep"])
def test_a_value_that_is_no_yaml_is_named_with_the_other_refused_overrides(
    capsys, tmp_path, command
):
    coins = PIPELINES / "coins.yaml"
    flag, shown = ("-s", "--set") if command == "run" else ("--grid", "--grid")
    args = [flag, "disk.size=[1", flag, "binary.k=xyz"]
    status, _, err = cli(capsys, command, coins, "-d", tmp_path / "out", "--no-cache", *args)
    assert status == 2 and "2 overrides are refused:" in err, err
    assert f"  - {shown} disk.size=" in err and "malformed YAML" in err
    assert f"  - {shown} binary.k='xyz': invalid value 'xyz'" in err
    assert not (tmp_path / "out").exists()


def test_a_sweeps_refused_set_and_grid_overrides_are_named_in_one_message(capsys, tmp_path):
    coins = PIPELINES / "coins.yaml"
    args = ["--grid", "params.window=31,abc", "-s", "disk.size=[1"]
    status, _, err = cli(capsys, "sweep", coins, "-d", tmp_path / "out", "--no-cache", *args)
    assert status == 2 and "2 overrides are refused:" in err, err
    assert "  - --set disk.size=[1: malformed YAML" in err
    assert "  - --grid params.window='abc': invalid value 'abc'" in err
    assert "(as binary.window)" in err
    assert not (tmp_path / "out").exists()


def test_a_pipeline_param_two_nodes_refuse_alike_is_one_line_and_one_override(capsys, tmp_path):
    """params.size stands for two footprints' size: one line names both, counted once."""
    text = (PIPELINES / "coins.yaml").read_text()
    assert "params:\n  window: 51\n" in text
    text = text.replace("params:\n  window: 51\n", "params:\n  window: 51\n  size: 5\n")
    text = text.replace(
        "disk:      {op: morphology.footprint, params: {shape: disk, size: 5}}",
        'disk:      {op: morphology.footprint, params: {shape: disk, size: "${params.size}"}}\n'
        '  disk2:     {op: morphology.footprint, params: {shape: disk, size: "${params.size}"}}',
    )
    assert text.count("${params.size}") == 2
    pipeline = tmp_path / "coins.yaml"
    pipeline.write_text(text)
    args = ["-s", "params.size=abc", "-s", "binary.k=zz"]
    status, _, err = cli(capsys, "run", pipeline, "-d", tmp_path / "out", "--no-cache", *args)
    assert status == 2 and "2 overrides are refused:" in err, err
    assert "of morphology.footprint: Input should be a valid integer" in err
    assert "(as disk.size, disk2.size)" in err
    assert err.count("params.size=") == 1


@pytest.mark.parametrize(
    "args",
    [
        ["-s", "binary.window=31", "--grid", "params.window=abc,xyz"],
        ["--grid", "binary.window=31,41", "-s", "params.window=abc"],
    ],
    ids=["set-node-grid-param", "grid-node-set-param"],
)
def test_a_sweeps_pipeline_param_is_not_checked_where_its_other_flag_sets_the_node(
    capsys, tmp_path, args
):
    """binary.window is "${params.window}": with binary.window set by the other flag, the
    param's value reaches no node, as `run -s binary.window=31 -s params.window=abc` accepts;
    a sweep refused it (found by the tryer)."""
    coins = PIPELINES / "coins.yaml"
    status, _, err = cli(capsys, "sweep", coins, "-d", tmp_path / "out", "--no-cache", *args)
    assert status == 0, err
    assert "refused" not in err
