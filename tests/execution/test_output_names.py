"""Output names cannot leave the output folder (issue 29 A): every name that is not a
plain identifier is refused at validation with file and line, by the Python builder
when it is declared, and nothing is ever written through a symlink in the folder."""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np
import pytest

import graphvision as gv
from graphvision.cli import main
from graphvision.errors import OutputFolderError
from graphvision.execution.folders import write_outputs

from ..conftest import PIPELINES

DEMO = PIPELINES / "denoise.yaml"
OUTPUT = "psnr_noisy_gaussian"

ESCAPING = [
    "../../escaped",
    "../escaped",
    "..",
    "/tmp/graphvision-escaped",
    "sub/escaped",
    "sub\\escaped",
    "escaped.png",
    "-rf",
    " spaced",
]


def pipeline_with_output(tmp_path: Path, name: str) -> tuple[Path, int]:
    """The demo pipeline with one output renamed to ``name``; returns it and that line."""
    lines = DEMO.read_text().splitlines()
    index = next(i for i, line in enumerate(lines) if line.strip().startswith(f"{OUTPUT}:"))
    indent = lines[index][: len(lines[index]) - len(lines[index].lstrip())]
    lines[index] = f"{indent}{json.dumps(name)}: {lines[index].split(':', 1)[1].strip()}"
    path = tmp_path / "hostile" / "p.yaml"
    path.parent.mkdir()
    path.write_text("\n".join(lines) + "\n")
    return path, index + 1


def files_under(root: Path) -> set[Path]:
    return {p for p in root.rglob("*")}


@pytest.mark.parametrize("name", ESCAPING)
def test_an_output_name_that_is_not_plain_is_refused_with_file_and_line(capsys, tmp_path, name):
    pipeline, line = pipeline_with_output(tmp_path, name)
    before = files_under(tmp_path)
    for command in (["validate", pipeline], ["run", pipeline, "-d", tmp_path / "run" / "out"]):
        status = main([str(a) for a in command])
        err = capsys.readouterr().err
        assert status == 2, err
        assert f"{pipeline}:{line}" in err
        assert "must be a plain name" in err and "Traceback" not in err
    assert files_under(tmp_path) == before  # nothing written, inside the folder or outside
    assert not Path("/tmp/graphvision-escaped.json").exists()


@pytest.mark.parametrize("name", ESCAPING)
def test_the_python_builder_refuses_the_same_names(name):
    graph = gv.Graph("g")
    graph.input("image", "GrayImage")
    with pytest.raises(ValueError, match="must be a plain name"):
        graph.output(name, "image")


def test_a_graph_whose_outputs_were_edited_directly_is_refused_when_compiled(registry):
    graph = gv.Graph("g")
    graph.input("image", "GrayImage")
    graph.outputs["../escaped"] = gv.Ref.parse("image")
    with pytest.raises(gv.PipelineError, match="must be a plain name"):
        gv.compile_graph(graph, registry)


def test_a_file_the_last_run_wrote_now_a_symlink_is_refused_never_written_through(capsys, tmp_path):
    """Replacing the link would lose it without a trace in history/ (it is not the file the
    run wrote): the run is refused, naming it, and neither the link nor its target changes."""
    out, victim = tmp_path / "out", tmp_path / "victim.json"
    victim.write_text("precious")
    assert main(["run", str(DEMO), "-d", str(out), "-o", OUTPUT]) == 0
    own = out / f"{OUTPUT}.json"
    own.unlink()
    own.symlink_to(victim)  # a file the last run wrote, now a link to someone else's file
    assert main(["run", str(DEMO), "-d", str(out), "-o", OUTPUT, "--no-cache"]) == 2
    assert f"{own} is a symbolic link to {victim}, where the previous run wrote a file" in (
        capsys.readouterr().err
    )
    assert victim.read_text() == "precious" and own.is_symlink()


def test_a_symlink_not_written_by_graphvision_is_refused_and_left_alone(capsys, tmp_path):
    out, victim = tmp_path / "out", tmp_path / "victim.json"
    out.mkdir()
    victim.write_text("precious")
    (out / f"{OUTPUT}.json").symlink_to(victim)
    status = main(["run", str(DEMO), "-d", str(out), "-o", OUTPUT])
    assert status == 2 and f"holds {OUTPUT}.json" in capsys.readouterr().err
    assert victim.read_text() == "precious" and (out / f"{OUTPUT}.json").is_symlink()


class _EscapingPort(gv.ArrayPort):
    """A port type whose writer ignores the stem it is given (a plugin's mistake)."""

    @classmethod
    def write(cls, value: np.ndarray, stem: Path) -> list[Path]:
        path = stem.parent.parent / "escaped.npy"
        np.save(path, value)
        return [path]


def test_a_port_type_that_writes_outside_its_stem_is_named(tmp_path, registry):
    graph = gv.Graph("g")
    graph.input("image", "GrayImage")
    graph.output("image", "image")
    compiled = gv.compile_graph(graph, registry)
    compiled.input_types["image"] = _EscapingPort  # as if the output were of that type
    staging = tmp_path / "staging"
    staging.mkdir()
    with pytest.raises(OutputFolderError, match="is not a plain file directly in"):
        write_outputs(compiled, {"image": np.zeros((2, 2), np.float32)}, staging)
    assert os.path.exists(tmp_path / "escaped.npy")  # the writer ran; the run refuses its file
