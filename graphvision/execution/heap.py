"""Memory a run frees stays with the process: a node's new arrays do not fault page by page.

Why
---
glibc's ``malloc`` gives a large block (128 KiB and more at first) its own ``mmap``, and
gives the free memory at the top of its heap back to the system once there is more of it
than its trim threshold. Its thresholds grow with what the program frees, up to 32 MiB
and 64 MiB, but a run frees each intermediate value after its last reader and every
value when its result is dropped, so the top of the heap came back to the system
between nodes and between runs, and each new array of the next node was handed fresh
pages that the kernel maps on first touch, one fault per 4 KiB page. On ``coins.yaml``
``threshold.local`` (a numba kernel filling four arrays of about 1 MB) took 0.50 ms in a
plain script and 0.83 ms in the engine, the same call: its kernel made about 500 minor
page faults per call in the engine against 375 in the script (``resource.getrusage``,
``ru_minflt``), whose values, kept until the next run overwrote them, held the heap up.
With the thresholds below, 0.48 ms and 0.50 ms.

How
---
:func:`keep_freed_memory` sets, once per process, the thresholds glibc's own rule ends at
(``M_MMAP_THRESHOLD`` 32 MiB, ``M_TRIM_THRESHOLD`` 64 MiB, :manpage:`mallopt(3)`): a
block under 32 MiB comes from the heap, and the heap keeps up to 64 MiB of free memory
at its top, which the next node reuses without a fault. A run calls it when its nodes
run in this process; elsewhere than glibc (no ``mallopt``) it does nothing. The memory
a run's values take is still given back to the allocator as soon as their last reader
has run; only the allocator's own reserve grows, by 64 MiB at most per arena. A Dask
worker, whose nanny sets ``MALLOC_TRIM_THRESHOLD_``, is given the same thresholds by its
first task (:func:`graphvision.execution.dask_worker.keep_freed_memory`).
"""

from __future__ import annotations

import ctypes
import functools

__all__ = ["MMAP_THRESHOLD", "TRIM_THRESHOLD", "keep_freed_memory"]

MMAP_THRESHOLD = 32 * 1024 * 1024
"""Blocks under this come from the heap (glibc's ``DEFAULT_MMAP_THRESHOLD_MAX``, 64-bit)."""

TRIM_THRESHOLD = 2 * MMAP_THRESHOLD
"""Free memory at the top of a heap beyond this goes back to the system (glibc's own
rule: twice the mmap threshold)."""

_M_TRIM_THRESHOLD, _M_MMAP_THRESHOLD = -1, -3  # glibc's <malloc.h>


@functools.cache  # once per process: the thresholds are process-wide
def keep_freed_memory() -> None:
    """Set glibc's ``malloc`` thresholds once for this process (see the module docstring);
    nothing where there is no glibc."""
    try:
        libc = ctypes.CDLL("libc.so.6")
        libc.mallopt(_M_MMAP_THRESHOLD, MMAP_THRESHOLD)
        libc.mallopt(_M_TRIM_THRESHOLD, TRIM_THRESHOLD)
    except (OSError, AttributeError):  # not glibc: nothing to set
        return
