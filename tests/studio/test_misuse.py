"""The studio survives misuse: a node that raises, a slow node cancelled, an input file
deleted while it runs; the server keeps serving and the cache stays sound."""

from __future__ import annotations

import time
from pathlib import Path

import imageio.v3 as iio
import numpy as np
import pytest

pytest.importorskip("starlette")

import graphvision as gv
from graphvision.studio.session import Session


def test_a_node_that_raises_is_reported_and_the_rest_is_kept(registry) -> None:
    graph = gv.Graph("failing")
    graph.add("c", "toy.const", params={"value": 2.0})
    graph.add("bad", "toy.fail", x="c", params={"message": "the lens cap is on"})
    graph.add("good", "toy.add", a="c", b="c")
    graph.output("bad", "bad")
    graph.output("good", "good")
    session = Session(graph, registry)
    first = session.start()
    session.wait()
    assert first.status == "failed"
    assert "node 'bad' (op toy.fail) failed" in first.nodes["bad"]["error"]
    assert "the lens cap is on" in first.error
    assert first.metrics == {"good": 4.0}  # the independent branch finished and is shown
    second = session.change({"c.value": 3.0})  # the session goes on
    session.wait()
    assert second.metrics == {"good": 6.0} and second.nodes["bad"]["status"] == "failed"


def test_cancel_stops_a_run_before_its_next_node(registry) -> None:
    graph = gv.Graph("slow")
    graph.add("c", "toy.const")
    graph.add("s1", "toy.sleep", x="c", params={"seconds": 0.5})
    graph.add("s2", "toy.sleep", x="s1", params={"seconds": 0.5})
    graph.add("s3", "toy.sleep", x="s2", params={"seconds": 0.5})
    graph.output("out", "s3")
    session = Session(graph, registry)
    events: list[dict] = []
    session.listeners.append(events.append)
    slow = session.start()
    deadline = time.monotonic() + 20
    while slow.nodes.get("s1", {}).get("status") != "running" and time.monotonic() < deadline:
        time.sleep(0.01)
    assert session.cancel() is slow
    session.wait()
    assert slow.status == "cancelled" and slow.values == {}
    assert "s2" not in slow.nodes or slow.nodes["s2"]["status"] == "queued"  # never started
    assert {"event": "run", "run": slow.id, "status": "cancelled"}.items() <= next(
        e for e in events if e.get("status") == "cancelled"
    ).items()
    again = session.start()  # the next run starts from what the cancelled one cached
    session.wait()
    assert again.status == "done" and again.metrics == {"out": 1.0}


def test_an_input_deleted_while_the_studio_runs(registry, tmp_path: Path) -> None:
    picture = tmp_path / "scene.png"
    iio.imwrite(picture, np.zeros((8, 8), np.uint8))
    graph = gv.Graph("counting")
    graph.input("image", "Image", default=str(picture))
    graph.add("n", "toy.count", image="image")
    graph.output("n", "n")
    session = Session(graph, registry)
    session.start()
    session.wait()
    assert session.runs[-1].status == "done"
    picture.unlink()
    broken = session.start()
    session.wait()
    assert broken.status == "failed"
    assert "scene.png" in broken.error
    iio.imwrite(picture, np.zeros((8, 8), np.uint8))
    mended = session.start()
    session.wait()
    assert mended.status == "done"


def test_the_free_port_is_held_from_the_moment_it_is_chosen(registry) -> None:
    """A port probed and let go could be taken by another process before the server bound
    it (two studios started at once failed with 'address already in use')."""
    import socket

    from graphvision.studio.server import make_server, serve_in_background

    graph = gv.Graph("held")
    graph.add("y", "toy.const", params={"value": 2.0})
    graph.output("y", "y")
    server = make_server(Session(graph, registry))
    with socket.socket() as other, pytest.raises(OSError):
        other.bind(("127.0.0.1", server.port))
    serve_in_background(server)
    try:
        assert server.server.started
    finally:
        server.stop()
