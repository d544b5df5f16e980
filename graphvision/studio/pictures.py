"""Pictures and descriptions of a session's values for the page, ahead of the page's request.

A picture (:func:`~graphvision.studio.payload.rgba_of`) is made once per run, node and
port and kept for the last few. A port whose picture the page has asked for before is
the one it shows: when its node finishes in a later run (the session's ``node`` event
with a value), its pictures (the preview, then the picture, as the page asked for them
last time) are made at once on a thread of their own, while the event
travels to the page and the page asks for the value's description, so the page's request
for the picture finds it made, or part made.

A value's description (:func:`~graphvision.studio.payload.describe_value`, well under a
millisecond) rides its node's ``node`` event (:class:`Descriptions`) once the page has
asked for that port's description: the page then asks for the pictures at once and for no
description, and its few connections to the server are left to the pictures.
"""

from __future__ import annotations

import json
import threading
import time
from collections import OrderedDict
from concurrent.futures import Future, ThreadPoolExecutor
from typing import Any

from graphvision.studio.payload import describe_value, rgba_of
from graphvision.studio.session import Session, StudioRun

__all__ = ["KEPT_PICTURES", "PUSHED_BYTES", "Descriptions", "Pictures"]

KEPT_PICTURES = 16
PUSHED_BYTES = 256 * 1024  # a larger description (a big table, a cloud) is asked for
Picture = tuple[bytes, list[int], float]  # RGBA bytes, [H, W], seconds it took to make


class Pictures:
    """The RGBA pictures of ``session``'s values (see the module docstring)."""

    def __init__(self, session: Session) -> None:
        self.session = session
        self.made: OrderedDict[tuple[int, str, str, int], Future] = OrderedDict()
        # port -> the last run the page asked for its picture, and the steps it asked for
        self.shown: dict[tuple[str, str], tuple[int, set[int]]] = {}
        self.lock = threading.Lock()
        self.pool = ThreadPoolExecutor(1, thread_name_prefix="studio-picture")
        session.listeners.append(self.on_event)

    def on_event(self, event: dict[str, Any]) -> None:
        """A node's value reached its run: make the pictures the page shows of it."""
        if event.get("event") != "node" or not event.get("value"):
            return
        studio_run = self.session.find_run(event["run"])
        if studio_run.compiled is None or studio_run.stop:
            return
        for port in studio_run.compiled.steps[event["node"]].outputs:
            _, steps = self.shown.get((event["node"], port), (0, set()))
            for step in sorted(steps, reverse=True):  # the preview first
                self.future(studio_run, event["node"], port, step)

    def future(self, studio_run: StudioRun, node: str, port: str, step: int = 1) -> Future | None:
        """The picture being made, or made (None: the run holds no such value); ``step``: a
        preview that many times smaller (:func:`~graphvision.studio.payload.rgba_of`)."""
        key = (studio_run.id, node, port, step)
        with self.lock:
            found = self.made.get(key)
            if found is not None:
                self.made.move_to_end(key)
                return found
            value = studio_run.values.get((node, port))
            if value is None or studio_run.compiled is None:
                return None
            kind = studio_run.compiled.steps[node].outputs[port]
            found = self.made[key] = self.pool.submit(_made, kind, value, step)
            while len(self.made) > KEPT_PICTURES:
                self.made.popitem(last=False)
        return found

    def wanted(self, run: int, node: str, port: str, step: int) -> None:
        """The page shows this port of ``run`` at ``step`` (a preview, then the picture):
        make the same pictures as soon as each later run computes its value."""
        asked, steps = self.shown.get((node, port), (0, set()))
        if run > asked:
            asked, steps = run, set()
        if run == asked:
            steps.add(step)
            self.shown[(node, port)] = (asked, steps)


def _made(kind: Any, value: Any, step: int) -> Picture | None:
    began = time.perf_counter()
    picture = rgba_of(kind, value, step)
    if picture is None:
        return None
    return picture[0], picture[1], time.perf_counter() - began


class Descriptions:
    """The descriptions of ``session``'s values, pushed with their node's event to the page
    once it has asked for the port's description (see the module docstring)."""

    def __init__(self, session: Session) -> None:
        self.session = session
        self.asked: set[tuple[str, str]] = set()  # ports whose description the page asked for
        session.describer = self.of_node

    def describe(self, studio_run: StudioRun, node: str, port: str) -> dict[str, Any]:
        """The description of a value the run holds (the page's request: pushed from now on)."""
        assert studio_run.compiled is not None
        self.asked.add((node, port))
        kind = studio_run.compiled.steps[node].outputs[port]
        value = studio_run.values[(node, port)]
        described = describe_value(kind, value, studio_run.compiled, node, port)
        described["run"] = studio_run.id
        return described

    def of_node(self, studio_run: StudioRun, node: str) -> dict[str, Any]:
        """The descriptions of ``node``'s outputs in ``studio_run`` the page asked for before,
        by port; one that fails, is not plain JSON or is larger than PUSHED_BYTES is left
        out (the page asks for it, and is told what went wrong)."""
        found: dict[str, Any] = {}
        if studio_run.compiled is None:
            return found
        for port in studio_run.compiled.steps[node].outputs:
            if (node, port) not in self.asked or (node, port) not in studio_run.values:
                continue
            try:
                described = self.describe(studio_run, node, port)
                size = len(json.dumps(described, allow_nan=False))
            except Exception:  # a nicety: the page's own request says why
                continue
            if size <= PUSHED_BYTES:
                found[port] = described
        return found
