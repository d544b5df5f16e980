"""A graph input whose source's scheme is mistyped (``samples:camera`` for
``sample:camera``) is refused with the scheme meant: it was read as a file's name and
refused as ``no such file: samples:camera``, no hint."""

from __future__ import annotations

import pytest

import graphvision as gv
from graphvision.cli import main

PIPELINE = """name: small
inputs:
  image: {type: Image, default: "%s"}
nodes:
  gray: {op: colour.to_gray, in: {image: image}}
outputs: {gray: gray}
"""


@pytest.mark.parametrize(
    ("given", "meant"),
    [
        ("samples:camera", "sample:camera"),
        ("smaple:camera", "sample:camera"),
        ("Sample:coins", "sample:coins"),
        ("SAMPLE:coins", "sample:coins"),  # (no hint: compared case by case; TRY45b)
        ("fil:x.png", "file:x.png"),
    ],
)
def test_a_mistyped_scheme_is_named_with_the_one_meant(tmp_path, capsys, monkeypatch, given, meant):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "p.yaml").write_text(PIPELINE % "sample:camera")
    assert main(["run", "p.yaml", "--no-cache", "-i", f"image={given}"]) == 2
    assert capsys.readouterr().err == (
        f"error: input 'image': no such file: {given} (looked for from the working folder "
        f"{tmp_path}) (did you mean '{meant}'?)\n"
    )
    (tmp_path / "q.yaml").write_text(PIPELINE % given)  # a default, in `validate`
    assert main(["validate", "q.yaml"]) == 2
    assert f"q.yaml:3: no such file: {given} " in capsys.readouterr().err
    graph = gv.load_pipeline(tmp_path / "p.yaml")
    with pytest.raises(gv.InputError, match=rf"\(did you mean '{meant}'\?\)$"):
        gv.run(graph, inputs={"image": given}, cache=None)


@pytest.mark.parametrize("given", ["missing.png", "c:missing.png", "sample:camra", "a:b:c"])
def test_no_hint_where_no_scheme_is_near(tmp_path, capsys, monkeypatch, given):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "p.yaml").write_text(PIPELINE % "sample:camera")
    assert main(["run", "p.yaml", "--no-cache", "-i", f"image={given}"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: input 'image': ")
    assert "(did you mean '" not in err.replace("(did you mean 'camera'?)", "")


def test_a_file_whose_name_looks_like_a_mistyped_scheme_is_read(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "p.yaml").write_text(PIPELINE % "sample:camera")
    assert main(["run", "p.yaml", "--no-cache", "-i", "image=sample:camera", "-d", "a"]) == 0
    (tmp_path / "a" / "gray.png").rename(tmp_path / "samples:camera")
    assert main(["run", "p.yaml", "--no-cache", "-i", "image=samples:camera"]) == 0


@pytest.mark.parametrize(
    ("pattern", "hint"),
    [
        ("smaple:camera", "did you mean 'sample:camera'?"),
        ("file:imgs/*.png",
         "a batch's pattern names files, without a source's scheme: did you mean 'imgs/*.png'?"),
        # it suggested 'camera', which matches no file either (found by NU45)
        ("sample:camera",
         "a batch runs over files; 'sample:camera' is one value: give it with -i, or inputs="),
    ],
)  # fmt: skip
def test_a_batch_pattern_with_a_scheme_says_what_was_meant(
    tmp_path, capsys, monkeypatch, pattern, hint
):
    """A batch said only 'no file matches', where -i hinted (found by TRY45b)."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "p.yaml").write_text(PIPELINE % "sample:camera")
    assert main(["run", "p.yaml", "--no-cache", "-d", "out", "--batch", f"image={pattern}"]) == 2
    assert capsys.readouterr().err == (
        f"error: --batch image={pattern}: batch input 'image': no file matches '{pattern}' "
        f"({hint})\n"
    )
    assert not (tmp_path / "out").exists()
