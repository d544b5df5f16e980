"""Serving the studio: uvicorn on 127.0.0.1 (unless a host is given), a random token.

:func:`studio` is ``gv.studio``: it starts the server in a background thread and
returns a :class:`StudioServer` (shown inline in a notebook as the page in a frame);
the ``graphvision studio`` command serves in the foreground until Ctrl-C.
"""

from __future__ import annotations

import secrets
import socket
import threading
import time
import webbrowser
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from graphvision.graph.model import Graph
from graphvision.nodes.registry import Registry
from graphvision.studio.session import Session

__all__ = ["StudioServer", "studio"]

MISSING_EXTRA = (
    "the studio needs the 'studio' extra (Starlette, uvicorn, ruamel.yaml): "
    "pip install 'graphvision[studio]'"
)


@dataclass(eq=False)
class StudioServer:
    """A running studio: its session, its URL (with the token), and how to stop it."""

    session: Session
    host: str
    port: int
    token: str
    server: Any = field(repr=False, default=None)
    thread: threading.Thread | None = field(repr=False, default=None)
    bound: socket.socket | None = field(repr=False, default=None)  # its port, held open

    def serve(self) -> None:
        """Serve until stopped (in this thread), on the socket bound for its port."""
        self.server.run(sockets=[self.bound] if self.bound is not None else None)

    @property
    def url(self) -> str:
        shown = f"[{self.host}]" if ":" in self.host else self.host
        return f"http://{shown}:{self.port}/?token={self.token}"

    def stop(self) -> None:
        """Stop serving: the run in flight is cancelled, the worker processes end."""
        self.session.emit({"event": "closed"})  # event streams end, so shutting down is quick
        if self.server is not None:
            self.server.should_exit = True
        if self.thread is not None:
            self.thread.join(10)
        self.session.close()

    def _repr_html_(self) -> str:
        return (
            f'<p>graphvision studio: <a href="{self.url}" target="_blank">{self.url}</a></p>'
            f'<iframe src="{self.url}" style="width:100%;height:640px;border:1px solid #ccc">'
            "</iframe>"
        )


def make_server(session: Session, host: str = "127.0.0.1", port: int = 0) -> StudioServer:
    """A server for ``session`` (not started), its port bound; port 0 picks a free one.
    OSError when the port cannot be had (in use)."""
    try:
        import uvicorn

        from graphvision.studio.app import make_app
    except ImportError as error:
        raise ImportError(f"{MISSING_EXTRA} ({error})") from None
    token = secrets.token_urlsafe(24)
    # bound here and kept: a port probed and let go can be taken before use, and a port in
    # use is refused now (OSError), before its address is printed or a browser opened
    bound = socket.socket(socket.AF_INET6 if ":" in host else socket.AF_INET)
    try:
        bound.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)  # (as uvicorn's own)
        bound.bind((host, port))
    except OSError:
        bound.close()
        raise
    port = bound.getsockname()[1]
    config = uvicorn.Config(
        make_app(session, token), host=host, port=port, log_level="warning", lifespan="off",
        timeout_graceful_shutdown=1,
    )  # fmt: skip
    return StudioServer(session, host, port, token, uvicorn.Server(config), bound=bound)


def serve_in_background(studio_server: StudioServer, timeout: float = 20.0) -> StudioServer:
    """Start serving in a daemon thread; return once the server accepts connections."""
    thread = threading.Thread(target=studio_server.serve, daemon=True, name="studio")
    thread.start()
    studio_server.thread = thread
    deadline = time.monotonic() + timeout
    while not studio_server.server.started:
        if not thread.is_alive() or time.monotonic() > deadline:
            raise RuntimeError(f"the studio could not start on {studio_server.host}:"
                               f"{studio_server.port}")  # fmt: skip
        time.sleep(0.02)
    return studio_server


def studio(
    graph: Graph | str | Path,
    *,
    inputs: dict[str, Any] | None = None,
    overrides: dict[str, Any] | None = None,
    registry: Registry | None = None,
    host: str = "127.0.0.1",
    port: int = 0,
    open_browser: bool = False,
    run: bool = True,
) -> StudioServer:
    """Open a pipeline in graphvision studio (a local web page) and return the server.

    Parameters
    ----------
    graph : Graph, str or Path
        The pipeline, or the path of its YAML file (parameters can be saved back to it).
    inputs, overrides : dict, optional
        Graph inputs and ``node.param`` overrides to start from.
    registry : Registry, optional
        Defaults to the installed plugins plus the graph's ``plugins:``.
    host, port : str, int
        Where to listen: 127.0.0.1 and a free port by default.
    open_browser : bool
        Open the page in the default browser.
    run : bool
        Start a first run at once.

    Returns
    -------
    StudioServer
        ``.url`` (with its token), ``.session`` and ``.stop()``; shown inline in a notebook.
    """
    from graphvision.graph.pipeline_file import load_pipeline
    from graphvision.nodes.plugins import discover_for

    if not isinstance(graph, Graph):
        graph = load_pipeline(graph)
    session = Session(graph, registry or discover_for(graph), inputs=inputs, overrides=overrides)
    studio_server = serve_in_background(make_server(session, host, port))
    if run:
        session.start()
    if open_browser:
        webbrowser.open(studio_server.url)
    return studio_server
