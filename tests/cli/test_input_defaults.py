"""An input's default is loaded by ``validate`` as ``run`` loads it, and a default that does
not load is named at its line by both (and by ``gv.run``): a tryer's ``sample:camra``
validated, and ``run`` refused it without its file and line."""

from __future__ import annotations

from pathlib import Path

import pytest

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


def test_good_defaults_validate(tmp_path, capsys):
    assert main(["validate", str(_pipeline(tmp_path, "sample:camera"))]) == 0
    assert capsys.readouterr().out.endswith(": ok\n")
