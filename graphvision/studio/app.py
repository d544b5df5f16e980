"""The studio's web application (Starlette): the page, its API and its event stream.

Every request needs the session's token: ``?token=...`` in the URL (as Jupyter prints
it), the ``X-Studio-Token`` header, or the cookie the first tokened request sets; any
other request gets 403. Routes:

``GET /``                               the page
``GET /static/...``                     its scripts, styles and fonts
``GET /api/graph``                      the pipeline (nodes, edges, docs, widgets), runs
``GET /api/events``                     server-sent events: runs and node states
``POST /api/change``                    ``{"overrides": {...}, "inputs": {...}}``: validate,
                                        then run; 422 with every problem if refused
``POST /api/cancel``                    stop the run in flight
``GET /api/runs``                       every run of the session: diff (None: the file's
                                        value, given in ``file``), metrics, states
``GET /api/value/RUN/NODE/PORT``        a value's description (:mod:`.payload`)
``GET /api/png/RUN/NODE/PORT``          its picture; ``/api/raw/...`` its float32 values;
                                        ``/api/rgba/...?step=N`` its picture as RGBA bytes,
                                        N times smaller (made ahead: :mod:`.pictures`)
``POST /api/save``                      ``{"path": optional new file}``: save parameters
``GET /api/command``                    the equivalent ``graphvision run`` command
"""

from __future__ import annotations

import asyncio
import hmac
import json
import time
import weakref
from collections import OrderedDict
from collections.abc import AsyncIterator
from pathlib import Path
from typing import Any

from starlette.applications import Starlette
from starlette.concurrency import run_in_threadpool
from starlette.requests import Request
from starlette.responses import JSONResponse, Response, StreamingResponse
from starlette.routing import Mount, Route
from starlette.staticfiles import StaticFiles
from starlette.types import ASGIApp, Receive, Scope, Send

from graphvision.errors import OutputFolderError, PipelineError
from graphvision.studio.describe import describe_graph
from graphvision.studio.payload import MAX_STEP, png_of, raw_of
from graphvision.studio.pictures import Descriptions, Pictures
from graphvision.studio.saving import command_line, save_parameters
from graphvision.studio.session import Session, StudioRun

__all__ = ["STATIC", "make_app"]

STATIC = Path(__file__).parent / "static"
COOKIE = "graphvision_studio_token"


class TokenGate:
    """ASGI middleware: 403 unless the request carries the token (then a cookie holds it)."""

    def __init__(self, app: ASGIApp, token: str) -> None:
        self.app, self.token = app, token

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] not in ("http", "websocket"):
            await self.app(scope, receive, send)
            return
        request = Request(scope)
        given = (
            request.query_params.get("token")
            or request.headers.get("x-studio-token")
            or request.cookies.get(COOKIE)
            or ""
        )
        if not hmac.compare_digest(given.encode(), self.token.encode()):
            response = Response("403: this studio needs its token (see the URL it printed)", 403)
            await response(scope, receive, send)
            return

        async def send_with_cookie(message: Any) -> None:
            if message["type"] == "http.response.start" and "token" in request.query_params:
                cookie = f"{COOKIE}={self.token}; Path=/; HttpOnly; SameSite=Strict"
                message.setdefault("headers", []).append((b"set-cookie", cookie.encode()))
            await send(message)

        await self.app(scope, receive, send_with_cookie)


def make_app(session: Session, token: str) -> ASGIApp:
    """The studio's ASGI application for ``session``, behind its token."""
    api = _Api(session)
    routes = [
        Route("/", api.page),
        Route("/api/graph", api.graph),
        Route("/api/events", api.events),
        Route("/api/change", api.change, methods=["POST"]),
        Route("/api/cancel", api.cancel, methods=["POST"]),
        Route("/api/runs", api.runs),
        Route("/api/value/{run:int}/{node}/{port}", api.value),
        Route("/api/png/{run:int}/{node}/{port}", api.png),
        Route("/api/raw/{run:int}/{node}/{port}", api.raw),
        Route("/api/rgba/{run:int}/{node}/{port}", api.rgba),
        Route("/api/save", api.save, methods=["POST"]),
        Route("/api/command", api.command),
        Mount("/static", StaticFiles(directory=STATIC), name="static"),
    ]
    return TokenGate(Starlette(routes=routes), token)


class _Api:
    def __init__(self, session: Session) -> None:
        self.session = session
        self.pngs: OrderedDict[tuple[int, str, str], tuple[Any, bytes]] = OrderedDict()
        self.pictures = Pictures(session)
        self.descriptions = Descriptions(session)

    async def page(self, request: Request) -> Response:
        text = (STATIC / "index.html").read_text(encoding="utf-8")
        return Response(text, media_type="text/html")

    async def graph(self, request: Request) -> JSONResponse:
        session = self.session
        found = describe_graph(session.graph, session.compiled, session.inputs)
        found["overrides"] = session.overrides
        found["inputs_given"] = {k: str(v) for k, v in session.inputs.items()}
        found["runs"] = [r.summary() for r in session.runs]
        return JSONResponse(found)

    async def events(self, request: Request) -> StreamingResponse:
        loop = asyncio.get_running_loop()
        queue: asyncio.Queue[dict[str, Any]] = asyncio.Queue()

        def listener(event: dict[str, Any]) -> None:
            loop.call_soon_threadsafe(queue.put_nowait, dict(event))

        async def stream() -> AsyncIterator[str]:
            self.session.listeners.append(listener)
            try:
                yield "retry: 1000\n\n"
                while True:
                    try:
                        event = await asyncio.wait_for(queue.get(), 15.0)
                    except TimeoutError:
                        yield ": keep-alive\n\n"
                        continue
                    if event.get("event") == "closed":  # the server stops
                        return
                    yield f"data: {json.dumps(event, default=str)}\n\n"
            finally:  # the tab closed: forget it (the run goes on for the other tabs)
                self.session.listeners.remove(listener)

        headers = {"Cache-Control": "no-cache", "X-Accel-Buffering": "no"}
        return StreamingResponse(stream(), media_type="text/event-stream", headers=headers)

    async def change(self, request: Request) -> JSONResponse:
        body = await _json_body(request)
        if body is None:
            return JSONResponse({"problems": [{"where": "", "message": "not JSON"}]}, 400)
        try:
            started = await run_in_threadpool(
                self.session.change, body.get("overrides") or {}, body.get("inputs") or {}
            )
        except PipelineError as error:
            problems = [{"where": p.where, "message": p.message} for p in error.problems]
            return JSONResponse({"problems": problems}, 422)
        return JSONResponse({"run": started.id})

    async def cancel(self, request: Request) -> JSONResponse:
        stopped = self.session.cancel()
        return JSONResponse({"cancelled": stopped.id if stopped else None})

    async def runs(self, request: Request) -> JSONResponse:
        return JSONResponse([r.summary() for r in self.session.runs])

    def _value(self, request: Request) -> tuple[StudioRun, str, str, Any, Any] | Response:
        params = request.path_params
        try:
            studio_run = self.session.find_run(params["run"])
        except KeyError as error:
            return JSONResponse({"error": str(error.args[0])}, 404)
        node, port = params["node"], params["port"]
        if (node, port) not in studio_run.values or studio_run.compiled is None:
            message = f"run {studio_run.id} holds no value of {node}.{port}"
            return JSONResponse({"error": message}, 404)
        kind = studio_run.compiled.steps[node].outputs[port]
        return studio_run, node, port, kind, studio_run.values[(node, port)]

    async def value(self, request: Request) -> Response:
        found = self._value(request)
        if isinstance(found, Response):
            return found
        studio_run, node, port = found[:3]
        described = await run_in_threadpool(self.descriptions.describe, studio_run, node, port)
        return JSONResponse(described)

    async def png(self, request: Request) -> Response:
        found = self._value(request)
        if isinstance(found, Response):
            return found
        _, node, port, kind, value = found
        # Keyed by the value's id so that runs sharing a value share its PNG; a freed
        # value's id can be reused, so the entry is taken only if it names this value.
        key = (id(value), node, port)
        cached = self.pngs.get(key)
        began = time.perf_counter()
        data: bytes | None = None
        if cached is not None and _same(cached[0], value):
            data = cached[1]
        else:
            data = await run_in_threadpool(png_of, kind, value)
            if data is None:
                return JSONResponse({"error": f"{kind.type_name()} has no picture"}, 404)
            self.pngs[key] = (_reference(value), data)
            while len(self.pngs) > 64:
                self.pngs.popitem(last=False)
        timing = f"encode;dur={(time.perf_counter() - began) * 1e3:.1f}"
        headers = {"Cache-Control": "no-store", "Server-Timing": timing}
        return Response(data, media_type="image/png", headers=headers)

    async def raw(self, request: Request) -> Response:
        found = self._value(request)
        if isinstance(found, Response):
            return found
        _, _, _, kind, value = found
        raw = raw_of(kind, value)
        if raw is None:
            return JSONResponse({"error": "no array values for this type"}, 404)
        data, shape = raw
        headers = {"X-Shape": ",".join(map(str, shape)), "Cache-Control": "no-store"}
        return Response(data, media_type="application/octet-stream", headers=headers)

    async def rgba(self, request: Request) -> Response:
        found = self._value(request)
        if isinstance(found, Response):
            return found
        studio_run, node, port = found[:3]
        text = request.query_params.get("step", "1")
        if not text.isdigit() or not 1 <= int(text) <= MAX_STEP:
            message = f"step={text!r}: must be a whole number from 1 to {MAX_STEP}"
            return JSONResponse({"error": message}, 400)
        began = time.perf_counter()
        self.pictures.wanted(studio_run.id, node, port, int(text))
        making = self.pictures.future(studio_run, node, port, int(text))
        picture = None if making is None else await asyncio.wrap_future(making)
        if picture is None:
            return JSONResponse({"error": "no picture for this type"}, 404)
        data, shape, seconds = picture
        waited = (time.perf_counter() - began) * 1e3
        headers = {
            "X-Shape": ",".join(map(str, shape)),
            "Cache-Control": "no-store",
            # encode: what this request waited for the picture (made ahead when the page
            # showed the port before); made: what making it took (on the picture thread)
            "Server-Timing": f"encode;dur={waited:.1f}, made;dur={seconds * 1e3:.1f}",
        }
        return Response(data, media_type="application/octet-stream", headers=headers)

    async def save(self, request: Request) -> JSONResponse:
        body = await _json_body(request) or {}
        source = self.session.graph.source
        if not source or not Path(source).is_file():
            return JSONResponse({"error": "this pipeline was not read from a file"}, 400)
        target = Path(body["path"]) if body.get("path") else None
        try:
            saved = await run_in_threadpool(
                save_parameters, Path(source), self.session.overrides, target
            )
        except (KeyError, PipelineError, OutputFolderError, OSError) as error:
            return JSONResponse({"error": str(error)}, 400)  # (a file that cannot be written)
        return JSONResponse({"saved": str(saved)})

    async def command(self, request: Request) -> JSONResponse:
        session = self.session
        text = command_line(session.graph.source or "PIPELINE.yaml", session.overrides,
                            session.inputs)  # fmt: skip
        return JSONResponse({"command": text})


async def _json_body(request: Request) -> dict[str, Any] | None:
    try:
        body = await request.json()
    except ValueError:
        return None
    return body if isinstance(body, dict) else None


def _reference(value: Any) -> Any:
    """A weak reference to ``value`` where it takes one (arrays do), else ``value`` itself."""
    try:
        return weakref.ref(value)
    except TypeError:
        return value


def _same(reference: Any, value: Any) -> bool:
    """Whether ``reference`` (from :func:`_reference`) still names ``value``."""
    held = reference() if isinstance(reference, weakref.ref) else reference
    return held is value
