"""The studio's session and server, without a browser: changes, superseding, token, saving."""

from __future__ import annotations

import asyncio
import json
import os
import stat
import urllib.error
import urllib.request
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

pytest.importorskip("starlette")
pytest.importorskip("uvicorn")

import graphvision as gv
from graphvision.errors import PipelineError
from graphvision.studio.app import _Api, _reference
from graphvision.studio.payload import describe_value, view_of
from graphvision.studio.saving import command_line, save_parameters
from graphvision.studio.session import Session

PIPELINES = Path(__file__).parents[2] / "pipelines"


@pytest.fixture(scope="module")
def coins() -> Session:
    graph = gv.load_pipeline(PIPELINES / "coins.yaml")
    session = Session(graph, gv.discover())
    session.start()
    session.wait()
    return session


def _statuses(run) -> dict[str, str]:
    return {node.name: node.status for node in run.record.nodes}


def test_a_change_recomputes_only_what_is_downstream(coins: Session) -> None:
    coins.change({"binary.k": -0.3})
    coins.wait()
    run = coins.runs[-1]
    assert run.status == "done"
    statuses = _statuses(run)
    assert statuses["gray"] == "cached" and statuses["disk"] == "cached"
    downstream = ["binary", "closed", "filled", "opened", "labels", "measured", "coins", "overlay"]
    assert all(statuses[name] == "computed" for name in downstream)
    assert run.metrics["count"] == 23  # one coin lost to the lower threshold (24 before)
    assert run.diff == {"binary.k": [None, -0.3]}
    assert run.summary()["file"] == {"binary.k": 0.0}  # coins.yaml's k: the runs table shows it
    assert ("labels", "out") in run.values and ("gray", "out") in run.values  # every node's value


def test_an_invalid_value_is_refused_before_anything_runs(coins: Session) -> None:
    runs = len(coins.runs)
    with pytest.raises(PipelineError, match="must be odd"):
        coins.change({"params.window": 50})
    with pytest.raises(PipelineError, match="less than or equal to 1"):
        coins.change({"binary.k": 3})
    with pytest.raises(PipelineError, match="no node 'binarry'"):
        coins.change({"binarry.k": 0.1})
    assert len(coins.runs) == runs


def test_a_newer_change_supersedes_the_run_in_flight() -> None:
    graph = gv.load_pipeline(PIPELINES / "coins.yaml")
    session = Session(graph, gv.discover())  # a cold cache: the first run takes seconds
    first = session.start()
    second = session.change({"binary.k": -0.3})
    session.wait()
    assert first.status == "superseded" and first.values == {}  # nothing of it is shown
    assert second.status == "done" and second.metrics["count"] == 23
    third = session.change({"binary.k": None})  # back to the file's value
    session.wait()
    assert third.metrics["count"] == 24 and _statuses(third)["gray"] == "cached"
    fourth = session.change({"binary.k": -0.3})  # the cache holds what the second run made
    session.wait()
    assert fourth.metrics["count"] == 23 and set(_statuses(fourth).values()) == {"cached"}


def test_the_server_refuses_requests_without_the_token() -> None:
    server = gv.studio(PIPELINES / "coins.yaml", run=False)  # the package takes the call
    try:
        base = f"http://127.0.0.1:{server.port}"
        for url in (f"{base}/", f"{base}/api/graph", f"{base}/static/studio.js",
                    f"{base}/api/graph?token=wrong"):  # fmt: skip
            with pytest.raises(urllib.error.HTTPError) as refused:
                urllib.request.urlopen(url, timeout=10)
            assert refused.value.code == 403
        with urllib.request.urlopen(f"{base}/api/graph?token={server.token}", timeout=10) as ok:
            graph = json.load(ok)
        assert server.host == "127.0.0.1"
        binary = next(n for n in graph["nodes"] if n["id"] == "binary")
        window = next(p for p in binary["params"] if p["name"] == "window")
        assert window["key"] == "params.window"  # written as ${params.window} in the file
        assert window["schema"]["x-odd"] is True
        assert (window["schema"]["minimum"], window["schema"]["maximum"]) == (3, 1001)
    finally:
        server.stop()


def test_parameters_are_saved_back_with_the_comments(tmp_path: Path) -> None:
    source = tmp_path / "coins.yaml"
    text = (
        (PIPELINES / "coins.yaml")
        .read_text()
        .replace("params:\n", "# tuned in the studio\nparams:\n")
    )
    source.write_text(text)
    save_parameters(source, {"binary.k": -0.3, "params.window": 41})
    saved = source.read_text()
    assert "# tuned in the studio" in saved and "window: 41" in saved
    graph = gv.load_pipeline(source)
    assert graph.nodes["binary"].params["k"] == -0.3 and graph.params["window"] == 41
    copy = save_parameters(source, {"binary.k": -0.2}, tmp_path / "copy.yaml")
    assert gv.load_pipeline(copy).nodes["binary"].params["k"] == -0.2
    # a parameter the file does not write yet: the document is written anew, comments kept
    save_parameters(source, {"binary.method": "sauvola"})
    assert "# tuned in the studio" in source.read_text()
    assert gv.load_pipeline(source).nodes["binary"].params["method"] == "sauvola"
    with pytest.raises(KeyError, match="no node 'nope'"):
        save_parameters(source, {"nope.k": 1})


@pytest.mark.parametrize(
    ("overrides", "line", "before", "after"),
    [
        ({"binary.k": -0.3}, 16, "k: 0.0,", "k: -0.3,"),
        ({"binary.foreground": "dark"}, 16, "foreground: bright}}", "foreground: dark}}"),
        ({"params.window": 41}, 12, "window: 51  # pixels", "window: 41  # pixels"),
        ({"disk.size": 7, "disk.shape": "square"}, 17, "{shape: disk, size: 5}",
         "{shape: square, size: 7}"),
    ],
)  # fmt: skip
def test_a_saved_value_changes_its_own_characters_alone(tmp_path, overrides, line, before, after):
    source = tmp_path / "coins.yaml"
    text = (PIPELINES / "coins.yaml").read_text().replace("window: 51", "window: 51  # pixels")
    source.write_text(text)
    save_parameters(source, overrides)
    old, new = text.splitlines(), source.read_text().splitlines()
    assert len(new) == len(old)
    assert [i for i, (a, b) in enumerate(zip(old, new, strict=True)) if a != b] == [line]
    assert before in old[line] and new[line] == old[line].replace(before, after)
    graph = gv.load_pipeline(source)
    for key, value in overrides.items():
        target, _, param = key.partition(".")
        got = graph.params[param] if target == "params" else graph.nodes[target].params[param]
        assert got == value


def test_a_saved_file_keeps_its_permissions_and_a_new_one_gets_the_default(tmp_path):
    source = tmp_path / "coins.yaml"
    source.write_text((PIPELINES / "coins.yaml").read_text())
    source.chmod(0o640)
    save_parameters(source, {"binary.k": -0.3})
    assert stat.S_IMODE(source.stat().st_mode) == 0o640
    umask = os.umask(0o022)
    os.umask(umask)
    copy = save_parameters(source, {"binary.k": -0.2}, tmp_path / "copy.yaml")
    assert stat.S_IMODE(copy.stat().st_mode) == 0o666 & ~umask
    assert sorted(p.name for p in tmp_path.iterdir()) == ["coins.yaml", "copy.yaml"]


def test_a_value_the_loader_would_read_as_another_is_refused_and_nothing_written(tmp_path):
    source = tmp_path / "coins.yaml"
    text = (PIPELINES / "coins.yaml").read_text()
    source.write_text(text)
    # a new key (the document is written anew, in YAML 1.2) holding YAML 1.1's "no"
    with pytest.raises(
        PipelineError,
        match=r"binary.method in .*coins.yaml: 'no' would be read back from the file as False",
    ):
        save_parameters(source, {"binary.method": "no"})
    assert source.read_text() == text


def test_numpy_scalars_are_saved_as_their_values(tmp_path):
    source = tmp_path / "coins.yaml"
    source.write_text((PIPELINES / "coins.yaml").read_text())
    save_parameters(source, {"binary.k": np.float64(-0.25), "params.window": np.int64(41)})
    graph = gv.load_pipeline(source)
    assert graph.nodes["binary"].params["k"] == -0.25 and graph.params["window"] == 41


def test_the_command_line_reruns_the_tuned_values() -> None:
    text = command_line("pipelines/coins.yaml", {"binary.k": -0.3, "binary.method": "sauvola"},
                        {"image": "coins.png"})  # fmt: skip
    assert text == (
        "graphvision run pipelines/coins.yaml -i image=coins.png "
        "--set binary.k=-0.3 --set binary.method=sauvola"
    )


def test_each_port_type_gets_its_viewer(coins: Session) -> None:
    run = coins.latest_with_values()
    assert run is not None and run.compiled is not None
    steps = run.compiled.steps
    views = {
        (node, port): view_of(steps[node].outputs[port], value)
        for (node, port), value in run.values.items()
    }
    assert views[("labels", "out")] == "labels"
    assert views[("gray", "out")] == "image"
    assert views[("binary", "out")] == "mask"
    assert views[("coins", "count")] == "scalar"
    assert views[("measured", "out")] == "table"
    depth = np.linspace(0.5, 4.0, 64 * 48, dtype=np.float32).reshape(48, 64)
    described = describe_value(gv.FloatImagePort, depth, run.compiled, "x", "out")
    assert described["view"] == "floatmap"
    assert described["range"] == pytest.approx([0.5, 4.0])


def test_a_node_value_is_at_hand_as_soon_as_the_node_finishes(coins: Session) -> None:
    seen: dict[str, bool] = {}

    def listener(event: dict) -> None:
        if event.get("event") == "node" and event["status"] == "computed":
            run, node = coins.find_run(event["run"]), event["node"]
            ports = run.compiled.steps[node].outputs
            held = all((node, port) in run.values for port in ports)
            seen[node] = event["value"] and held and run.status == "running"  # before its end

    coins.listeners.append(listener)
    try:
        coins.change({"binary.k": -0.25})
        coins.wait()
    finally:
        coins.listeners.remove(listener)
    downstream = ["binary", "closed", "filled", "opened", "labels", "measured", "coins", "overlay"]
    assert seen == dict.fromkeys(downstream, True)


def test_a_cached_png_is_served_only_for_the_value_it_was_made_from(coins: Session) -> None:
    """PNGs are cached by the value's id, which CPython reuses once a value is freed."""
    api = _Api(coins)
    run = coins.latest_with_values()
    assert run is not None
    request = SimpleNamespace(path_params={"run": run.id, "node": "gray", "port": "out"})
    fresh = asyncio.run(api.png(request)).body  # type: ignore[arg-type]
    value = run.values[("gray", "out")]
    other = np.zeros(3)  # another live value under the same id, as after a reuse
    api.pngs[(id(value), "gray", "out")] = (_reference(other), b"stale")
    assert asyncio.run(api.png(request)).body == fresh  # type: ignore[arg-type]
    assert fresh.startswith(b"\x89PNG")


def test_saving_where_no_file_can_be_written_answers_in_words(coins: Session, tmp_path) -> None:
    """``save as`` onto a folder: the page hears which file could not be written (not the
    temporary file beside it, nor a server error), and nothing is left behind."""

    async def body() -> dict[str, str]:
        return {"path": str(tmp_path)}  # a folder: no file can take its place

    answer = asyncio.run(_Api(coins).save(SimpleNamespace(json=body)))  # type: ignore[arg-type]
    assert answer.status_code == 400
    assert json.loads(answer.body) == {"error": f"cannot write {tmp_path}: Is a directory"}
    assert list(tmp_path.iterdir()) == []
