"""``graphvision studio``: tune a pipeline live in the browser (the ``studio`` extra)."""

from __future__ import annotations

import argparse
import sys
import webbrowser

from graphvision.cli.common import (
    UsageError,
    disk_cache,
    load_run_arguments,
)
from graphvision.cli.exits import EXIT_OK

__all__ = ["cmd_studio", "studio_options"]


def studio_options(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--no-browser", action="store_true", help="print the URL only")
    parser.add_argument("--port", type=int, default=0, help="port to listen on (default: free)")
    parser.add_argument(
        "--host",
        default="127.0.0.1",
        help="address to listen on (default 127.0.0.1: this machine only)",
    )


def cmd_studio(args: argparse.Namespace) -> int:
    from graphvision.errors import GraphvisionError

    try:
        from graphvision.studio.server import make_server
        from graphvision.studio.session import Session
    except ImportError as error:  # pragma: no cover - the extra is part of dev
        raise UsageError(str(error)) from None
    if not 0 <= args.port <= 65535:
        raise UsageError(f"--port {args.port}: must be between 0 and 65535")
    graph, registry, overrides, inputs = load_run_arguments(args)
    session = None
    try:
        session = Session(graph, registry, inputs=inputs, overrides=overrides,
                          cache=disk_cache(args), executor=args.executor)  # fmt: skip
        server = make_server(session, args.host, args.port)
    except ImportError as error:
        raise UsageError(str(error)) from None
    except GraphvisionError:
        raise
    except OSError as error:  # (a port in use: refused before its address is printed)
        if session is not None:
            session.close()  # its worker processes end
        raise UsageError(f"--host {args.host} --port {args.port}: {error.strerror}") from None
    print(f"graphvision studio on {graph.name}: {server.url}", file=sys.stderr, flush=True)
    print("Ctrl-C stops it", file=sys.stderr, flush=True)
    session.start()
    if not args.no_browser:
        webbrowser.open(server.url)
    server.serve()
    return EXIT_OK
