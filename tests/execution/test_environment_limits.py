"""A malformed limit in the environment (GRAPHVISION_MAX_PIXELS, _NODE_TIMEOUT, _NODE_MEMORY,
_MAX_MEMORY) is refused once, before any work, naming the variable and its value: the pixel
budget was read only when a file was, so `run` of a sample went through, `run` of a file
failed deep in the run and a batch failed file by file (found by an earlier adversary)."""

from __future__ import annotations

from pathlib import Path

import imageio.v3 as iio
import numpy as np
import pytest

import graphvision as gv
from graphvision.cli import main

from ..conftest import TOY

PIPELINE = """\
version: 1
name: dark
inputs:
  image: {type: GrayImage, default: "sample:camera"}
nodes:
  dark: {op: toy.darken, in: {image: image}, params: {factor: 0.5}}
outputs: {dark: dark}
"""

MALFORMED = [
    ("GRAPHVISION_MAX_PIXELS", "abc", "is not a whole number of pixels above 0"),
    ("GRAPHVISION_MAX_PIXELS", "-1", "is not a whole number of pixels above 0"),
    ("GRAPHVISION_MAX_PIXELS", "0", "is not a whole number of pixels above 0"),
    ("GRAPHVISION_NODE_TIMEOUT", "abc", "is not a positive number"),
    ("GRAPHVISION_NODE_MEMORY", "-5", "is not a positive number"),
    ("GRAPHVISION_MAX_MEMORY", "0", "is not a number of bytes above 0"),
]


def _files(tmp_path: Path) -> Path:
    for number in range(3):
        iio.imwrite(tmp_path / f"p{number}.png", np.full((6, 7), 40 * number, np.uint8))
    pipeline = tmp_path / "dark.yaml"
    pipeline.write_text(PIPELINE)
    return pipeline


def _command(kind: str, tmp_path: Path, pipeline: Path) -> list[str]:
    out = str(tmp_path / "out")
    rest = {
        "run": ["run", str(pipeline), "-d", out],
        "file": ["run", str(pipeline), "-i", f"image={tmp_path / 'p0.png'}", "-d", out],
        "batch": ["run", str(pipeline), "--batch", f"image={tmp_path}/*.png", "-d", out],
        "sweep": ["sweep", str(pipeline), "--grid", "dark.factor=0.5,0.25", "-d", out],
        "studio": ["studio", str(pipeline), "--no-browser", "--port", "0"],
    }[kind]
    return ["--plugins", str(TOY), *rest, "--no-cache"]


@pytest.mark.parametrize("kind", ["run", "file", "batch", "sweep", "studio"])
@pytest.mark.parametrize(("variable", "value", "reason"), MALFORMED)
def test_a_command_refuses_a_malformed_limit_before_any_work(
    capsys, monkeypatch, tmp_path, kind, variable, value, reason
):
    monkeypatch.setenv(variable, value)
    status = main(_command(kind, tmp_path, _files(tmp_path)))
    err = capsys.readouterr().err
    assert status == 2, err
    assert err == f"error: {variable}='{value}' {reason}" + err.partition(reason)[2]
    assert err.count("\n") == 1  # once, not once a file
    assert not (tmp_path / "out").exists()  # nothing ran, no folder made


def test_max_pixels_on_the_command_line_supersedes_the_variable(capsys, monkeypatch, tmp_path):
    monkeypatch.setenv("GRAPHVISION_MAX_PIXELS", "abc")
    args = [*_command("file", tmp_path, _files(tmp_path)), "--max-pixels", "1e3"]
    assert main(args) == 0, capsys.readouterr().err


@pytest.mark.parametrize(("variable", "value", "reason"), MALFORMED)
def test_the_python_api_refuses_a_malformed_limit_before_any_work(
    registry, monkeypatch, tmp_path, variable, value, reason
):
    graph = gv.load_pipeline(_files(tmp_path))
    ran = []
    monkeypatch.setattr(
        "graphvision.execution.run._compiled", lambda *a: ran.append(a) or pytest.fail("ran")
    )
    monkeypatch.setenv(variable, value)
    with pytest.raises(gv.InputError, match=f"^{variable}='{value}' {reason}"):
        gv.run(graph, registry, cache=None)  # a sample: no file read, the budget was never
    with pytest.raises(gv.InputError, match=f"^{variable}='{value}' {reason}"):
        gv.run_batch(graph, str(tmp_path / "*.png"), input="image", output_dir=tmp_path / "o")
    assert not (tmp_path / "o").exists() and not ran


def test_a_limit_given_to_gv_run_supersedes_its_variable(registry, monkeypatch, tmp_path):
    graph = gv.load_pipeline(_files(tmp_path))
    monkeypatch.setenv("GRAPHVISION_MAX_PIXELS", "abc")
    monkeypatch.setenv("GRAPHVISION_MAX_MEMORY", "-1")
    result = gv.run(graph, registry, inputs={"image": str(tmp_path / "p1.png")}, cache=None,
                    max_pixels=1000, max_memory=2**30)  # fmt: skip
    assert result.outputs["dark"][0, 0] == pytest.approx(40 / 255 * 0.5)


def test_the_variable_takes_what_max_pixels_takes(monkeypatch):
    for text, budget in (("1e9", 10**9), ("1_000_000", 10**6), ("250", 250)):
        monkeypatch.setenv("GRAPHVISION_MAX_PIXELS", text)
        assert gv.max_pixels() == budget
