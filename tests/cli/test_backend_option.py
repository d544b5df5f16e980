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
    assert "opencv" in gv.discover().backends()  # one discovery writes the index


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


def _camera_pipeline(tmp_path: Path, order: str = "") -> Path:
    """A one-node pipeline (nothing to compute worth the name), with ``order`` as its
    ``backends:`` line."""
    path = tmp_path / "p.yaml"
    path.write_text(
        f"name: p\n{order}\nnodes:\n  camera: {{op: camera.pinhole, params: {{fx: 500.0}}}}\n"
        "outputs:\n  camera: camera\n"
    )
    return path


@pytest.mark.parametrize(
    ("given", "shown", "entry"), [("", "''", "1 of 1"), ("opencv,", "'opencv,'", "2 of 2"),
                                  ("numpy, ,opencv", "'numpy,,opencv'", "2 of 3")]
)  # fmt: skip
def test_an_empty_backend_entry_is_a_usage_error_naming_it(
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    given: str,
    shown: str,
    entry: str,
) -> None:
    """`--backend ''` ran the file's order, and `--backend opencv,` opencv, without a word
    (refused before any plugin is looked for)."""
    path = _camera_pipeline(tmp_path)
    assert main(["run", str(path), "--backend", given, "--no-cache"]) == 2
    assert capsys.readouterr().err.startswith(
        f"error: --backend: the backend order {shown} has an empty entry ({entry}): "
        "name each backend once, separated by commas"
    )
    with pytest.raises(ValueError, match=r"has an empty entry \(2 of 2\)"):
        gv.run(path, backends="opencv,", executor="sync")


@pytest.mark.parametrize("given", ["opencv,", ["opencv", " "]])
def test_an_empty_backend_entry_is_refused_on_every_python_path(tmp_path: Path, given) -> None:
    """`Graph.with_backends` dropped an empty entry without a word, and batches and sweeps
    go through it (only `gv.run` and the option were checked)."""
    path = _camera_pipeline(tmp_path)
    graph = gv.load_pipeline(path)
    with pytest.raises(ValueError, match=r"has an empty entry \(2 of 2\)"):
        graph.with_backends(given)
    with pytest.raises(ValueError, match=r"has an empty entry \(2 of 2\)"):
        gv.sweep(path, {"camera.fx": [400.0, 500.0]}, backends=given, executor="sync")


def test_a_backend_named_twice_is_refused_on_the_option_and_at_the_files_line(
    indexed: None, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = _camera_pipeline(tmp_path)
    assert main(["run", str(path), "--backend", "opencv,numpy,opencv", "--no-cache"]) == 2
    assert capsys.readouterr().err.startswith(
        "error: --backend opencv,numpy,opencv: backend 'opencv' is named 2 times in the order"
    )
    listed = _camera_pipeline(tmp_path, "backends: [opencv, opencv]")
    assert main(["validate", str(listed)]) == 2
    assert "p.yaml:2: backend 'opencv' is named 2 times" in capsys.readouterr().err


def test_a_backend_in_capitals_is_told_its_lower_case_name(
    indexed: None, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = _camera_pipeline(tmp_path)
    assert main(["run", str(path), "--backend", "OpenCV", "--no-cache"]) == 2
    assert (
        "error: --backend OpenCV: unknown backend 'OpenCV' (did you mean 'opencv'?)"
        in capsys.readouterr().err
    )


def test_validate_refuses_a_value_of_a_backend_it_does_not_import_from_the_index(
    indexed: None, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """`validate` (and `run`) import only the plugins a pipeline's ops and backends need:
    without --backend opencv, method: magsac was let through to fail at run time."""
    from graphvision.nodes.plugins import Needs

    text = (PIPELINES / "homography.yaml").read_text()
    fit = "params: {threshold: 3.0, seed: 0}"
    assert fit in text
    path = tmp_path / "homography.yaml"
    path.write_text(text.replace(fit, "params: {threshold: 3.0, seed: 0, method: magsac}"))
    line = next(n for n, t in enumerate(path.read_text().splitlines(), 1) if "  fit:" in t)
    needs = Needs.of(gv.load_pipeline(path))
    assert "opencv" not in gv.discover(needs=needs).plugins  # the check is the index's
    assert main(["validate", str(path)]) == 2
    err = capsys.readouterr().err
    assert f"homography.yaml:{line}: method: 'magsac' of geometry.homography_ransac" in err
    assert "implemented by the 'opencv' backend alone, not by 'numpy'" in err
    assert "pip install 'graphvision[opencv]'" in err
