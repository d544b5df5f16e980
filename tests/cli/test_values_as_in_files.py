"""A value means the same on the command line (``-s``, ``--grid``) as in a pipeline file:
both are read by the same YAML 1.1 reader (``010`` is 8, ``yes`` is True), as the CLI
reference says."""

from __future__ import annotations

import datetime

import pytest

import graphvision as gv
from graphvision.cli.common import yaml_value
from graphvision.cli.sweep import _listed

TEXTS = {  # YAML 1.1 as PyYAML reads it: the values written down, not read back
    "010": 8,
    "0x1F": 31,
    "12:30": 750,
    "yes": True,
    "on": True,
    "NO": False,
    "~": None,
    "1_000": 1000,
    "1e3": "1e3",  # (YAML 1.1 floats need a dot and a signed exponent)
    "1.0e3": "1.0e3",
    "1.0e+3": 1000.0,
    "2001-12-14": datetime.date(2001, 12, 14),
    '"010"': "010",
}


@pytest.mark.parametrize(("text", "meant"), TEXTS.items())
def test_a_value_reads_the_same_in_a_file_with_set_and_with_grid(tmp_path, text, meant):
    pipeline = tmp_path / "p.yaml"
    pipeline.write_text(
        f"version: 1\nname: p\nparams:\n  v: {text}\n"
        "nodes:\n  z: {op: pyramids.zone_plate}\noutputs:\n  z: z\n"
    )
    in_file = gv.load_pipeline(pipeline).params["v"]
    assert in_file == meant and type(in_file) is type(meant)
    on_line = yaml_value(text, f"--set params.v={text}")
    assert on_line == meant and type(on_line) is type(meant)
    assert _listed("params.v", f"{text},{text}") == [meant, meant]
