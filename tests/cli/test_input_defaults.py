"""An input's default is loaded by ``validate`` as ``run`` loads it, and a default that does
not load is named at its line by both (and by ``gv.run``): a tryer's ``sample:camra``
validated, and ``run`` refused it without its file and line."""

from __future__ import annotations

from pathlib import Path

import pytest

import graphvision as gv
from graphvision.cli import main

PIPELINE = """name: small
inputs:
  image:
    type: Image
    default: {default}
nodes:
  gray: {{op: colour.to_gray, in: {{image: image}}}}
outputs: {{gray: gray}}
"""


def _pipeline(folder: Path, default: str) -> Path:
    path = folder / "p.yaml"
    path.write_text(PIPELINE.format(default=default))
    return path


@pytest.mark.parametrize(
    ("default", "reason"),
    [
        (
            "sample:camra",
            "cannot load 'sample:camra': unknown sample image 'camra' (did you mean 'camera'?); "
            "samples: ",
        ),
        ("missing.png", "no such file: missing.png"),
    ],
)
def test_validate_refuses_a_default_that_does_not_load_at_its_line(
    tmp_path, capsys, default, reason
):
    path = _pipeline(tmp_path, default)
    status = main(["validate", str(path)])
    err = capsys.readouterr().err
    assert status == 2, err
    assert f"  - inputs.image.default at {path}:5: {reason}" in err


def test_run_names_the_default_and_its_line(tmp_path, capsys):
    path = _pipeline(tmp_path, "sample:camra")
    status = main(["run", str(path), "--no-cache", "--output-dir", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert status == 2, err
    assert err.startswith(
        f"error: inputs.image.default at {path}:5: cannot load 'sample:camra': unknown sample "
        "image 'camra' (did you mean 'camera'?); samples: astronaut,"
    )
    assert not (tmp_path / "out").exists()


def test_a_value_given_for_the_input_is_named_as_given(tmp_path, capsys):
    path = _pipeline(tmp_path, "sample:camera")
    status = main(["run", str(path), "--no-cache", "-i", "image=sample:camra"])
    assert capsys.readouterr().err.startswith("error: input 'image': cannot load 'sample:camra'")
    assert status == 2


def test_python_run_names_the_default_at_the_line_that_declared_it():
    graph = gv.Graph("small")
    image = graph.input("image", "Image", default="sample:camra")  # the line named
    graph.output("gray", graph.add("gray", "colour.to_gray", image=image))
    line = test_python_run_names_the_default_at_the_line_that_declared_it.__code__.co_firstlineno
    with pytest.raises(gv.InputError, match=rf"^inputs\.image\.default at {__file__}:{line + 2} "):
        gv.run(graph, cache=None)


def test_good_defaults_validate(tmp_path, capsys):
    assert main(["validate", str(_pipeline(tmp_path, "sample:camera"))]) == 0
    assert capsys.readouterr().out.endswith(": ok\n")


TWO = """name: two
inputs:
  image: {type: Image}
  other: {type: Image, default: "sample:camra"}
nodes:
  a: {op: colour.to_gray, in: {image: image}}
  b: {op: colour.to_gray, in: {image: other}}
outputs: {a: a, b: b}
"""


def test_a_batch_refuses_a_default_its_outputs_read_before_any_file(tmp_path, capsys):
    """Each file failed alike, naming the default; the batch now stops before it starts."""
    (tmp_path / "p.yaml").write_text(TWO)
    (tmp_path / "in").mkdir()
    (tmp_path / "in" / "x.png").write_bytes(b"not read")
    out = tmp_path / "out"
    batch = ["--batch", f"image={tmp_path}/in/*.png", "-d", str(out), "--no-cache"]
    assert main(["run", str(tmp_path / "p.yaml"), *batch]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"error: inputs.other.default at {tmp_path / 'p.yaml'}:4: cannot load")
    assert not out.exists()
    assert main(["run", str(tmp_path / "p.yaml"), *batch, "-o", "a"]) == 1  # b is not read
    assert "inputs.other" not in capsys.readouterr().err


def test_a_relative_default_missing_names_the_working_folder_it_was_looked_for_from(
    tmp_path, capsys, monkeypatch
):
    """A default's path is read from the working folder (pipeline-files.md), where plugins
    are read beside the pipeline: the message said only 'no such file: missing.png'."""
    path = _pipeline(tmp_path, "missing.png")
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    monkeypatch.chdir(elsewhere)
    assert main(["validate", str(path)]) == 2
    assert (
        f"  - inputs.image.default at {path}:5: no such file: missing.png (looked for from the "
        f"working folder {elsewhere})\n"
    ) in capsys.readouterr().err


def test_validate_takes_a_value_for_an_input_in_place_of_its_default(tmp_path, capsys):
    """``validate -i`` stands in for an input without a default (a placeholder), read by the
    same parsing as ``run -i``; it had no such option (a usage error)."""
    (tmp_path / "p.yaml").write_text(TWO)
    path = tmp_path / "p.yaml"
    given = ["-i", "image=sample:camera", "-i", "other=sample:coins"]
    assert main(["validate", str(path), *given]) == 0
    assert capsys.readouterr().out == f"{path}: ok\n"
    assert main(["validate", str(path), "-i", "image=sample:camra", "-i", "imgae=x"]) == 2
    err = capsys.readouterr().err
    assert "  - --input image=sample:camra: cannot load 'sample:camra': unknown sample" in err
    assert (
        "  - --input imgae=x: unknown input (did you mean 'image'?); inputs: image, other\n" in err
    )
    assert f"  - inputs.other.default at {path}:4: cannot load 'sample:camra'" in err  # not given


@pytest.mark.parametrize("given", ["image", "=x"])
def test_validate_reads_its_inputs_as_run_does(tmp_path, capsys, given):
    path = _pipeline(tmp_path, "sample:camera")
    assert main(["validate", str(path), "-i", given]) == main(["run", str(path), "-i", given]) == 2
    expected = f"error: --input expects NAME=VALUE, got '{given}'\n"
    assert capsys.readouterr().err == expected * 2
