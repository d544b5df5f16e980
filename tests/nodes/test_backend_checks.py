"""Backends beyond a module: a parameter value one backend alone handles
(``exclusive``), and a requirement checked by a function (a class a version of a
library lacks)."""

from __future__ import annotations

import textwrap
from pathlib import Path

import pytest

import graphvision as gv

PLUGIN = '''
"""An op whose 'turbo' mode only the fast backend has, and a backend that cannot run."""

from typing import Literal

from graphvision import Float, implements, node


@node("twice.value")
def value(x: Float, *, mode: Literal["plain", "turbo"] = "plain") -> Float:
    """x times 2."""
    if mode != "plain":
        raise ValueError("turbo is the fast backend's alone")
    return x * 2.0


@implements("twice.value", backend="fast", exclusive={"mode": ("turbo",)})
def fast_value(x, *, mode="plain"):
    return x * 2.0 + (1.0 if mode == "turbo" else 0.5)


def _lacks_thing() -> str:
    return "libx 2.0 has no Thing (libx 1.x has)"


@implements("twice.value", backend="old", requires=("numpy", _lacks_thing), extra="old")
def old_value(x, *, mode="plain"):
    raise AssertionError("never chosen: its check fails")
'''


def pipeline(tmp_path: Path, node: str = "") -> Path:
    (tmp_path / "twice.py").write_text(PLUGIN)
    path = tmp_path / "p.yaml"
    path.write_text(
        textwrap.dedent(
            f"""\
            name: p
            plugins: [twice.py]
            inputs:
              x: {{type: Float, default: 1.0}}
            nodes:
              v: {{op: twice.value, in: {{x: x}}{node}}}
            outputs:
              v: v
            """
        )
    )
    return path


def test_a_value_one_backend_alone_has_is_refused_on_the_others(tmp_path: Path) -> None:
    graph = gv.load_pipeline(pipeline(tmp_path, node=", params: {mode: turbo}"))
    with pytest.raises(
        gv.PipelineError,
        match=r"p.yaml:6.*mode: 'turbo' of twice.value is implemented by the 'fast' backend "
        r"alone, not by 'numpy': choose it \(--backend fast",
    ):
        gv.run(graph, executor="sync")
    with pytest.raises(gv.PipelineError, match=r"alone, not by 'numpy'"):
        gv.run(graph, executor="sync", backends=["old", "numpy"])  # old cannot run: numpy
    assert gv.run(graph, executor="sync", backends=["fast"]).outputs["v"] == 3.0
    plain = gv.load_pipeline(pipeline(tmp_path))
    assert gv.run(plain, executor="sync").outputs["v"] == 2.0


def test_a_failed_check_skips_the_backend_and_a_pin_gives_its_reason(tmp_path: Path) -> None:
    graph = gv.load_pipeline(pipeline(tmp_path))
    result = gv.run(graph, executor="sync", backends=["old", "fast"])
    assert result.record.nodes[0].backend == "fast"
    pinned = gv.load_pipeline(pipeline(tmp_path, node=", backend: old"))
    with pytest.raises(
        gv.PipelineError,
        match=r"p.yaml:6.*backend 'old' of twice.value cannot run here "
        r"\(libx 2.0 has no Thing \(libx 1.x has\)\): pip install 'graphvision\[old\]'",
    ):
        gv.run(pinned, executor="sync")
    # the check does not make the backend look uninstalled in listings (nothing imported)
    registry = gv.discover([tmp_path / "twice.py"], entry_points=False)
    assert registry.backends_of("twice.value") == {"numpy": True, "fast": True, "old": True}


def test_exclusive_must_name_a_parameter_of_the_op(tmp_path: Path) -> None:
    path = tmp_path / "bad.py"
    path.write_text(
        PLUGIN + "\n\n@implements('twice.value', backend='odd', exclusive={'speed': (2,)})\n"
        "def odd(x, *, mode='plain'):\n    return x\n"
    )
    (failure,) = gv.discover([path], entry_points=False).failed_plugins()
    assert "exclusive names no parameter of twice.value: speed" in failure.error


RELEASES = '''
"""An op whose second backend needs a release of NumPy that is not installed."""

from graphvision import Float, implements, node


@node("aged.value")
def value(x: Float) -> Float:
    """x."""
    return x


@implements("aged.value", backend="aged", requires=("numpy", "numpy<1.0"), extra="aged")
def aged_value(x):
    raise AssertionError("never chosen: the installed numpy is 1.0 or later")
'''


def test_a_release_out_of_range_is_read_from_metadata_listed_and_hinted(tmp_path: Path) -> None:
    """A release requirement is known without importing the library: listings mark the
    backend (the cascade on OpenCV 5 was listed as available), and a pin asks for it."""
    from importlib.metadata import version

    from graphvision.cli.nodes import backends_text, other_backends

    plugin = tmp_path / "aged.py"
    plugin.write_text(RELEASES)
    registry = gv.discover([plugin], entry_points=False)
    assert registry.backends_of("aged.value") == {"numpy": True, "aged": False}
    why = f"numpy {version('numpy')} is installed; needs numpy<1.0"
    assert registry.describe("aged.value")["unavailable"] == {"aged": why}
    described = registry.describe("aged.value")  # as `describe` and `nodes` print it
    assert backends_text(described) == f"numpy, aged (cannot run here: {why})"
    assert other_backends(described) == ["aged (cannot run here)"]
    path = tmp_path / "p.yaml"
    path.write_text(
        "name: p\nplugins: [aged.py]\nnodes:\n  v: {op: aged.value, in: {x: x}, backend: aged}\n"
        "inputs:\n  x: {type: Float, default: 1.0}\noutputs:\n  v: v\n"
    )
    with pytest.raises(
        gv.PipelineError,
        match=rf"p.yaml:4.*backend 'aged' of aged.value cannot run here \({why}\): "
        r"pip install 'graphvision\[aged\]' 'numpy<1.0'",
    ):
        gv.compile_graph(gv.load_pipeline(path), registry)


def test_requires_holds_modules_releases_and_checks_only(tmp_path: Path) -> None:
    path = tmp_path / "odd.py"
    path.write_text(RELEASES.replace('"numpy<1.0"', '"numpy ~= 1.0"'))
    (failure,) = gv.discover([path], entry_points=False).failed_plugins()
    assert (
        "requires holds modules ('cv2'), releases ('opencv-python-headless<5', 'numpy>=2') "
        "and checks; not 'numpy ~= 1.0'"
    ) in failure.error
