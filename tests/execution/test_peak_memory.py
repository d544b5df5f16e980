"""A run that cannot fit in memory is refused before it starts (issue 29 item 2): what it
must hold at least is estimated from its inputs' shapes (values alive at once), and the
estimate is a lower bound of what shipped pipelines really take."""

from __future__ import annotations

import tracemalloc

import numpy as np
import pytest

import graphvision as gv
from graphvision.cli import main
from graphvision.execution.peak_memory import estimate_peak

from ..conftest import PIPELINES

REGISTRY = gv.discover()


def _image(shape: tuple[int, ...]) -> np.ndarray:
    return np.random.default_rng(0).random(shape).astype(np.float32)


def _estimate(name: str, inputs: dict, running: int = 1) -> int:
    compiled = gv.compile_graph(gv.load_pipeline(PIPELINES / f"{name}.yaml"), REGISTRY)
    schedule = compiled.schedule_for(list(compiled.outputs))
    estimate = estimate_peak(compiled, schedule, inputs, running)
    assert estimate is not None
    return estimate.peak


@pytest.mark.parametrize("name", ["edges", "denoise", "pyramid"])
def test_the_estimate_is_at_most_what_the_run_takes(name):
    inputs = {"image": _image((192, 256, 3))}
    graph = gv.load_pipeline(PIPELINES / f"{name}.yaml")
    gv.run(graph, inputs=inputs, executor="sync", cache=None)  # imports and first-use caches
    tracemalloc.start()
    try:
        before = tracemalloc.get_traced_memory()[0]
        gv.run(graph, inputs=inputs, executor="sync", cache=None)
        taken = tracemalloc.get_traced_memory()[1] - before
    finally:
        tracemalloc.stop()
    estimate = _estimate(name, inputs)
    assert inputs["image"].nbytes < estimate <= taken


def test_the_estimate_scales_with_the_input_and_the_nodes_running_at_once():
    small = _estimate("edges", {"image": _image((100, 100, 3))})
    large = _estimate("edges", {"image": _image((200, 200, 3))})
    assert large == pytest.approx(4 * small, rel=0.01)
    assert _estimate("edges", {"image": _image((100, 100, 3))}, running=4) > small


def test_a_run_that_cannot_fit_is_refused_before_anything_runs():
    graph = gv.load_pipeline(PIPELINES / "edges.yaml")
    started = []

    class Watch(gv.RunHooks):
        def node_started(self, **info):
            started.append(info["name"])

    with pytest.raises(gv.InputError, match=r"this run cannot fit: it must hold at least "):
        gv.run(graph, inputs={"image": _image((300, 400, 3))}, max_memory=2**20, hooks=[Watch()])
    assert started == []
    result = gv.run(graph, inputs={"image": _image((30, 40, 3))}, max_memory=2**30, cache=None)
    assert result.outputs


def test_the_command_line_refuses_with_exit_2_and_creates_nothing(tmp_path, capsys):
    image = tmp_path / "big.npy"
    np.save(image, _image((300, 400, 3)))
    out = tmp_path / "out"
    status = main(
        ["run", str(PIPELINES / "edges.yaml"), "-i", f"image={image}", "--max-memory", "1M",
         "-d", str(out), "--no-cache"]
    )  # fmt: skip
    err = capsys.readouterr().err
    assert status == 2, err
    assert "this run cannot fit: it must hold at least" in err
    assert "1.0 MiB is allowed (--max-memory)" in err
    assert not out.exists()


@pytest.mark.parametrize(
    ("allowed", "shown"), [(2**10, "1.0 KiB is allowed"), (100, "100 bytes is allowed")]
)
def test_a_small_allowance_is_named_in_a_unit_that_shows_it(allowed, shown):
    """``--max-memory 1K`` was reported as '0.0 MiB is allowed'."""
    graph = gv.load_pipeline(PIPELINES / "edges.yaml")
    with pytest.raises(gv.InputError, match=shown):
        gv.run(graph, inputs={"image": _image((30, 40, 3))}, max_memory=allowed, cache=None)


def test_a_compiled_graph_run_again_is_estimated_again_for_larger_inputs(monkeypatch):
    """The estimate is kept per graph and input shapes: a second run on the same shapes plays
    the run once, and a larger input on the same compiled graph is still refused."""
    from graphvision.execution import peak_memory

    compiled = gv.compile_graph(gv.load_pipeline(PIPELINES / "edges.yaml"), REGISTRY)
    played: list[int] = []
    original = peak_memory.estimate_peak

    def counted(*args):
        played.append(1)
        return original(*args)

    monkeypatch.setattr(peak_memory, "estimate_peak", counted)
    small = {"image": _image((24, 32, 3))}
    for _ in range(2):
        gv.run(compiled, REGISTRY, inputs=small, executor="sync", max_memory=2**40)
    assert len(played) == 1
    fits = _estimate("edges", small)
    with pytest.raises(gv.InputError, match="this run cannot fit: it must hold at least"):
        gv.run(
            compiled, REGISTRY, inputs={"image": _image((48, 64, 3))}, executor="sync",
            max_memory=fits + 1,
        )  # fmt: skip
    assert len(played) == 2


def test_the_memory_available_is_read_only_when_the_free_memory_does_not_settle_it(monkeypatch):
    """``/proc/meminfo`` (0.1-0.2 ms) is read only for a peak above the free memory less a
    sixteenth of the total (the kernel's reserves are far less); never under a limit."""
    from graphvision.execution import peak_memory

    pages = {"SC_AVPHYS_PAGES": 1000, "SC_PHYS_PAGES": 1600, "SC_PAGE_SIZE": 4096}
    asked: list[str] = []
    monkeypatch.setattr(peak_memory.os, "sysconf", lambda name: asked.append(name) or pages[name])
    monkeypatch.setattr(peak_memory, "_PAGE_SIZE", 4096)
    monkeypatch.setattr(peak_memory, "_PHYSICAL", [])  # (as in a process that ran nothing)
    monkeypatch.setattr(peak_memory, "_MARGIN", [])
    monkeypatch.delenv("GRAPHVISION_MAX_MEMORY", raising=False)
    sure = (1000 - 1600 // 16) * 4096
    assert peak_memory._surely_available(sure)
    assert not peak_memory._surely_available(sure + 1)
    assert asked.count("SC_PHYS_PAGES") == 1 and asked.count("SC_AVPHYS_PAGES") == 2
    monkeypatch.setenv("GRAPHVISION_MAX_MEMORY", "1e12")
    assert not peak_memory._surely_available(0)


def test_a_peak_under_half_the_margin_read_within_a_second_is_settled_by_that_reading(monkeypatch):
    """The runs after one that read the free memory take it as read for a second when they
    need at most half of what it left (no ``sysinfo`` per run); a larger peak, or a later
    run, reads it again, and a drop in the free memory is then seen."""
    from graphvision.execution import peak_memory

    pages = {"SC_AVPHYS_PAGES": 1000, "SC_PHYS_PAGES": 1600}
    asked: list[str] = []
    clock = [100.0]
    monkeypatch.setattr(peak_memory.os, "sysconf", lambda name: asked.append(name) or pages[name])
    monkeypatch.setattr(peak_memory.time, "monotonic", lambda: clock[0])
    monkeypatch.setattr(peak_memory, "_PAGE_SIZE", 4096)
    monkeypatch.setattr(peak_memory, "_PHYSICAL", [])
    monkeypatch.setattr(peak_memory, "_MARGIN", [])
    monkeypatch.delenv("GRAPHVISION_MAX_MEMORY", raising=False)
    margin = (1000 - 100) * 4096
    assert peak_memory._surely_available(margin)  # read: 1 reading
    clock[0] += 0.9
    assert peak_memory._surely_available(margin // 2)  # settled by it
    assert asked.count("SC_AVPHYS_PAGES") == 1
    assert peak_memory._surely_available(margin // 2 + 1)  # over half of it: read again
    assert asked.count("SC_AVPHYS_PAGES") == 2
    pages["SC_AVPHYS_PAGES"] = 300  # the free memory drops: margin (300 - 100) pages
    clock[0] += 1.0
    assert not peak_memory._surely_available(margin // 2)  # a second on: read, and seen
    assert asked.count("SC_AVPHYS_PAGES") == 3
    assert peak_memory._surely_available(100 * 4096) and asked.count("SC_AVPHYS_PAGES") == 3
