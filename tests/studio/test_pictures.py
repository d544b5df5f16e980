"""Pictures for the page: RGBA bytes of known values, previews made smaller by block means,
made ahead of the page's request, a bad ``step`` refused with its reason; values to and
from the workers out of band; descriptions the page asked for pushed with their node's event."""

from __future__ import annotations

import json
import multiprocessing
import os
import threading
import urllib.error
import urllib.request
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("starlette")

import graphvision as gv
from graphvision.studio.payload import rgba_of, shrunk
from graphvision.studio.pictures import Descriptions, Pictures
from graphvision.studio.server import studio
from graphvision.studio.session import Session
from graphvision.studio.transport import Channel
from graphvision.values.ports import is_frozen

TOY = Path(__file__).parents[1] / "fixtures" / "toy.py"


class _Shown(gv.ColorImagePort):
    """A colour image whose picture is its value (the test's numbers, unchanged)."""

    @classmethod
    def preview(cls, value: np.ndarray) -> np.ndarray:
        return value


def test_rgba_bytes_are_the_rounded_levels_with_nan_as_zero() -> None:
    levels = np.arange(256, dtype=np.float64) / 255.0  # level k is k/255: its byte is k
    picture = np.stack([levels, levels[::-1], np.full(256, 0.5)], axis=1).reshape(16, 16, 3)
    picture[0, 0] = [np.nan, np.inf, -np.inf]
    picture[0, 1] = [-3.0, 7.0, 0.5]
    data, shape = rgba_of(_Shown, picture.astype(np.float32))
    rgba = np.frombuffer(data, np.uint8).reshape(16, 16, 4)
    assert shape == [16, 16]
    expected = np.stack([np.arange(256), 255 - np.arange(256), np.full(256, 128)], axis=1)
    expected = expected.reshape(16, 16, 3)
    expected[0, 0] = [0, 255, 0]  # NaN as 0, +inf as 1, -inf as 0
    expected[0, 1] = [0, 255, 128]  # clipped to [0, 1]
    assert np.array_equal(rgba[:, :, :3], expected)
    assert (rgba[:, :, 3] == 255).all()


def test_a_gray_picture_is_the_same_in_red_green_and_blue() -> None:
    gray = np.array([[0.0, 1.0], [0.2, 0.6]], np.float32)
    data, _ = rgba_of(gv.GrayImagePort, gray)
    rgba = np.frombuffer(data, np.uint8).reshape(2, 2, 4)
    assert rgba[:, :, 0].tolist() == [[0, 255], [51, 153]]
    assert (rgba[:, :, 0] == rgba[:, :, 1]).all() and (rgba[:, :, 0] == rgba[:, :, 2]).all()


def test_a_preview_is_the_mean_of_each_block() -> None:
    picture = np.arange(5 * 7, dtype=np.float32).reshape(5, 7)  # 5x7: 2x3 whole 2x2 blocks
    small = shrunk(picture, 2)
    assert small.shape == (2, 3)
    assert small[0, 0] == pytest.approx((0 + 1 + 7 + 8) / 4)
    assert small[1, 2] == pytest.approx((18 + 19 + 25 + 26) / 4)
    assert shrunk(picture, 1) is picture
    assert shrunk(picture, 8) is picture  # no whole block: the picture itself
    data, shape = rgba_of(_Shown, np.ones((40, 60, 3), np.float32) * 0.2, step=4)
    assert shape == [10, 15] and len(data) == 10 * 15 * 4


def _rgba_as_before(picture: np.ndarray, step: int) -> bytes:
    """The RGBA bytes as rgba_of made them before previews were summed a channel at a time."""
    scaled = np.multiply(shrunk(picture, step), 255.0, dtype=np.float32)
    np.add(scaled, 0.5, out=scaled)
    np.fmax(scaled, 0.0, out=scaled)
    np.fmin(scaled, 255.0, out=scaled)
    scaled = scaled if scaled.ndim == 3 else scaled[:, :, None]
    rgba = np.empty((*scaled.shape[:2], 4), np.uint8)
    rgba[:, :, 3] = 255
    rgba[:, :, : min(scaled.shape[2], 4)] = scaled[:, :, :4]
    if scaled.shape[2] < 3:
        rgba[:, :, 1:3] = scaled[:, :, :1]
    return rgba.tobytes()


@pytest.mark.parametrize("channels", [0, 1, 2, 3, 4, 5])
def test_a_preview_has_the_bytes_it_had_when_summed_all_channels_at_once(channels) -> None:
    rng = np.random.default_rng(channels)
    shape = (37, 53) if channels == 0 else (37, 53, channels)
    picture = (rng.random(shape, dtype=np.float32) * 1.4 - 0.2).astype(np.float32)
    picture.flat[::97] = np.nan  # NaN is 0, below 0 is 0, above 1 is 255
    for step in (1, 2, 3, 5, 16):
        data, _ = rgba_of(_Shown, picture, step=step)
        assert data == _rgba_as_before(picture, step), step
    doubles = rng.random((9, 12, 3))  # a float64 picture is summed as before too
    assert rgba_of(_Shown, doubles, step=2)[0] == _rgba_as_before(doubles, 2)


def test_the_picture_the_page_shows_is_made_when_its_node_finishes() -> None:
    graph = gv.Graph("darkening")
    graph.input("image", "GrayImage", default=np.full((6, 8), 0.8, np.float32))
    graph.add("dark", "toy.darken", image="image", params={"factor": 0.5})
    graph.output("dark", "dark")
    session = Session(graph, gv.discover([TOY]), executor="threads")
    pictures = Pictures(session)
    first = session.start()
    session.wait()
    assert pictures.made == {}  # the page has shown no picture yet
    pictures.wanted(first.id, "dark", "out", 2)
    second = session.change({"dark.factor": 0.25})
    session.wait()
    made = pictures.made[(second.id, "dark", "out", 2)].result()  # before anyone asked
    data, shape, _ = made
    assert shape == [3, 4]
    assert set(data[::4]) == {round(0.8 * 0.25 * 255)}  # the newer run's value


def test_a_description_the_page_asked_for_rides_its_node_event() -> None:
    graph = gv.Graph("darkening")
    graph.input("image", "GrayImage", default=np.full((6, 8), 0.8, np.float32))
    graph.add("dark", "toy.darken", image="image", params={"factor": 0.5})
    graph.add("darker", "toy.darken", image="dark", params={"factor": 0.5})
    graph.output("darker", "darker")
    session = Session(graph, gv.discover([TOY]), executor="threads")
    descriptions = Descriptions(session)
    first = session.start()
    session.wait()
    assert descriptions.describe(first, "dark", "out")["range"] == pytest.approx([0.4, 0.4])
    events: list[dict] = []
    session.listeners.append(events.append)
    second = session.change({"dark.factor": 0.25})
    session.wait()
    nodes = {e["node"]: e for e in events if e["event"] == "node" and e["status"] == "computed"}
    pushed = nodes["dark"]["values"]["out"]  # asked for in run 1: pushed in run 2
    assert pushed["run"] == second.id and pushed["view"] == "image"
    assert pushed["shape"] == [6, 8] and pushed["range"] == pytest.approx([0.2, 0.2])
    assert nodes["darker"].get("values", {}) == {}  # never asked for: the page asks


def test_a_bad_step_is_refused_with_its_reason() -> None:
    graph = gv.Graph("darkening")
    graph.input("image", "GrayImage", default=np.full((6, 8), 0.8, np.float32))
    graph.add("dark", "toy.darken", image="image")
    graph.output("dark", "dark")
    server = studio(graph, registry=gv.discover([TOY]))
    try:
        server.session.wait()
        base = f"http://127.0.0.1:{server.port}/api/rgba/1/dark/out?token={server.token}"
        with urllib.request.urlopen(base + "&step=2", timeout=30) as answer:
            assert answer.headers["X-Shape"] == "3,4"
        for bad in ("0", "17", "two"):
            with pytest.raises(urllib.error.HTTPError) as refused:
                urllib.request.urlopen(f"{base}&step={bad}", timeout=30)
            assert refused.value.code == 400
            error = json.loads(refused.value.read())["error"]
            assert error == f"step='{bad}': must be a whole number from 1 to 16"
    finally:
        server.stop()


def test_values_cross_the_pipe_unchanged() -> None:
    mine, theirs = multiprocessing.Pipe()
    sent = {"picture": np.arange(12, dtype=np.float32).reshape(3, 4), "n": 3,
            "columns": np.asfortranarray(np.ones((2, 3)))}  # fmt: skip
    Channel(mine).send(sent)
    got = Channel(theirs).receive()
    assert got["n"] == 3 and np.array_equal(got["picture"], sent["picture"])
    assert got["picture"].dtype == np.float32 and np.array_equal(got["columns"], sent["columns"])


@pytest.mark.parametrize(
    ("duplex", "memory_files"), [(True, True), (False, True), (True, False)]
)  # a socket pair: shared memory; a pipe, or no memfd_create (not Linux): inline
def test_large_values_cross_the_pipe_unchanged(
    duplex: bool, memory_files: bool, monkeypatch: pytest.MonkeyPatch
) -> None:
    if not memory_files:
        monkeypatch.delattr(os, "memfd_create", raising=False)
    reader, writer = multiprocessing.Pipe(duplex)
    big = np.random.default_rng(0).random((256, 512, 3)).astype(np.float32)  # 1.5 MB: shared
    sent = {"big": big, "small": np.arange(5.0), "again": big[::2]}
    sender = threading.Thread(target=Channel(writer).send, args=(sent,))  # a pipe holds 64 kB
    sender.start()
    got = Channel(reader).receive()
    sender.join()
    assert np.array_equal(got["big"], big) and got["big"].dtype == np.float32
    assert np.array_equal(got["small"], np.arange(5.0)) and np.array_equal(got["again"], big[::2])


def _exchange(size: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    return rng.random(size, dtype=np.float32), rng.random(size // 2, dtype=np.float32)


def test_the_arena_is_reused_and_what_was_received_stays_as_it_came() -> None:
    a, b = (Channel(end) for end in multiprocessing.Pipe(duplex=True))
    first, second = _exchange(100_000, 1), _exchange(100_000, 2)  # 400 and 200 kB: shared
    a.send(first)
    got_first = b.receive()
    arena = a.out
    b.send("answer")  # the peer answers: the arena may be written again
    assert a.receive() == "answer"
    a.send(second)
    got_second = b.receive()
    assert arena is not None and a.out is arena  # the same memory file, not a new one
    for got, sent in zip((*got_first, *got_second), (*first, *second), strict=True):
        assert np.array_equal(got, sent)  # the first message's values were copied out
        assert is_frozen(got)  # immutable and aligned as received: no copy to freeze them
    a.close()
    b.close()


def test_a_message_sent_before_the_answer_does_not_write_over_the_last() -> None:
    a, b = (Channel(end) for end in multiprocessing.Pipe(duplex=True))
    first, second = _exchange(100_000, 3), _exchange(300_000, 4)  # the second grows it
    a.send(first)
    a.send(second)  # no answer in between: the first is still unread
    got_first, got_second = b.receive(), b.receive()
    for got, sent in zip((*got_first, *got_second), (*first, *second), strict=True):
        assert np.array_equal(got, sent)
    b.send("answer")
    a.receive()
    a.send(second)  # the arena grows to hold it
    assert all(np.array_equal(g, s) for g, s in zip(b.receive(), second, strict=True))
    a.close()
    b.close()
