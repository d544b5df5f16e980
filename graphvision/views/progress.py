"""Progress of runs, batches and sweeps: a bar on a terminal, plain lines elsewhere.

On a terminal, a ``tqdm`` bar counts nodes (or files) done out of the total
and names what is running and for how long, refreshed twice a second, so a
long node is never silent. When the output is not a terminal (CI, a log
file), each finished node (or file) is one line, and a node still running
after ``heartbeat`` seconds gets a line saying so, at that interval.
"""

from __future__ import annotations

import sys
import threading
import time
from typing import IO, Any

from graphvision.execution.record import RunHooks, RunRecord

__all__ = ["FileProgress", "RunProgress"]


def _is_terminal(stream: IO[str]) -> bool:
    return bool(getattr(stream, "isatty", lambda: False)())


def _duration(seconds: float) -> str:
    if seconds < 1:
        return f"{seconds * 1e3:.0f} ms"
    if seconds < 120:
        return f"{seconds:.1f} s"
    return f"{seconds // 60:.0f} min {seconds % 60:02.0f} s"


class _Ticker:
    """Calls ``tick`` every ``interval`` seconds in a daemon thread until stopped."""

    def __init__(self, tick: Any, interval: float) -> None:
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._loop, args=(tick, interval), daemon=True)
        self._thread.start()

    def _loop(self, tick: Any, interval: float) -> None:
        while not self._stop.wait(interval):
            tick()

    def stop(self) -> None:
        self._stop.set()
        self._thread.join()


class RunProgress(RunHooks):
    """Nodes done out of the nodes to compute, and which are running, for how long.

    Parameters
    ----------
    stream : file, optional
        Where to write (default ``sys.stderr``).
    bar : bool, optional
        Force the bar (True) or plain lines (False); default: a bar on a terminal.
    heartbeat : float
        Plain-line mode: seconds between "still running" lines for a long node.
    """

    def __init__(
        self, stream: IO[str] | None = None, *, bar: bool | None = None, heartbeat: float = 10.0
    ) -> None:
        self.stream = stream or sys.stderr
        self.use_bar = _is_terminal(self.stream) if bar is None else bar
        self.heartbeat = heartbeat
        self.total = self.done = 0
        self.running: dict[str, tuple[str, float]] = {}  # name -> (op, started)
        self._announced: dict[str, float] = {}
        self._lock = threading.Lock()
        self._bar: Any = None
        self._ticker: _Ticker | None = None

    def run_started(self, *, pipeline: str, steps: list[str]) -> None:
        self.total, self.done = len(steps), 0
        if self.use_bar:
            from tqdm import tqdm

            self._bar = tqdm(
                total=self.total, desc=pipeline, unit="node", file=self.stream, leave=True
            )
            self._ticker = _Ticker(self._refresh, 0.5)
        else:
            self._write(f"running {pipeline}: {self.total} node(s) to compute")
            # a quarter of the heartbeat: a node is announced within 1.25 heartbeats of its
            # start, whenever in the ticker's period it started
            self._ticker = _Ticker(self._still_running, min(1.0, self.heartbeat / 4))

    def node_started(self, *, name: str, op: str) -> None:
        with self._lock:
            self.running[name] = (op, time.monotonic())

    def node_finished(self, *, name: str, op: str, status: str, seconds: float) -> None:
        if status == "cached":  # loaded before the run started: not one of the nodes to compute
            return
        with self._lock:
            self.running.pop(name, None)
            self._announced.pop(name, None)
            self.done += 1
        if self._bar is not None:
            self._bar.update(1)
            self._refresh()
        else:
            self._write(f"  [{self.done}/{self.total}] {name} ({op}) {status} {_duration(seconds)}")

    def run_finished(self, *, record: RunRecord, failed: bool) -> None:
        if self._ticker is not None:
            self._ticker.stop()
            self._ticker = None
        if self._bar is not None:
            self._bar.close()
            self._bar = None

    def _running_now(self) -> list[tuple[str, str, float]]:
        now = time.monotonic()
        with self._lock:
            return sorted(
                ((name, op, now - began) for name, (op, began) in self.running.items()),
                key=lambda item: -item[2],
            )

    def _refresh(self) -> None:
        bar = self._bar
        if bar is None:
            return
        shown = ", ".join(f"{name} {_duration(age)}" for name, _, age in self._running_now()[:3])
        bar.set_postfix_str(f"running: {shown}" if shown else "", refresh=True)

    def _still_running(self) -> None:
        for name, op, age in self._running_now():
            last = self._announced.get(name, 0.0)
            if age >= self.heartbeat and age - last >= self.heartbeat:
                self._announced[name] = age
                self._write(f"  ... {name} ({op}) still running after {_duration(age)}")

    def _write(self, line: str) -> None:
        print(line, file=self.stream, flush=True)


class FileProgress:
    """Files done out of the total, with failures and the time left, for batches and sweeps.

    Parameters
    ----------
    total : int
        How many files (or combinations) there are.
    label : str
        What is counted, in the bar and the lines (``files``, ``combinations``).
    stream, bar
        As for :class:`RunProgress`.
    began : float, optional
        When the work began (``time.monotonic()``), if before this object was
        made: the time left is estimated from it. Default: now.
    """

    def __init__(
        self,
        total: int,
        label: str = "files",
        stream: IO[str] | None = None,
        *,
        bar: bool | None = None,
        began: float | None = None,
    ) -> None:
        self.stream = stream or sys.stderr
        self.total, self.done, self.failed = total, 0, 0
        self.label = label
        self.began = time.monotonic() if began is None else began
        self._first_finished = self.began
        self._bar: Any = None
        if _is_terminal(self.stream) if bar is None else bar:
            from tqdm import tqdm

            self._bar = tqdm(total=total, unit=label.rstrip("s") or label, file=self.stream)

    def finished(self, item: str, ok: bool, seconds: float) -> None:
        """One file (or combination) finished, successfully or not."""
        self.done += 1
        self.failed += not ok
        if self._bar is not None:
            self._bar.update(1)
            self._bar.set_postfix_str(f"{self.failed} failed" if self.failed else "")
            return
        left = self._time_left(time.monotonic())
        status = "ok" if ok else "FAILED"
        print(
            f"  [{self.done}/{self.total} {self.label}] {item} {status} {_duration(seconds)}"
            f" (about {_duration(left)} left)",
            file=self.stream,
            flush=True,
        )

    def _time_left(self, now: float) -> float:
        """The files left at the pace since the first one finished, from the third one on;
        at the pace since the work began before that. The first file carries the start-up
        (workers starting, kernels compiled, caches read): counted in the pace, it had a
        200-file batch announce several times its real time left for most of its run."""
        if self.done == 1:
            self._first_finished = now
        if self.done >= 3:
            pace = (now - self._first_finished) / (self.done - 1)
        else:
            pace = (now - self.began) / self.done
        return pace * (self.total - self.done)

    def close(self) -> None:
        if self._bar is not None:
            self._bar.close()
