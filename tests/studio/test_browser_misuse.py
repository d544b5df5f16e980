"""The studio's page when things go wrong, in Debian's Chromium (Playwright): a worker
killed with ``kill -9``, the cancel button on a node that would spin for ten minutes, an
input file deleted while the studio runs. The page says what happened, naming the node or
the file; the server keeps serving and the next change runs."""

from __future__ import annotations

import os
import re
import signal
import time
from pathlib import Path

import imageio.v3 as iio
import numpy as np
import pytest

pytest.importorskip("starlette")

import graphvision as gv
from graphvision.studio.server import studio

PLUGIN = Path(__file__).parent / "stopping_plugin.py"
TOY = Path(__file__).parents[1] / "fixtures" / "toy.py"


@pytest.fixture(scope="module")
def registry() -> gv.Registry:
    return gv.discover([PLUGIN, TOY])


def _spinning(registry: gv.Registry, pidfile: Path):
    graph = gv.Graph("spinning")
    graph.input("x", "Float", default=1.0)
    graph.add("spin", "studio_test.spin", x="x",
              params={"seconds": 600.0, "pidfile": str(pidfile)})  # fmt: skip
    graph.output("y", "spin")
    return studio(graph, registry=registry)


def _pid(pidfile: Path) -> int:
    deadline = time.monotonic() + 120  # a cold worker imports numpy and the plugins first
    while not pidfile.exists() or not pidfile.read_text():
        assert time.monotonic() < deadline
        time.sleep(0.02)
    return int(pidfile.read_text())


def _ended(pid: int) -> bool:
    deadline = time.monotonic() + 10.0  # the node would spin for ten minutes
    while time.monotonic() < deadline:
        try:
            state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
        except FileNotFoundError:
            return True
        if state in ("Z", "X"):
            return True
        time.sleep(0.01)
    return False


def _recorded(studio_run, node: str) -> str:
    """The node's status in the run's record once its run thread has ended: the page hears
    "cancelled" when the button is pressed, the record hears of the killed worker after."""
    deadline = time.monotonic() + 30.0
    while studio_run.nodes[node].get("status") == "running" and time.monotonic() < deadline:
        time.sleep(0.01)
    return studio_run.nodes[node]["status"]


def _status(page, status: str) -> str:
    page.wait_for_selector(f"#run-status[data-status={status}]", timeout=60_000)
    return page.inner_text("#run-status")


def test_the_page_names_the_node_whose_worker_died_and_the_next_change_runs(
    browser, registry, tmp_path: Path
) -> None:
    server = _spinning(registry, tmp_path / "pid")
    try:
        page = browser.new_page(viewport={"width": 1400, "height": 900})
        page.goto(server.url)
        pid = _pid(tmp_path / "pid")
        os.kill(pid, signal.SIGKILL)
        said = _status(page, "failed")
        assert re.search(
            r"run 1 failed in \d+ ms: node 'spin' \(op studio_test.spin\) failed: "
            rf"WorkerDiedError: the worker process running this node \(pid {pid}\) died: "
            r"killed by signal 9 \(SIGKILL\); a new worker took its place",
            said,
        ), said
        page.click("[data-node=spin]")
        box = page.locator("[data-inspect=spin] [data-param=seconds] input.gv-number")
        box.fill("0.25")
        box.press("Enter")
        page.wait_for_selector("body[data-painted-run='2']", timeout=60_000)
        assert float(page.inner_text("[data-output=y] .gv-scalar")) == 1.25
        assert server.session.runs[-1].status == "done"
    finally:
        server.stop()


def test_a_runs_list_asked_for_before_the_run_ended_does_not_undo_its_end(
    browser, registry, tmp_path: Path
) -> None:
    """The page asks for the runs list (``api/runs``) as it opens; the answer, made while run
    1 was running, may arrive after the run's end came by the event stream (another
    connection). Here every such answer is held until the page has shown the end: the
    older answer must not put the header back to "running" (it did, and the CI run that
    checked a killed worker's message timed out waiting for "failed")."""
    server = _spinning(registry, tmp_path / "pid")
    held: list[tuple[object, object]] = []
    holding = [True]

    def hold(route) -> None:
        if holding[0]:
            held.append((route, route.fetch()))  # the server's answer now, delivered later
        else:
            route.continue_()

    try:
        page = browser.new_page()
        errors: list[object] = []
        page.on("pageerror", lambda error: errors.append(error))  # (a run lacked its diff)
        page.route("**/api/runs", hold)
        page.goto(server.url)
        pid = _pid(tmp_path / "pid")
        while not held:  # the page has asked, and the server answered "running"
            page.wait_for_timeout(20)
        os.kill(pid, signal.SIGKILL)
        assert _status(page, "failed").startswith("run 1 failed")
        holding[0] = False
        while held:
            route, answer = held.pop(0)
            page.evaluate("document.querySelector('#runs > table')?.setAttribute('data-old', '')")
            route.fulfill(response=answer)
            page.wait_for_selector("#runs > table:not([data-old])", timeout=60_000)
            assert page.get_attribute("#run-status", "data-status") == "failed"
        assert page.inner_text("#runs tr[data-run='1'] td:nth-child(4)") == "failed"
        assert not errors, errors
    finally:
        holding[0] = False
        for route, answer in held:
            route.fulfill(response=answer)
        server.stop()


def test_the_cancel_button_ends_the_running_node(browser, registry, tmp_path: Path) -> None:
    server = _spinning(registry, tmp_path / "pid")
    try:
        page = browser.new_page()
        page.goto(server.url)
        pid = _pid(tmp_path / "pid")
        page.wait_for_selector("#cancel:not([disabled])")
        page.click("#cancel")
        assert _status(page, "cancelled").startswith("run 1 cancelled")
        assert _ended(pid)  # not after ten minutes: the node's worker was killed
        assert page.get_attribute("[data-node=spin]", "data-state") == "stale"
        assert _recorded(server.session.runs[-1], "spin") == "stopped"
    finally:
        server.stop()


def test_an_input_deleted_while_the_studio_runs_is_named(browser, registry, tmp_path: Path) -> None:
    picture = tmp_path / "scene.png"
    iio.imwrite(picture, np.zeros((8, 8), np.uint8))
    graph = gv.Graph("counting")
    graph.input("image", "Image", default=str(picture))
    graph.add("n", "toy.count", image="image")
    graph.output("n", "n")
    server = studio(graph, registry=registry)
    try:
        page = browser.new_page()
        page.goto(server.url)
        page.wait_for_selector("body[data-painted-run='1']", timeout=60_000)
        picture.unlink()
        page.click("[data-node=image]")
        page.fill("[data-input=image]", str(picture))  # the same path: ask for a run
        page.dispatch_event("[data-input=image]", "change")
        said = _status(page, "failed")
        assert re.search(rf"run 2 failed.*: input 'image': no such file: {picture}", said), said
        iio.imwrite(picture, np.zeros((4, 4), np.uint8))  # the server kept serving
        page.fill("[data-input=image]", str(picture))
        page.dispatch_event("[data-input=image]", "change")
        page.wait_for_selector("body[data-painted-run='3']", timeout=60_000)
        # the count of the new picture (under a loaded CI, once, the card read '' at the
        # moment run 3 was marked painted: the value it settles on is what is checked)
        shown = "document.querySelector('[data-output=n] .gv-scalar')?.innerText === '16'"
        page.wait_for_function(shown, timeout=10_000)
    finally:
        server.stop()
