"""``--backend``: its names are checked against every installed plugin's backends (from
the plugin index, without importing them), and its mistakes are the command line's."""

from __future__ import annotations

import textwrap
from pathlib import Path

import pytest

import graphvision as gv
from graphvision.cli.main import main

PIPELINES = Path(__file__).parents[2] / "pipelines"


@pytest.fixture
def indexed() -> None:
    """A plugin index in this test's cache folder (a first discovery writes it), so a run
    loads only the plugins its ops and backends need, as the command line does."""
    gv.discover()
    assert "opencv" in gv.discover().backends()


def test_an_unknown_backend_lists_every_installed_one_and_blames_the_option(
    indexed: None, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["run", str(PIPELINES / "coins.yaml"), "--backend", "cuda", "--no-cache"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: --backend cuda: unknown backend 'cuda'; backends: numpy, opencv")
    assert "coins.yaml" not in err
    sweep = ["sweep", str(PIPELINES / "coins.yaml"), "--grid", "binary.window=[11]"]
    options = ["--backend", "opencv,bogus", "--no-cache", "-d", str(tmp_path / "s")]
    assert main(sweep + options) == 2
    assert "error: --backend opencv,bogus: unknown backend 'bogus'" in capsys.readouterr().err


def test_a_backend_implementing_none_of_the_ops_is_known_and_runs_the_reference(
    indexed: None, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "p.yaml"
    path.write_text(
        textwrap.dedent(
            """\
            name: p
            nodes:
              camera: {op: camera.pinhole, params: {fx: 500.0}}
            outputs:
              camera: camera
            """
        )
    )
    assert main(["run", str(path), "--backend", "opencv", "--no-cache", "--record"]) == 0
    assert " numpy " in capsys.readouterr().out  # camera.pinhole has no opencv implementation


def test_a_pipeline_files_unknown_backend_is_its_lines(
    indexed: None, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    text = (PIPELINES / "coins.yaml").read_text().replace("\nnodes:", "\nbackends: [cuda]\nnodes:")
    path = tmp_path / "coins.yaml"
    path.write_text(text)
    line = text.splitlines().index("backends: [cuda]") + 1
    assert main(["run", str(path), "--no-cache"]) == 2
    err = capsys.readouterr().err
    assert f"coins.yaml:{line}: unknown backend 'cuda'; backends: numpy, opencv" in err


def test_a_node_pinned_to_a_misspelt_backend_lists_the_ops_installed_ones(
    indexed: None, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The list named only the backends whose plugins the run had loaded ('numpy')."""
    text = (PIPELINES / "coins.yaml").read_text()
    assert "op: colour.to_gray" in text
    path = tmp_path / "pinned.yaml"
    path.write_text(text.replace("op: colour.to_gray", "op: colour.to_gray, backend: OpenCV"))
    assert main(["run", str(path), "--no-cache"]) == 2
    err = capsys.readouterr().err
    assert (
        "colour.to_gray has no 'OpenCV' implementation (did you mean 'opencv'?); "
        "backends: numpy, opencv"
    ) in err  # a backend's name is lower case: its case is no typo to miss
