"""A batch started by a worker that is importing the client's script (a script without
``if __name__ == "__main__":``): refused, naming the guard (:func:`refuse_in_bootstrap`).

A worker started by ``spawn`` or ``forkserver`` (Dask's own workers, a
replacement for a worker that died, ``processes`` workers from the fork
server) first imports the client's main script, as ``__mp_main__``. A script
that runs its batch at module level, outside the guard, would start that
batch again in every such worker: on Dask the worker never finished starting
and the client's batch waited for it without a word. Python's
``multiprocessing`` refuses to start a process at that moment with the same
test (``current_process()._inheriting``, true while the worker imports the
script); here a batch, or a local Dask cluster, is refused then, with an error
that names the guard. The worker exits with it (its traceback on the
terminal), and the client, whose cluster then did not start, says why
(:func:`guard_hint`).
"""

from __future__ import annotations

import multiprocessing
import re
import sys
from pathlib import Path

from graphvision.errors import GraphvisionError

__all__ = ["UnguardedScriptError", "guard_hint", "refuse_in_bootstrap"]

_GUARD = re.compile(r"""__name__\s*==\s*['"]__main__['"]|['"]__main__['"]\s*==\s*__name__""")
GUARD = 'if __name__ == "__main__":'


class UnguardedScriptError(GraphvisionError, RuntimeError):
    """A worker importing the client's script was made to start a batch (or a cluster)."""


def bootstrapping() -> bool:
    """Whether this process is a worker still importing its client's main script."""
    return bool(getattr(multiprocessing.current_process(), "_inheriting", False))


def refuse_in_bootstrap(what: str) -> None:
    """Raise :class:`UnguardedScriptError` when this process is a worker importing its
    client's script (see the module docstring): ``what`` is what it was about to start."""
    if not bootstrapping():
        return
    script = _main_script() or "the main script"
    raise UnguardedScriptError(
        f"{what} started while this worker process imports {script}, the script of the "
        f"process that started it: the script starts its work again in every worker. Put "
        f"the code that runs it under `{GUARD}` (each worker imports the script first, as "
        "Python's spawn and forkserver start methods do)"
    )


def guard_hint() -> str:
    """For workers that did not start or died (a local Dask cluster's, a process pool's not
    forked): a note naming the guard when the main script, which each spawned worker
    imports first, has none (else nothing)."""
    script = _main_script()
    if script is None:
        return ""
    try:
        text = Path(script).read_text(encoding="utf-8", errors="replace")
    except OSError:
        return ""
    if _GUARD.search(text):
        return ""
    return (
        f"; {script} has no `{GUARD}`: each worker imports it first and, starting its "
        "work again there, stops (put the code that runs the batch or the run under the guard)"
    )


def _main_script() -> str | None:
    """The file a spawned worker imports as the client's main module, if any (none for
    ``python -c``, a notebook or ``python -m package``)."""
    main = sys.modules.get("__mp_main__" if bootstrapping() else "__main__")  # as a worker
    spec = getattr(main, "__spec__", None)
    name = getattr(spec, "name", None)
    if name is not None and (name == "__main__" or name.endswith(".__main__")):
        return None  # a package's __main__: never imported again (multiprocessing.spawn)
    found = getattr(main, "__file__", None)
    return str(found) if isinstance(found, str) else None
