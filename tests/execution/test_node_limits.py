"""Time and memory limits per node (issue 29 item 4): a node past its limit fails alone,
with a message naming it and the limit, on every executor that keeps limits; on processes
its worker is ended and replaced; a memory limit is refused where it cannot be kept."""

from __future__ import annotations

import re

import pytest

import graphvision as gv
from graphvision.cli import main

SLOW = '''
import time

import numpy as np

from graphvision import Float, node


@node("slow.sleep")
def sleep(*, seconds: float = 60.0) -> Float:
    """Sleeps ``seconds``."""
    time.sleep(seconds)
    return 1.0


@node("slow.spin")
def spin() -> Float:
    """Never returns, in NumPy's C code most of the time."""
    while True:
        np.sort(np.random.default_rng(0).random(10**5))


@node("slow.hog")
def hog(*, megabytes: int = 3000) -> Float:
    """Allocates ``megabytes``."""
    return float(np.ones(megabytes * 2**20 // 8).sum())


@node("slow.quick")
def quick() -> Float:
    """Returns at once."""
    return 2.0
'''


def _pipeline(tmp_path, nodes: str) -> gv.Graph:
    (tmp_path / "slow.py").write_text(SLOW)
    names = [line.split(":")[0].strip() for line in nodes.strip().splitlines()]
    outputs = "\n".join(f"  {name}: {name}" for name in names)
    text = f"version: 1\nname: limits\nplugins: [slow.py]\nnodes:\n{nodes}\noutputs:\n{outputs}\n"
    (tmp_path / "p.yaml").write_text(text)
    return gv.load_pipeline(tmp_path / "p.yaml")


def _failures(graph: gv.Graph, **options) -> tuple[dict[str, str], dict]:
    with pytest.raises(gv.RunError) as caught:
        gv.run(graph, cache=None, keep_going=True, **options)
    outputs = caught.value.result.outputs  # type: ignore[attr-defined]
    return {name: str(error) for name, error in caught.value.failures.items()}, outputs


@pytest.mark.parametrize("executor", ["sync", "threads", "processes"])
def test_a_node_past_its_timeout_fails_alone_naming_itself_and_the_limit(tmp_path, executor):
    graph = _pipeline(tmp_path, "  nap: {op: slow.sleep, timeout: 0.5}\n  ok: {op: slow.quick}")
    failures, outputs = _failures(graph, executor=executor)
    assert list(failures) == ["nap"]
    assert "node 'nap' (slow.sleep) ran past its time limit of 0.5 s" in failures["nap"]
    if executor == "processes":
        assert "its worker process was ended and replaced" in failures["nap"]
    assert outputs == {"ok": 2.0}


def test_the_lower_of_the_node_timeout_and_the_runs_applies(tmp_path):
    graph = _pipeline(tmp_path, "  nap: {op: slow.sleep, timeout: 50, params: {seconds: 30}}")
    failures, _ = _failures(graph, node_timeout=0.5)
    assert "ran past its time limit of 0.5 s" in failures["nap"]
    graph = _pipeline(tmp_path, "  nap: {op: slow.sleep, timeout: 0.5, params: {seconds: 30}}")
    failures, _ = _failures(graph, node_timeout=50)
    assert "ran past its time limit of 0.5 s" in failures["nap"]
    graph = _pipeline(tmp_path, "  nap: {op: slow.sleep, params: {seconds: 0.01}}")
    assert gv.run(graph, cache=None, node_timeout=30).outputs == {"nap": 1.0}


def test_a_node_spinning_in_c_code_on_processes_ends_its_worker(tmp_path):
    graph = _pipeline(tmp_path, "  spin: {op: slow.spin}\n  ok: {op: slow.quick}")
    failures, outputs = _failures(graph, executor="processes", node_timeout=1, workers=1)
    assert "node 'spin' (slow.spin) ran past its time limit of 1 s" in failures["spin"]
    assert outputs == {"ok": 2.0}  # on a worker that replaced the ended one


def test_a_node_over_its_memory_limit_on_processes_fails_alone(tmp_path):
    graph = _pipeline(tmp_path, "  hog: {op: slow.hog}\n  ok: {op: slow.quick}")
    failures, outputs = _failures(graph, executor="processes", node_memory=200 * 2**20)
    assert "node 'hog' (slow.hog) went over its memory limit of 200 MiB" in failures["hog"]
    assert outputs == {"ok": 2.0}
    small = _pipeline(tmp_path, "  hog: {op: slow.hog, params: {megabytes: 50}}")
    assert gv.run(small, cache=None, executor="processes", node_memory=200 * 2**20).outputs


def test_limits_are_refused_where_they_cannot_be_kept(tmp_path, capsys):
    graph = _pipeline(tmp_path, "  ok: {op: slow.quick}")
    with pytest.raises(ValueError, match="a node memory limit needs --executor processes"):
        gv.run(graph, cache=None, node_memory=2**30)
    with pytest.raises(ValueError, match="node_timeout must be a positive number, got -1"):
        gv.run(graph, cache=None, node_timeout=-1)
    path = str(tmp_path / "p.yaml")
    assert main(["run", path, "--node-memory", "1G"]) == 2
    assert "--node-memory needs --executor processes" in capsys.readouterr().err
    assert main(["run", path, "--node-timeout", "-3"]) == 2
    assert "seconds must be positive, got '-3'" in capsys.readouterr().err


def test_a_timeout_in_the_pipeline_file_is_checked_and_kept(tmp_path):
    with pytest.raises(
        gv.PipelineError, match=r"nodes.nap.timeout at .*p.yaml:6: Input should be greater than 0"
    ):
        _pipeline(tmp_path, "  nap: {op: slow.sleep,\n         timeout: -2}")
    with pytest.raises(
        gv.PipelineError, match=r"nodes.nap.timeout at .*p.yaml:5: .*valid number, got true"
    ):  # YAML's true was read as 1 second
        _pipeline(tmp_path, "  nap: {op: slow.sleep, timeout: true}")
    for written, spelt in (("1e-9", "1.0e-9"), ("2.5e3", "2.5e+3")):  # YAML 1.1 reads text
        with pytest.raises(
            gv.PipelineError,
            match=re.escape(f'got "{written}" (YAML reads {written} as text: write {spelt})'),
        ):
            _pipeline(tmp_path, f"  nap: {{op: slow.sleep, timeout: {written}}}")
        assert gv.parse_pipeline(
            (tmp_path / "p.yaml").read_text().replace(written, spelt), "p.yaml"
        ).nodes["nap"].timeout == float(spelt)
    graph = _pipeline(tmp_path, "  nap: {op: slow.sleep, timeout: 2.5}")
    assert graph.nodes["nap"].timeout == 2.5
    again = gv.parse_pipeline(gv.dump_pipeline(graph), "again.yaml")
    assert again.nodes["nap"].timeout == 2.5


def test_a_timeout_in_the_pipeline_file_is_refused_on_dask_at_its_line(tmp_path, capsys):
    """Dask's workers are not ours to end: the file's timeout is named, with its line,
    before anything runs (it was a ValueError from run(), an internal error on the CLI)."""
    graph = _pipeline(tmp_path, "  ok: {op: slow.quick}\n  nap: {op: slow.sleep, timeout: 2}")
    with pytest.raises(gv.PipelineError, match=r"nodes.nap.timeout at .*p.yaml:6: node time"):
        gv.run(graph, cache=None, executor="dask")
    assert main(["run", str(tmp_path / "p.yaml"), "--executor", "dask"]) == 2
    err = capsys.readouterr().err
    assert "nodes.nap.timeout at" in err and "not dask" in err and "Traceback" not in err


def test_an_infinite_timeout_in_the_pipeline_file_is_refused_at_its_line(tmp_path):
    """`timeout: .inf` passed validation, then broke the timer thread with a traceback and
    the node ran unlimited."""
    with pytest.raises(gv.PipelineError, match=r"nodes.nap.timeout at .*p.yaml:6: "):
        _pipeline(tmp_path, "  ok: {op: slow.quick}\n  nap: {op: slow.sleep, timeout: .inf}")
