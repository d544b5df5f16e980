"""``graphvision run -d DIR`` prints the pipeline's scalar outputs (issue 29, item 10), the
lines a run without ``-d`` prints for them; pictures and arrays stay in their files."""

from __future__ import annotations

import numpy as np

from graphvision.cli import main

from ..conftest import TOY, write

PIPELINE = """name: figures
inputs:
  image: {type: GrayImage}
  flag: {type: Bool, default: true}
  label: {type: Text, default: "tile 3"}
nodes:
  total: {op: toy.const, params: {value: 2.5}}
  pixels: {op: toy.count, in: {image: image}}
  dark: {op: toy.darken, in: {image: image}}
outputs:
  total: total
  pixels: pixels
  dark: dark
  flag: flag
  label: label
"""


def run(capsys, *args) -> tuple[int, str, str]:
    status = main(["--plugins", str(TOY), "run", *map(str, args), "--no-cache", "--no-progress"])
    out, err = capsys.readouterr()
    return status, out, err


def test_a_run_into_a_folder_prints_every_scalar_output_as_a_run_without_one(capsys, tmp_path):
    pipeline = write(tmp_path, "figures.yaml", PIPELINE)
    image = tmp_path / "image.npy"
    np.save(image, np.full((6, 7), 0.5, np.float32))
    status, printed, _ = run(capsys, pipeline, "-i", f"image={image}")
    assert status == 0
    status, out, err = run(capsys, pipeline, "-i", f"image={image}", "-d", tmp_path / "out")
    assert status == 0 and "wrote 5 output(s)" in err
    scalars = [line for line in printed.splitlines() if not line.startswith("dark:")]
    assert out.splitlines() == scalars
    assert out.splitlines() == [
        "total: Float 2.5",
        "pixels: Int 42",
        "flag: Bool True",
        "label: Text 'tile 3'",
    ]
