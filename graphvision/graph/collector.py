"""The cyclic garbage collector paused while validation builds a graph.

Parsing a pipeline file and compiling a graph allocate a handful of
containers per node (mappings, declarations, references, steps), every one
of them reachable until the graph is dropped. CPython's generational
collector runs a young-generation pass every 700 net allocations and, as the
survivors pile up, older-generation passes that walk all of them again: on a
100,000-node file the walks cost a third of the validation time and find
nothing. Validation runs no node code, so pausing the collector for it leaves
no garbage behind that reference counting would not free.
"""

from __future__ import annotations

import gc
from collections.abc import Iterator
from contextlib import contextmanager

__all__ = ["collector_paused"]


@contextmanager
def collector_paused() -> Iterator[None]:
    """Disable ``gc`` for the block, then restore it as it was (also on an error)."""
    enabled = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if enabled:
            gc.enable()
