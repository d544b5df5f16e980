"""What a run must hold at least, estimated from its inputs' shapes before it starts
(issue 29 item 2).

The pixel budget (:mod:`graphvision.values.budget`) bounds each image a run reads;
this refuses a run that cannot fit as a whole, before its first node runs, instead of
letting it run out of memory minutes later. The run is played in its order without
computing anything: every value is alive from the step that makes it until its last
reader has run (outputs to the end), as the run keeps them. Each value is priced at
what it takes at least when nodes keep the size of their input:

* a graph input at its own size, once read;
* a node output of an array type (images, masks, labels, disparities...) at the pixels
  of the largest array input × its type's narrowest dtype, × the input's channels for
  a type that is ``H×W×C`` only (a colour image); nodes that shrink an image (a
  downsampled pyramid level, a crop) are the exception to "at least";
* records, tables and scalars as nothing.

With several nodes running at once, each of the others adds the widest output. The
estimate leaves out what nodes take while they run (their temporaries: 2 to 20 times
their input on the shipped pipelines), so a run refused cannot fit, and a run accepted
may still need more. The limit is ``max_memory`` (``--max-memory``, the
``GRAPHVISION_MAX_MEMORY`` environment variable), else the memory the system says is
available (``MemAvailable`` in ``/proc/meminfo``; no check where it cannot be read).
Inputs given as ``sample:NAME`` are loaded only when a node reads them: they are not
counted (scikit-image's samples are small).
"""

from __future__ import annotations

import os
import time
import weakref
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from graphvision.compiler.compile import CompiledGraph, Schedule
from graphvision.errors import InputError
from graphvision.execution.executors import executor_width
from graphvision.values.budget import pixels_of
from graphvision.values.ports import ArrayPort, PortType

__all__ = [
    "MEMORY_VARIABLE",
    "Estimate",
    "check_peak_memory",
    "environment_memory",
    "estimate_peak",
    "memory_allowed",
    "running_at_once",
]

MEMORY_VARIABLE = "GRAPHVISION_MAX_MEMORY"


@dataclass(frozen=True)
class Estimate:
    """What a run holds at least at its peak (bytes), and what that was derived from."""

    peak: int
    largest_input: str
    largest_bytes: int
    live: int
    running: int


def _array_bytes(value: Any) -> int:
    arrays = [value] if isinstance(value, np.ndarray) else []
    return sum(a.nbytes for a in arrays)


def _output_bytes(kind: type[PortType], pixels: int, channels: int) -> int:
    """An upper bound of a node output of type ``kind`` from inputs of ``pixels``."""
    if not issubclass(kind, ArrayPort):
        return 0
    narrowest = min((np.dtype(t).itemsize for t in kind.dtypes), default=1)
    depth = channels if kind.ndims == (3,) else 1
    return pixels * depth * narrowest


def estimate_peak(
    compiled: CompiledGraph, schedule: Schedule, values: dict[str, Any], running: int
) -> Estimate | None:
    """What the run holds at least at its peak (None when no input is an array)."""
    shapes = {n: v.shape for n, v in values.items() if isinstance(v, np.ndarray) and v.ndim}
    if not shapes:
        return None
    largest = max(shapes, key=lambda n: pixels_of(shapes[n]))
    pixels, shape = pixels_of(shapes[largest]), shapes[largest]
    channels = shape[2] if len(shape) == 3 and 1 <= shape[2] <= 4 else 1
    sizes: dict[tuple[str, str], int] = {
        (n, ""): _array_bytes(values[n]) for n in schedule.inputs if n in values
    }
    left = dict(schedule.readers)
    pinned = set(compiled.outputs.values())
    live = sum(sizes.values())
    peak, widest = live, 0
    for name in schedule.steps:
        step = compiled.steps[name]
        made = {(name, p): _output_bytes(k, pixels, channels) for p, k in step.outputs.items()}
        sizes.update(made)
        live += sum(made.values())
        widest = max([widest, *made.values()])
        peak = max(peak, live)
        for source in set(step.inputs.values()):
            left[source] = left.get(source, 1) - 1
            if left[source] <= 0 and source not in pinned:
                live -= sizes.pop(source, 0)
    steps = min(running, len(schedule.steps))
    total = peak + (steps - 1) * widest if steps else peak
    return Estimate(total, largest, _array_bytes(values[largest]), peak, steps)


def running_at_once(executor: Any, workers: int | None) -> int:
    """Nodes the executor may run at once: 1 on ``sync``, else its workers."""
    if isinstance(executor, str):
        return 1 if executor == "sync" else workers or os.cpu_count() or 1
    return executor_width(executor)


def memory_allowed(max_memory: int | None = None) -> tuple[int | None, str]:
    """Bytes a run may take (``max_memory``, the environment's, else what is available;
    None when unknown) and where that figure comes from."""
    if max_memory is not None:
        return max_memory, "allowed (max_memory)"
    given = environment_memory()
    if given is not None:
        return given, "allowed (--max-memory)"
    try:
        for line in Path("/proc/meminfo").read_text().splitlines():
            if line.startswith("MemAvailable:"):
                return int(line.split()[1]) * 1024, "available"
    except OSError:
        pass
    return None, ""


def environment_memory() -> int | None:
    """The bytes :data:`MEMORY_VARIABLE` allows a run (None when it is unset).

    Raises
    ------
    InputError
        When it is not a number of bytes above 0, naming it and its value.
    """
    text = os.environ.get(MEMORY_VARIABLE, "")
    if not text:
        return None
    try:
        value = int(float(text))
    except (ValueError, OverflowError):
        value = 0
    if value <= 0:  # (-1 refused every run as over its memory)
        raise InputError(f"{MEMORY_VARIABLE}={text!r} is not a number of bytes above 0")
    return value


def _surely_available(peak: int) -> bool:
    """Whether ``peak`` bytes are below the memory available for sure, without reading
    ``/proc/meminfo`` (0.1-0.2 ms a run, a tenth of the engine's cost on a 12 ms pipeline):
    the kernel's ``MemAvailable`` is at least its free memory less its reserves, far under a
    sixteenth of the memory (``sysinfo``, through ``os.sysconf``; the memory's size read
    once per process, a system call less per run: the reserves are set from it at boot, so
    memory added since only widens the margin). A peak under half the margin found less
    than :data:`FRESH_SECONDS` ago is settled by it, without a system call (the runs of a
    script's loop, a sweep's or a batch's: half of the free memory is not taken in a
    second unnoticed more than during the run itself). Never without a limit from the
    environment, which is checked as given."""
    if os.environ.get(MEMORY_VARIABLE):
        return False
    now = time.monotonic()  # (no system call: the vDSO's clock)
    if _MARGIN and now - _MARGIN[0] < FRESH_SECONDS and 2 * peak <= _MARGIN[1]:
        return True
    try:
        page = _PAGE_SIZE or 0
        free = os.sysconf("SC_AVPHYS_PAGES") * page
        total = _PHYSICAL[0] if _PHYSICAL else _physical(os.sysconf("SC_PHYS_PAGES") * page)
    except (ValueError, OSError):  # a system without these names
        return False
    _MARGIN[:] = (now, free - total // 16)
    return peak <= _MARGIN[1]


FRESH_SECONDS = 1.0
"""How long the free memory read for one run settles the peaks of the next ones that take
at most half of it (:func:`_surely_available`)."""

_PHYSICAL: list[int] = []  # the memory's size, read at the first run
_MARGIN: list[Any] = []  # when the free memory was last read, and it less the reserves


def _physical(total: int) -> int:
    _PHYSICAL.append(total)
    return total


def _page_size() -> int | None:
    try:
        return os.sysconf("SC_PAGE_SIZE")
    except (ValueError, OSError):
        return None


_PAGE_SIZE = _page_size()


def check_peak_memory(
    compiled: CompiledGraph,
    schedule: Schedule,
    values: dict[str, Any],
    running: int,
    max_memory: int | None = None,
) -> Estimate | None:
    """Refuse a run that must hold more than :func:`memory_allowed`, before it starts.

    Raises
    ------
    InputError
        Naming the estimate, what it comes from, what is allowed and what to do.
    """
    estimate = _known_estimate(compiled, schedule, values, running)
    if max_memory is None and _surely_available(estimate.peak if estimate else 0):
        return estimate
    allowed, where = memory_allowed(max_memory)
    if estimate is None or allowed is None or estimate.peak <= allowed:
        return estimate
    shape = " × ".join(str(n) for n in values[estimate.largest_input].shape)
    raise InputError(
        f"this run cannot fit: it must hold at least {_gib(estimate.peak)} at once "
        f"(estimated before it starts from input '{estimate.largest_input}', {shape}, "
        f"{_gib(estimate.largest_bytes)}: the values alive at once with "
        f"{estimate.running} node(s) running), and {_gib(allowed)} is {where}. Use a "
        "smaller input, fewer --workers, or --max-memory SIZE (max_memory= in Python)"
    )


_ESTIMATES: dict[tuple[Any, ...], tuple[Any, Any, Estimate | None]] = {}
"""The estimates of the last runs, by graph, schedule, the array inputs' shapes and dtypes and
the nodes running at once (all it depends on): the runs of one compiled graph on inputs of
one size (a batch, a sweep, a script calling ``run`` in a loop) play the run through once.
The memory allowed is read for every run."""


def _known_estimate(
    compiled: CompiledGraph, schedule: Schedule, values: dict[str, Any], running: int
) -> Estimate | None:
    """:func:`estimate_peak`, kept for runs of the same graph and schedule objects (held
    weakly: a key whose objects are gone never matches) on arrays of the same shapes."""
    shapes = tuple(
        (n, v.shape, v.dtype.str) for n, v in values.items() if isinstance(v, np.ndarray)
    )
    key = (id(compiled), id(schedule), shapes, running)
    known = _ESTIMATES.get(key)
    if known is not None and known[0]() is compiled and known[1]() is schedule:
        return known[2]
    estimate = estimate_peak(compiled, schedule, values, running)
    if len(_ESTIMATES) > 32:
        _ESTIMATES.clear()
    _ESTIMATES[key] = (weakref.ref(compiled), weakref.ref(schedule), estimate)
    return estimate


def _gib(count: int) -> str:
    """A byte count in the largest unit that keeps it at least 0.25 (1 KiB, not '0.0 MiB')."""
    for unit, size in (("GiB", 2**30), ("MiB", 2**20), ("KiB", 2**10)):
        if count >= size // 4:
            return f"{count / size:.2f} {unit}" if unit == "GiB" else f"{count / size:.1f} {unit}"
    return f"{count} bytes"
