"""Outputs that need ground truth (issue 29 item 9): an input marked ``truth_of`` goes
with the inputs it names; given those without it, the outputs that read it are skipped
with one line saying why, the others run; asked for by name, they are refused (exit 2)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import graphvision as gv
from graphvision.cli import main

from ..conftest import PIPELINES

PIPELINE = """version: 1
name: truth
inputs:
  image: {type: GrayImage, default: "sample:camera"}
  truth:
    type: GrayImage
    default: "sample:camera"
    truth_of: [image]
nodes:
  blur:  {op: filters.gaussian, in: {image: image}, params: {sigma: 1.0}}
  error: {op: metrics.mse, in: {a: blur, b: truth}}
  mean:  {op: filters.gaussian, in: {image: truth}, params: {sigma: 2.0}}
outputs:
  blur: blur
  error: error
  truth_blur: mean
"""


@pytest.fixture
def graph(tmp_path):
    (tmp_path / "p.yaml").write_text(PIPELINE)
    return gv.load_pipeline(tmp_path / "p.yaml")


def _image(seed: int) -> np.ndarray:
    return np.random.default_rng(seed).random((24, 32)).astype(np.float32)


def test_given_images_without_their_truth_skip_what_reads_it_with_one_line(graph):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = gv.run(graph, inputs={"image": _image(0)}, cache=None)
    assert set(result.outputs) == {"blur"}  # error and truth_blur read the truth
    [warning] = [w for w in caught if issubclass(w.category, gv.MissingTruthWarning)]
    assert str(warning.message) == (
        "skipped outputs error, truth_blur: they need the ground truth 'truth': its default "
        "goes with the default image only, and it was given; give input truth "
        "(--input truth=FILE) to compute them"
    )


def test_with_their_truth_or_all_defaults_every_output_runs(graph):
    image, truth = _image(0), _image(1)
    result = gv.run(graph, inputs={"image": image, "truth": truth}, cache=None)
    assert set(result.outputs) == {"blur", "error", "truth_blur"}
    expected = np.mean((result.outputs["blur"].astype(np.float64) - truth) ** 2)
    assert result.outputs["error"] == pytest.approx(expected, rel=1e-5)
    with warnings.catch_warnings():
        warnings.simplefilter("error", gv.MissingTruthWarning)
        assert set(gv.run(graph, cache=None).outputs) == {"blur", "error", "truth_blur"}


def test_an_output_asked_for_without_its_truth_is_refused_before_the_run(graph):
    with pytest.raises(gv.InputError, match=r"output error needs the ground truth 'truth'"):
        gv.run(graph, inputs={"image": _image(0)}, outputs=["error"], cache=None)
    assert gv.run(graph, inputs={"image": _image(0)}, outputs=["blur"], cache=None).outputs


def test_truth_of_names_other_inputs_and_survives_a_round_trip(tmp_path, graph):
    again = gv.parse_pipeline(gv.dump_pipeline(graph), "again.yaml")
    assert again.inputs["truth"].truth_of == ["image"]
    (tmp_path / "bad.yaml").write_text(PIPELINE.replace("truth_of: [image]", "truth_of: [imag]"))
    with pytest.raises(
        gv.PipelineError,
        match=r"truth_of at .*bad.yaml:8: 'imag' is not another input .*did you mean 'image'",
    ):
        gv.compile_graph(gv.load_pipeline(tmp_path / "bad.yaml"), gv.discover())


def test_the_command_line_prints_the_skip_as_one_line_and_exits_0(tmp_path, capsys):
    (tmp_path / "p.yaml").write_text(PIPELINE)
    status = main(["run", str(tmp_path / "p.yaml"), "-i", "image=sample:coins", "--no-cache"])
    err = capsys.readouterr().err
    assert status == 0, err
    lines = [line for line in err.splitlines() if "skipped" in line]
    assert lines == [
        "warning: skipped outputs error, truth_blur: they need the ground truth 'truth': its "
        "default goes with the default image only, and it was given; give input truth "
        "(--input truth=FILE) to compute them"
    ]
    status = main(["run", str(tmp_path / "p.yaml"), "-i", "image=sample:coins", "-o", "error"])
    assert status == 2
    assert "output error needs the ground truth 'truth'" in capsys.readouterr().err


def test_a_node_measuring_against_a_truth_in_the_pipeline_is_skipped_on_other_inputs(tmp_path):
    text = PIPELINE.replace("    truth_of: [image]\n", "").replace(
        "b: truth}}", "b: truth}, truth_of: [image]}"
    )
    (tmp_path / "n.yaml").write_text(text)
    graph = gv.load_pipeline(tmp_path / "n.yaml")
    assert graph.nodes["error"].truth_of == ["image"]
    with pytest.warns(gv.MissingTruthWarning) as caught:
        result = gv.run(graph, inputs={"image": _image(0), "truth": _image(1)}, cache=None)
    assert set(result.outputs) == {"blur", "truth_blur"}
    assert str(caught[0].message) == (
        "skipped output error: it needs node 'error', whose truth goes with the default image "
        "only, and it was given; the pipeline holds no truth for yours, so nothing can compute it"
    )
    assert gv.parse_pipeline(gv.dump_pipeline(graph), "x.yaml").nodes["error"].truth_of == ["image"]


def test_every_shipped_pipeline_marks_the_truth_inputs_it_has():
    for path in sorted(PIPELINES.glob("*.yaml")):
        graph = gv.load_pipeline(path)
        for name, decl in graph.inputs.items():
            if "truth" in name or "truth" in decl.description.lower():
                assert decl.truth_of, f"{path.name}: input '{name}' is ground truth, unmarked"
    assert gv.load_pipeline(PIPELINES / "stereo.yaml").inputs["truth"].truth_of == [
        "left",
        "right",
    ]
    reconstruct = gv.load_pipeline(PIPELINES / "reconstruct.yaml")
    assert reconstruct.nodes["errors"].truth_of == ["left", "right"]


@pytest.mark.parametrize("where", ["input", "node"])
def test_an_empty_truth_of_is_refused_at_its_line(tmp_path, where):
    """``truth_of: []`` said nothing and was accepted silently."""
    text = (
        PIPELINE.replace("truth_of: [image]", "truth_of: []")
        if where == "input"
        else PIPELINE.replace("params: {sigma: 2.0}}", "params: {sigma: 2.0}, truth_of: []}")
    )
    (tmp_path / "empty.yaml").write_text(text)
    line = next(n for n, row in enumerate(text.splitlines(), 1) if "truth_of: []" in row)
    with pytest.raises(
        gv.PipelineError, match=rf"truth_of at .*empty.yaml:{line}: an empty list: name at least"
    ):
        gv.load_pipeline(tmp_path / "empty.yaml")


@pytest.mark.parametrize("where", ["input", "node"])
def test_an_input_named_twice_in_truth_of_is_refused_at_its_line(tmp_path, where):
    """``truth_of: [image, image]`` was accepted: the second name said nothing new."""
    text = (
        PIPELINE.replace("truth_of: [image]", "truth_of: [image, image]")
        if where == "input"
        else PIPELINE.replace(
            "params: {sigma: 2.0}}", "params: {sigma: 2.0}, truth_of: [image, image]}"
        )
    )
    (tmp_path / "twice.yaml").write_text(text)
    line = next(n for n, row in enumerate(text.splitlines(), 1) if "[image, image]" in row)
    with pytest.raises(
        gv.PipelineError, match=rf"truth_of at .*twice.yaml:{line}: 'image' is named twice"
    ):
        gv.compile_graph(gv.load_pipeline(tmp_path / "twice.yaml"), gv.discover())
