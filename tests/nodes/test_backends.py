"""Backends: one op, implementations by backend, chosen by a lookup order; the
implementation and its version in the cache key and the record; errors that name
the node's line and the extra to install."""

from __future__ import annotations

import textwrap
from pathlib import Path

import numpy as np
import pytest

import graphvision as gv
from graphvision.cli.main import main

PLUGIN = '''
"""An op with a reference and two more implementations (one not installed)."""

from graphvision import Float, implements, node


@node("twice.value")
def value(x: Float, *, gain: float = 2.0) -> Float:
    """x times gain."""
    return x * gain


@implements("twice.value", backend="fast")
def fast_value(x, *, gain=2.0):
    return x * gain + 0.5  # marked, so a test sees which one ran


@implements("twice.value", backend="gpu", requires=("no_such_module_xyz",), extra="gpu")
def gpu_value(x, *, gain=2.0):
    raise AssertionError("never chosen: its module is missing")
'''


@pytest.fixture
def plugin(tmp_path: Path) -> Path:
    path = tmp_path / "twice.py"
    path.write_text(PLUGIN)
    return path


def pipeline(tmp_path: Path, extra: str = "", node: str = "") -> Path:
    path = tmp_path / "p.yaml"
    path.write_text(
        textwrap.dedent(
            f"""\
            name: p
            plugins: [twice.py]
            {extra}
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


def test_the_reference_runs_by_default_and_the_order_chooses(plugin: Path, tmp_path: Path) -> None:
    graph = gv.load_pipeline(pipeline(tmp_path))
    assert gv.run(graph, executor="sync").outputs["v"] == 2.0
    fast = gv.run(graph, executor="sync", backends=["fast", "numpy"])
    assert fast.outputs["v"] == 2.5
    assert [n.backend for n in fast.record.nodes] == ["fast"]
    assert "fast" in fast.record.table().splitlines()[1]


def test_an_order_falls_back_past_a_backend_not_installed(plugin: Path, tmp_path: Path) -> None:
    graph = gv.load_pipeline(pipeline(tmp_path))
    result = gv.run(graph, executor="sync", backends="gpu,fast")
    assert result.outputs["v"] == 2.5
    only_gpu = gv.run(graph, executor="sync", backends=["gpu"])  # then the reference
    assert only_gpu.outputs["v"] == 2.0 and only_gpu.record.nodes[0].backend == "numpy"


def test_the_file_order_and_a_pin(plugin: Path, tmp_path: Path) -> None:
    graph = gv.load_pipeline(pipeline(tmp_path, extra="backends: [fast]"))
    assert gv.run(graph, executor="sync").outputs["v"] == 2.5
    assert gv.run(graph, executor="sync", backends=["numpy"]).outputs["v"] == 2.0
    pinned = gv.load_pipeline(pipeline(tmp_path, node=", backend: numpy", extra="backends: [fast]"))
    assert gv.run(pinned, executor="sync").outputs["v"] == 2.0
    assert gv.parse_pipeline(gv.dump_pipeline(pinned)) == pinned


def test_a_pinned_backend_not_installed_names_the_line_and_the_extra(
    plugin: Path, tmp_path: Path
) -> None:
    path = pipeline(tmp_path, node=", backend: gpu")
    with pytest.raises(gv.PipelineError, match=r"p.yaml:7.*pip install 'graphvision\[gpu\]'"):
        gv.run(gv.load_pipeline(path), executor="sync")


def test_a_pin_the_op_lacks_and_an_unknown_backend_are_refused(
    plugin: Path, tmp_path: Path
) -> None:
    path = pipeline(tmp_path, node=", backend: cuda")
    with pytest.raises(gv.PipelineError, match=r"twice.value has no 'cuda' implementation"):
        gv.run(gv.load_pipeline(path), executor="sync")
    graph = gv.load_pipeline(pipeline(tmp_path))
    with pytest.raises(gv.PipelineError, match=r"unknown backend 'fats' \(did you mean 'fast'"):
        gv.run(graph, executor="sync", backends=["fats"])


def test_two_backends_never_share_a_cache_entry(plugin: Path, tmp_path: Path) -> None:
    graph = gv.load_pipeline(pipeline(tmp_path))
    cache = gv.Cache(gv.MemoryStore())
    first = gv.run(graph, executor="sync", cache=cache)
    other = gv.run(graph, executor="sync", cache=cache, backends=["fast"])
    assert other.record.nodes[0].status == "computed" and other.outputs["v"] == 2.5
    assert first.record.nodes[0].keys != other.record.nodes[0].keys
    again = gv.run(graph, executor="sync", cache=cache, backends=["fast"])
    assert again.record.nodes[0].status == "cached" and again.outputs["v"] == 2.5


def test_an_implementation_must_take_the_ops_ports_and_parameters(tmp_path: Path) -> None:
    path = tmp_path / "bad.py"
    path.write_text(
        PLUGIN + "\n\n@implements('twice.value', backend='odd')\ndef odd(x, *, scale=1.0):\n"
        "    return x\n"
    )
    registry = gv.discover([path], entry_points=False)
    (failure,) = registry.failed_plugins()
    assert "missing: gain; not the op's: scale" in failure.error
    with pytest.raises(gv.RegistrationError, match="lower-case name other than 'numpy'"):
        from graphvision.nodes.backends import implementation_of

        implementation_of(gv.implements("twice.value", backend="numpy")(lambda x: x), "p")


def test_the_cli_takes_an_order_and_lists_backends(plugin: Path, tmp_path: Path, capsys) -> None:
    path = pipeline(tmp_path)
    assert main(["run", str(path), "--backend", "fast,numpy", "--record", "--no-cache"]) == 0
    out = capsys.readouterr().out
    assert "v: Float 2.5" in out and " fast " in out
    assert main(["run", str(path), "--backend", "fats", "--no-cache"]) == 2
    assert "unknown backend 'fats'" in capsys.readouterr().err
    assert main(["describe", "twice.value", "--plugins", str(plugin)]) == 0
    assert "backends: numpy, fast, gpu (not installed)" in capsys.readouterr().out
    assert main(["describe", "threshold.otsu"]) == 0
    assert "conformance: max_abs 0.004. OpenCV splits 256" in capsys.readouterr().out
    assert main(["nodes", "--plugins", str(plugin)]) == 0
    assert "[+fast, gpu (not installed)]" in capsys.readouterr().out  # marked, as describe


def test_the_opencv_backend_runs_a_shipped_pipeline() -> None:
    pytest.importorskip("cv2", reason="needs opencv-python-headless (dev extra)")
    pipelines = Path(__file__).parents[2] / "pipelines"
    graph = gv.load_pipeline(pipelines / "denoise.yaml")
    result = gv.run(graph, executor="sync", backends=["opencv", "numpy"])
    ran = {n.op: n.backend for n in result.record.nodes}
    assert ran["filters.median"] == "opencv" and ran["filters.gaussian"] == "opencv"
    reference = gv.run(graph, executor="sync")
    for name, value in reference.outputs.items():
        assert np.allclose(result.outputs[name], value, atol=0.05), name


def test_a_sweep_takes_the_order_too(plugin: Path, tmp_path: Path) -> None:
    graph = gv.load_pipeline(pipeline(tmp_path))
    result = gv.sweep(graph, {"v.gain": [1.0, 3.0]}, backends=["fast"], executor="sync")
    assert [row["v"] for row in result.rows] == [1.5, 3.5]
    assert {n.backend for record in result.records for n in record.nodes} == {"fast"}


def test_opencv_is_imported_only_when_chosen_and_its_version_keys_results() -> None:
    pytest.importorskip("cv2", reason="needs opencv-python-headless (dev extra)")
    import subprocess
    import sys

    code = (
        "import sys, graphvision as gv; r = gv.discover(); "
        "assert 'filters.gaussian' in r.implementations; print('cv2' in sys.modules)"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert done.stdout.strip() == "False"
    spec = gv.discover().implementation("filters.gaussian", "opencv")
    assert spec is not None and spec.key_id == "filters.gaussian@opencv"
    assert "+opencv-python-headless==" in spec.source_hash
