"""recognition.lbp_detect on OpenCV: the model written in OpenCV's cascade format, and
a backend that OpenCV 5 (no CascadeClassifier) cannot run, refused with the reason."""

from __future__ import annotations

import re
import textwrap
from pathlib import Path

import numpy as np
import pytest

import graphvision as gv
from graphvision_plugins.recognition import lbp_cascade
from graphvision_plugins.recognition._opencv_cascade import parse_opencv_cascade

cv2 = pytest.importorskip("cv2", reason="the opencv backend needs opencv-python-headless")

from graphvision_plugins.opencv_backend.cascade import cascade_xml  # noqa: E402

PIPELINE = """\
    name: faces
    inputs:
      image: {type: Image, default: "sample:astronaut"}
    nodes:
      gray:    {op: colour.to_gray, in: {image: image}, backend: numpy}
      cascade: {op: recognition.lbp_cascade}
      boxes:   {op: recognition.lbp_detect, in: {image: gray, cascade: cascade}%s}
    outputs:
      boxes: boxes
    """


def test_the_written_cascade_reads_back_as_the_same_model() -> None:
    model = lbp_cascade()
    again = parse_opencv_cascade(cascade_xml(model))
    for name in ("rects", "feature", "subsets", "leaves", "stage", "stage_threshold"):
        np.testing.assert_array_equal(getattr(again, name), getattr(model, name), err_msg=name)
    assert (again.height, again.width) == (model.height, model.width)


@pytest.mark.skipif(hasattr(cv2, "CascadeClassifier"), reason="this OpenCV has the class")
def test_a_pin_on_an_opencv_without_cascade_classifier_names_why(tmp_path: Path) -> None:
    path = tmp_path / "faces.yaml"
    path.write_text(textwrap.dedent(PIPELINE % ", backend: opencv"))
    with pytest.raises(
        gv.PipelineError,
        match=r"faces.yaml:7.*backend 'opencv' of recognition.lbp_detect cannot run here "
        rf"\(OpenCV {cv2.__version__} has no CascadeClassifier: OpenCV 5 dropped it; "
        r"opencv-python-headless 4.x has it\): "
        r"pip install 'graphvision\[opencv\]' 'opencv[a-z-]*-python[a-z-]*<5'$",
    ):
        gv.compile_graph(gv.load_pipeline(path), gv.discover())
    path.write_text(textwrap.dedent(PIPELINE % ""))  # an order falls back to the reference
    compiled = gv.compile_graph(gv.load_pipeline(path), gv.discover(), backends=["opencv"])
    assert compiled.steps["boxes"].spec.backend == "numpy"


@pytest.mark.skipif(hasattr(cv2, "CascadeClassifier"), reason="this OpenCV has the class")
def test_on_opencv_5_the_listings_say_the_cascade_cannot_run_from_the_wheels_release(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """``nodes`` and ``describe`` print from the plugin index, without importing OpenCV:
    they listed the opencv implementation as available on OpenCV 5."""
    from graphvision.cli.main import main

    gv.discover()  # the index they print from
    assert main(["describe", "recognition.lbp_detect"]) == 0
    assert re.search(
        r"backends: numpy, opencv \(cannot run here: (opencv[a-z-]*) 5[.\d]* is installed; "
        r"needs \1<5\)\n",
        capsys.readouterr().out,
    )
    assert main(["nodes"]) == 0
    lines = capsys.readouterr().out.splitlines()
    (line,) = [t for t in lines if t.split()[:1] == ["recognition.lbp_detect"]]
    assert line.endswith("[+opencv (cannot run here)]")


@pytest.mark.skipif(not hasattr(cv2, "CascadeClassifier"), reason="OpenCV 5 lacks the class")
def test_opencv_4_finds_the_astronauts_face_where_the_reference_does() -> None:
    import skimage.data

    from graphvision_plugins.opencv_backend import cv_lbp_detect
    from graphvision_plugins.recognition import lbp_detect

    gray = skimage.data.astronaut().mean(axis=2).astype(np.float32) / 255
    ours, theirs = lbp_detect(gray, lbp_cascade()), cv_lbp_detect(gray, lbp_cascade())
    assert len(ours) == len(theirs) == 1  # reference [177, 67, 273, 163]; OpenCV 4.14
    np.testing.assert_allclose(theirs.xyxy, ours.xyxy, atol=7.0)  # [171, 64, 275, 168]
