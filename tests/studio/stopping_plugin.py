"""A local plugin for the studio's tests: a node that spins (and says in which process),
and one that ends its own process."""

import os
import time
from pathlib import Path

from graphvision import Float, node


@node("studio_test.spin", cache=False)
def spin(x: Float, *, seconds: float = 0.0, pidfile: str = "") -> Float:
    """Writes its process id to ``pidfile``, keeps a core busy ``seconds``, returns x + seconds."""
    if pidfile:
        Path(pidfile).write_text(str(os.getpid()))
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        pass
    return x + seconds


@node("studio_test.exit", cache=False)
def exit_now(x: Float, *, status: int = 3) -> Float:
    """Ends its own process with ``status`` (os._exit: no exception, no clean-up); 0 returns x."""
    if status:
        os._exit(status)
    return x
