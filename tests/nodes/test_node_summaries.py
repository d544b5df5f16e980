"""``graphvision nodes`` summaries are plain sentences (issue 29, item 12): the first sentence
of a node's docstring, whole even when wrapped over lines, its inline LaTeX and
reStructuredText as plain text, without pointers such as "(module docstring)"."""

from __future__ import annotations

import re

import pytest

import graphvision as gv
from graphvision.cli import main
from graphvision.nodes.spec import doc_summary, math_text

RAW = re.compile(r"\\|[{}`]|:math:|:func:|:class:|module docstring|\(module\b")


def test_every_registered_node_has_a_plain_one_sentence_summary(registry):
    for op, spec in registry.nodes.items():
        summary = spec.summary
        assert summary, f"{op} has no summary"
        assert not RAW.search(summary), f"{op}: {summary!r}"
        assert summary[-1] in ".!?", f"{op}: {summary!r}"
        assert summary.count("(") == summary.count(")"), f"{op}: {summary!r}"
        first_line = spec.doc.strip().splitlines()[0].strip()
        if first_line[-1] not in ".!?":  # a sentence wrapped over lines is read to its end
            assert len(summary.split()) > len(first_line.split()), f"{op}: {summary!r}"


@pytest.mark.parametrize(
    ("doc", "summary"),
    [
        ("Closing: dilation then erosion. Fills holes.", "Closing: dilation then erosion."),
        (
            "Build a network and train it by\n    mini-batch SGD, e.g. with momentum.\n\n    More.",
            "Build a network and train it by mini-batch SGD, e.g. with momentum.",
        ),
        ("Zhang's calibration of a board (module docstring).", "Zhang's calibration of a board."),
        ("Blur by the circle (thin lens, module docstring).", "Blur by the circle (thin lens)."),
        ("Pixels to pixels (module ``_projection``).", "Pixels to pixels."),
        ("A trained network (see the module docstring).", "A trained network."),
        (
            r"The line :math:`l = v_1 \times v_2` through two points.",
            "The line l = v₁ × v₂ through two points.",
        ),
        ("Match ``a`` to ``b`` (like :func:`~pkg.mod.gaussian`).", "Match a to b (like gaussian)."),
        ("Where the element *fits*", "Where the element fits."),
        (
            "Keep f(x) (the value. Not split) whole. Then more.",
            "Keep f(x) (the value. Not split) whole.",
        ),
    ],
)
def test_a_summary_is_the_first_sentence_as_plain_text(doc, summary):
    assert doc_summary(doc) == summary


@pytest.mark.parametrize(
    ("tex", "text"),
    [
        (r"\frac{1}{N}\sum_i (a_i - b_i)^2", "1/N Σᵢ (aᵢ - bᵢ)²"),
        (r"x = K\, d(\pi(R(X - \tilde C)))", "x = K d(π(R(X - C̃)))"),
        (r"P = K [R \mid -R \tilde C]", "P = K [R | -R C̃]"),
        (r"h = \lceil 3\sigma \rceil", "h = ⌈ 3σ ⌉"),
        (r"\hat x = K^{-1} x", "x̂ = K⁻¹ x"),
        (r"H(x) = \mathrm{sign}\sum_t \alpha_t h_t(x)", "H(x) = sign Σₜ αₜ hₜ(x)"),
        (r"\|w\| \le 2 \arctan(d / 2f)", "‖w‖ ≤ 2 arctan(d / 2f)"),
        (r"E = K_b^T F K_a", "E = K_bᵀ F Kₐ"),
        (r"\sum_{r' \le r} I", "Σ_(r′ ≤ r) I"),
    ],
)
def test_inline_latex_reads_as_unicode_text(tex, text):
    assert math_text(tex) == text


PLUGIN = '''
from graphvision import Float, node


@node("maths.mean_square")
def mean_square(x: Float) -> Float:
    r"""Mean square :math:`\\frac{1}{N}\\sum_i x_i^2` of the values, over every pixel and
    channel of the image (module docstring).

    Parameters
    ----------
    x : the value
    """
    return x * x
'''


def test_nodes_prints_plain_summaries_of_a_plugin_of_ones_own(capsys, tmp_path):
    plugin = tmp_path / "maths.py"
    plugin.write_text(PLUGIN)
    assert main(["--plugins", str(plugin), "nodes"]) == 0
    out = capsys.readouterr().out
    line = next(line for line in out.splitlines() if "maths.mean_square" in line)
    assert line.split("maths.mean_square", 1)[1].strip() == (
        "Mean square 1/N Σᵢ xᵢ² of the values, over every pixel and channel of the image."
    )
    assert not RAW.search(out)


def test_describe_shows_the_documentation_as_text_and_json_keeps_it_as_written(capsys):
    assert main(["describe", "camera.horizon"]) == 0
    out = capsys.readouterr().out
    assert "l = v₁ × v₂" in out and ":math:" not in out
    spec = gv.discover().nodes["camera.horizon"]
    info = spec.describe()
    assert ":math:" in info["doc"] and info["summary"] == spec.summary
