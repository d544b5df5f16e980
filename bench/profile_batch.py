"""Where a batch file's time goes: the engine's cost per file beside the nodes' compute.

A ``sync`` batch of coins images (as ``bench_batch.py`` makes them, output
``count``) runs with ``time.perf_counter`` around the functions that do each part
of the engine's work (no profiler: a wrapper costs about a microsecond a call,
where ``cProfile`` slowed Python-heavy parts several times more than array
kernels). Each part's wall time, divided by the files, gives milliseconds per file:

- compute: the node functions themselves;
- planning: compiling the graph, keying the steps, the cache plan;
- read: reading and decoding the input image file (its bytes read whole and
  hashed for the provenance, its header checked against the pixel budget, then
  its pixels: one Pillow handle for a PNG);
- hashing: content keys of the inputs, SHA-256 of the files written
  (``record.json``'s ``file_sha256``; the input file's is taken as it is read);
- transport: port types' encode/decode (cache entries, values to and from
  other processes);
- record: the run's provenance (versions, git state) and ``record.json``;
- report: ``report.md`` and ``report.html``, their pictures included;
- thumbnails: the pictures' thumbnails and their PNG bytes (inside the report);
- outputs: the outputs' files (PNG, ``.npy``, JSON);
- write: the whole of a file's folder (``finish_item``: outputs, digests,
  record, pages, moving them in place).

The last column runs the first batch with its folders in memory (``/dev/shm``,
where there is one): what the disk adds is the difference. On this project's
cloud VM creating a file or a folder cost 0.3-1 ms of CPU (and removing a
folder 0.2-3 ms of wall time: the disk discards freed blocks), so a coins
file's folder (the folder, ``count.json``, ``record.json``, ``report.md``,
``report.html``) cost 4-5 ms of the engine's 6-7 ms CPU, where in memory the
whole engine cost about 1 ms. Where that CPU goes (``perf record -g`` of a loop
making files): ext4 without a journal (this VM's) does not reuse an inode freed in
the last 1-6 minutes, and its allocator (``find_inode_bit``) passes over each such
inode of the block group (``recently_deleted``, a buffer looked up for each), so a
file made where many were just removed (a batch's temporary
folders, other benchmarks on the same disk, a claim file made and removed per
batch file) costs more the more were removed: one more reason to make and remove
nothing per file on the disk that the folder does not keep (the stop flag's claims
are made in memory, ``graphvision.execution.batch_stop``).

A part is timed from its outermost call only (a part that calls itself is not
counted twice); parts overlap where one calls another (thumbnails are inside the
report, the report and outputs inside write). "engine" is the whole file less
its compute. Wall time: run it on a quiet machine, and read ratios within one run.

:func:`waits` runs the count batch on ``sync`` and on threads (two files at once), its
folders in memory, timing each part's wall and CPU (``time.thread_time``) in each thread:
in the threads batch, a part's wall less its CPU is what it waited, for the GIL or, on a
loaded machine, for a core. Each file's Python holds the GIL, and each system call
releases it and takes it again (a wait when the other file's thread holds it):
:func:`system_calls` counts them per file, by name (``strace -f``, where it is installed).

Run: ``python bench/profile_batch.py [FILES]`` (the threads table over twice as many).
"""

from __future__ import annotations

import contextlib
import dataclasses
import functools
import importlib
import os
import re
import subprocess
import sys
import tempfile
import threading
import time
from collections import Counter
from collections.abc import Callable
from pathlib import Path
from typing import Any

from bench_batch import PIPELINE, _write_images

import graphvision as gv
from graphvision.execution import batch
from graphvision.views.batch_page import BATCH_PAGES

PARTS: dict[str, list[tuple[str, str]]] = {
    "compute": [("graphvision.execution.node_call", "call_labelled")],
    "planning": [
        ("graphvision.execution.run", "_compiled"),
        ("graphvision.execution.state", "RunState.key_steps"),
        ("graphvision.execution.state", "RunState.plan"),
        ("graphvision.execution.state", "RunState.prepare"),
    ],
    "read": [("graphvision_plugins.io._image_file", "read_image_file")],
    "hashing": [
        ("graphvision.cache.keys", "content_key"),
        ("graphvision.execution.provenance", "file_sha256"),
    ],
    "transport": [
        ("graphvision.values.ports", "*.encode"),
        ("graphvision.values.ports", "*.decode"),
    ],
    "record": [
        ("graphvision.execution.provenance", "describe_run"),
        ("graphvision.execution.record", "RunRecord.to_json"),
    ],
    "report": [],  # the batch's run pages (BATCH_PAGES.run), wrapped where they are passed
    "thumbnails": [
        ("graphvision.values.pictures", "png_bytes"),
        ("graphvision.values.pictures", "thumbnail"),
    ],
    "outputs": [("graphvision.execution.folders", "write_outputs")],
    "write": [("graphvision.execution.batch_write", "finish_item")],
}


class _Clock:
    """Seconds spent in each part, wall and the thread's CPU (``time.thread_time``), counted
    at its outermost call only, in each thread on its own (a batch on threads runs two
    files at once): what a part waited (for the GIL, or for a core) is its wall less its CPU."""

    def __init__(self) -> None:
        self.threads: list[dict[str, list[float]]] = []  # per thread: part -> depth, wall, CPU
        self.local = threading.local()

    def _parts(self) -> dict[str, list[float]]:
        parts = getattr(self.local, "parts", None)
        if parts is None:
            parts = self.local.parts = {part: [0, 0.0, 0.0] for part in PARTS}
            self.threads.append(parts)
        return parts

    def wrap(self, part: str, function: Callable[..., Any]) -> Callable[..., Any]:
        clock, cpu = time.perf_counter, time.thread_time

        @functools.wraps(function)
        def timed(*args: Any, **kwargs: Any) -> Any:
            counted = self._parts()[part]
            counted[0] += 1
            began, began_cpu = clock(), cpu()
            try:
                return function(*args, **kwargs)
            finally:
                counted[0] -= 1
                if not counted[0]:
                    counted[1] += clock() - began
                    counted[2] += cpu() - began_cpu

        return timed

    def seconds(self, column: int) -> dict[str, float]:
        """Each part's seconds over every thread: wall (``column`` 1) or CPU (2)."""
        return {part: sum(parts[part][column] for parts in self.threads) for part in PARTS}


def _subclasses(kind: type) -> list[type]:
    found, todo = [], [kind]
    while todo:
        found.append(todo.pop())
        todo += found[-1].__subclasses__()
    return found


def _install(clock: _Clock) -> Callable[[], None]:
    """Wrap every part's functions where they are looked up (each module holding the same
    function object, each class defining the method); return what undoes it."""
    undo: list[tuple[Any, str, Any]] = []

    def replace(owner: Any, name: str, new: Any) -> None:
        undo.append((owner, name, owner.__dict__[name]))
        setattr(owner, name, new)

    for part, functions in PARTS.items():
        for module_name, qualified in functions:
            module = importlib.import_module(module_name)
            if "." in qualified:
                owner_name, method = qualified.split(".")
                owners = (
                    _subclasses(module.PortType)
                    if owner_name == "*"
                    else [getattr(module, owner_name)]
                )
                for owner in owners:
                    if method in owner.__dict__:
                        raw = owner.__dict__[method]
                        if isinstance(raw, classmethod):
                            replace(owner, method, classmethod(clock.wrap(part, raw.__func__)))
                        else:
                            replace(owner, method, clock.wrap(part, raw))
                continue
            original = getattr(module, qualified)
            timed = clock.wrap(part, original)
            for holder in list(sys.modules.values()):
                if getattr(holder, "__dict__", None) is None:
                    continue
                for key, value in list(vars(holder).items()):
                    if value is original:
                        replace(holder, key, timed)

    def restore() -> None:
        for owner, name, value in reversed(undo):
            setattr(owner, name, value)

    return restore


def measure(
    files: int, outputs: list[str] | None = None, where: str | None = None, executor: str = "sync"
) -> tuple[float, dict[str, float], dict[str, float]]:
    """Wall seconds of a batch of ``files`` coins images on ``executor`` (writing ``outputs``,
    all of them with None, into a folder in ``where``, default beside this file), and each
    part's wall and CPU seconds (over every thread; the process's CPU as ``CPU``)."""
    import bench_batch

    bench_batch.FILES = files
    graph = gv.load_pipeline(PIPELINE)
    with tempfile.TemporaryDirectory(dir=where or Path(__file__).parent) as scratch:
        paths = _write_images(Path(scratch) / "in")
        gv.run_batch(  # plugins loaded, kernels compiled: what follows is per file
            graph, [str(paths[0])], input="image", output_dir=Path(scratch) / "warm", cache=None
        )
        clock = _Clock()
        restore = _install(clock)
        pages = dataclasses.replace(
            BATCH_PAGES, run=tuple(clock.wrap("report", page) for page in BATCH_PAGES.run)
        )
        try:
            began, cpu = time.perf_counter(), time.process_time()
            batch.run_batch(
                graph,
                [str(p) for p in paths],
                input="image",
                output_dir=Path(scratch) / "out",
                outputs=outputs,
                executor=executor,
                cache=None,
                pages=pages,
            )
            wall, used = time.perf_counter() - began, time.process_time() - cpu
        finally:
            restore()
    return wall, {**clock.seconds(1), "CPU": used}, clock.seconds(2)


CASES: dict[str, tuple[list[str] | None, str | None]] = {
    "output count (bench_batch's batch)": (["count"], None),
    "all 4 outputs": (None, None),
}
if os.path.isdir("/dev/shm"):  # the same batch, its folders in memory: the disk's share
    CASES["output count, folders in memory (/dev/shm)"] = (["count"], "/dev/shm")


def profile(files: int) -> list[str]:
    """Per-file milliseconds of each part (perf_counter), for a sync batch of ``files``
    writing the output ``count`` (as ``bench_batch.py``), then all four outputs."""
    measured = {case: measure(files, *how)[:2] for case, how in CASES.items()}
    load = f"{os.getloadavg()[0]:.1f}"
    rows = [
        f"| part ({files} files, sync, perf_counter), wall ms per file | "
        + " | ".join(CASES)
        + " | load 1 min |",
        "| --- | " + "---: | " * len(CASES) + "---: |",
    ]
    lines: dict[str, list[float]] = {"whole file": [], "engine (whole file less compute)": []}
    lines.update({part: [] for part in PARTS})
    lines["whole file, CPU ms (process_time: the load does not count)"] = []
    for wall, seconds in measured.values():
        per = {part: s / files * 1e3 for part, s in seconds.items()}
        lines["whole file, CPU ms (process_time: the load does not count)"].append(per.pop("CPU"))
        lines["whole file"].append(wall / files * 1e3)
        lines["engine (whole file less compute)"].append(wall / files * 1e3 - per["compute"])
        for part, ms in per.items():
            lines[part].append(ms)
    for name, values in lines.items():
        rows.append(f"| {name} | " + " | ".join(f"{v:.1f}" for v in values) + f" | {load} |")
    return rows


def waits(files: int) -> list[str]:
    """Per file, each part's wall and CPU milliseconds (``thread_time``) in a sync batch and
    in a batch on threads (two files at once, summed over both threads), folders in
    ``/dev/shm`` (or beside this file): in the threads batch, a part's wall less its CPU is
    what it waited, for the GIL or for a core (the load column says how busy the machine
    was; on a quiet one it is the GIL). ``py-spy --gil`` samples a thread that holds the GIL
    while the machine has put it aside, so under load it counted waits as GIL time."""
    where = "/dev/shm" if os.path.isdir("/dev/shm") else None
    runs = {name: measure(files, ["count"], where, name) for name in ("sync", "threads")}
    rows = [
        f"| part ({files} files, output count), ms per file | sync wall | sync CPU | "
        "sync waited | threads wall | threads CPU | threads waited | load 1 min |",
        "| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |",
    ]
    load = f"{os.getloadavg()[0]:.1f}"
    for part in PARTS:
        cells = []
        for name in runs:
            wall, cpu = (runs[name][k][part] / files * 1e3 for k in (1, 2))
            cells += [wall, cpu, wall - cpu]
        rows.append(f"| {part} | " + " | ".join(f"{c:.2f}" for c in cells) + f" | {load} |")
    cells = []
    for name in runs:
        wall, cpu = runs[name][0] / files * 1e3, runs[name][1]["CPU"] / files * 1e3
        cells += [f"{wall:.2f}", f"{cpu:.2f}", ""]
    rows.append(
        f"| whole batch, elapsed (threads: two files at once) | {' | '.join(cells)} | {load} |"
    )
    return rows


_BATCH = """
import os, sys
sys.path.insert(0, {here!r})
from pathlib import Path
import bench_batch, graphvision as gv
paths = [str(p) for p in bench_batch._write_images(Path({scratch!r}) / "in")[:{files}]]
graph = gv.load_pipeline(bench_batch.PIPELINE)
for name, chosen in (("warm", paths[:1]), ("out", paths)):
    os.path.exists({mark!r} + name)
    gv.run_batch(graph, chosen, input="image", output_dir=Path({scratch!r}) / name,
                 outputs=["count"], executor={executor!r}, workers=2, cache=None)
os.path.exists({mark!r} + "end")
"""
_MARK = "/graphvision-profile-mark-"  # a path looked at (not found) around the timed batch


def _strace_calls(
    files: int, executor: str, where: str | None, only: tuple[str, ...] = ()
) -> Counter[str]:
    """Calls by system call name (``strace -f``, every thread) of a batch of ``files`` on
    ``executor``, run after a one-file batch in the same process (the plugins loaded); with
    ``only``, those calls alone are traced (``--seccomp-bpf``: the others run unstopped)."""
    import subprocess

    with tempfile.TemporaryDirectory(dir=where) as scratch:
        trace = Path(scratch) / "strace.txt"
        code = _BATCH.format(here=str(Path(__file__).parent), scratch=scratch, files=files,
                             executor=executor, mark=_MARK)  # fmt: skip
        traced = ["--seccomp-bpf", "-e", f"trace={','.join(('%%stat', *only))}"] if only else []
        command = ["strace", "-f", *traced, "-o", str(trace), sys.executable, "-c", code]
        subprocess.run(command, check=True)
        calls: Counter[str] = Counter()
        inside = False
        for line in trace.read_text().splitlines():
            if _MARK in line:
                inside = _MARK + "out" in line
            elif inside and (call := re.match(r"\d+\s+(\w+)\(", line)):
                calls[call.group(1)] += 1  # (a call resumed after a thread switch: once)
        return calls


def _per_file(executor: str, where: str | None, only: tuple[str, ...] = ()) -> dict[str, float]:
    """System calls per file by name: batches of 12 and of 36 files, the difference over 24
    (what every batch does once cancels)."""
    few, many = (_strace_calls(n, executor, where, only) for n in (12, 36))
    return {name: (many[name] - few[name]) / 24 for name in {*few, *many}}


def system_calls(executor: str = "threads") -> list[str]:
    """System calls per batch file (each releases the GIL and takes it back, a wait on
    threads when the other file's thread holds it): ``strace -f`` of a batch of 12 files
    and of one of 36 (each after a one-file batch in its process, which loads the plugins),
    the difference over 24 files, folders in ``/dev/shm``; not ``futex``, the GIL's own
    waits, which strace's stops change. Then the ``futex`` calls traced alone (with the
    ``stat`` that finds the marks around the timed batch): the threads' hand-offs of the GIL
    (a thread that finds it held waits in one, the holder wakes it in another), which each
    system call's stop multiplied. Needs ``strace`` (5.3 or later for the last row)."""
    import shutil

    if shutil.which("strace") is None:
        return ["(strace is not installed: no table of system calls)"]
    where = "/dev/shm" if os.path.isdir("/dev/shm") else None
    per = _per_file(executor, where)
    shown = sorted((n for n in per if abs(per[n]) >= 0.5 and n != "futex"), key=lambda n: -per[n])
    rows = [
        f"| system calls per file ({executor}, folders in memory) | calls |",
        "| --- | ---: |",
        f"| all but futex (the GIL's waits) | {sum(per.values()) - per.get('futex', 0):.1f} |",
    ]
    rows += [f"| {name} | {per[name]:.1f} |" for name in shown]
    with contextlib.suppress(subprocess.CalledProcessError):  # (an strace without seccomp)
        handoffs = _per_file(executor, where, ("futex",)).get("futex", 0.0)
        rows.append(
            f"| futex traced alone (the GIL's hand-offs between threads) | {handoffs:.1f} |"
        )
    return rows


def main() -> list[str]:
    return [*profile(50), "", *waits(100), "", *system_calls()]


if __name__ == "__main__":
    count = int(sys.argv[1]) if len(sys.argv) > 1 else 50
    print("\n".join([*profile(count), "", *waits(2 * count), "", *system_calls()]))
