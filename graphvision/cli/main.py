"""The ``graphvision`` command line: argument parsing and printing, nothing else.

::

    graphvision run PIPELINE [-i NAME=VALUE]... [-s NODE.PARAM=VALUE]... [-o NAME]...
                             [-d DIR] [--batch NAME=GLOB] [--executor KIND] [--workers N]
                             [--scheduler ADDRESS] [--no-cache | --cache-dir DIR]
                             [--keep-going] [--record] [--[no-]progress]
    graphvision sweep PIPELINE --grid NODE.PARAM=V1,V2,... [--grid ...] -d DIR [--plot OUTPUT]
    graphvision studio PIPELINE [-i NAME=VALUE]... [-s NODE.PARAM=VALUE]... [--no-browser]
                                [--port N] [--host ADDRESS]
    graphvision validate PIPELINE... [-i NAME=VALUE]...
    graphvision nodes [--json]
    graphvision describe OP|PIPELINE [--json]
    graphvision schema
    graphvision graph PIPELINE [--format dot|mermaid|svg]
    graphvision cache info|prune|clear [--cache-dir DIR] [--max-bytes SIZE]

``--plugins PATH`` and ``--debug`` go anywhere on the line. Exit status: 0
success, 1 a run failed (or the environment: a full disk, a closed pipe), 2
an invalid pipeline or usage, 130 interrupted (Ctrl-C), 143 terminated
(SIGTERM), 129 hung up (SIGHUP: the terminal closed, an ssh connection
dropped). Every mistake is one message, never a traceback (``--debug`` adds
it). Every sub-command calls the Python API; heavy modules are imported by
the command that needs them, so ``--help`` is quick.
"""

from __future__ import annotations

import contextlib
import os
import signal
import sys
import time
from typing import TYPE_CHECKING, Any

from graphvision.cli.exits import (
    EXIT_FAILED,
    EXIT_HUNG_UP,
    EXIT_INTERRUPTED,
    EXIT_OK,
    EXIT_TERMINATED,
    EXIT_USAGE,
)
from graphvision.execution.batch_signals import defer_signals_in_imports

if TYPE_CHECKING:
    import argparse
    from collections.abc import Callable, Sequence


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line on ``argv``; return the exit status (never raises for a mistake).

    The one place errors become messages: a graphvision error is a usage
    problem (2), a failed run or a problem of the environment (a full disk,
    no permission, a closed pipe) a failure (1), Ctrl-C 130, SIGTERM 143, SIGHUP 129.
    """
    argv = list(sys.argv[1:] if argv is None else argv)
    debug = "--debug" in argv
    began = time.perf_counter()
    try:  # (the imports in here: a Ctrl-C that comes meanwhile is answered as any other)
        import warnings

        from graphvision.cli.parser import build_parser
        from graphvision.cli.usage import UsageError
        from graphvision.execution.warnings import show_warning

        warnings.showwarning = show_warning
        parser = build_parser()
        if not argv:
            parser.print_usage(sys.stderr)
            print(
                "commands: " + ", ".join(_commands(parser)) + "; --help for more", file=sys.stderr
            )
            return EXIT_USAGE
        try:
            args = parser.parse_args(argv)
        except SystemExit as done:  # --help, --version
            return int(done.code or 0)
        if args.command is None:
            raise UsageError("give a command: " + ", ".join(_commands(parser)))
        return int(args.func(args))
    except KeyboardInterrupt as stop:
        return _report_stop(stop, began)
    except BrokenPipeError:  # `graphvision nodes | head -1`: the reader has what it wanted
        _silence_stdout()
        return EXIT_OK
    except Exception as error:
        from graphvision.errors import chained

        wrapped = chained(error, KeyboardInterrupt)
        if wrapped is not None:  # a stop wrapped by code it interrupted: a __set_name__
            return _report_stop(wrapped, began)
        if debug:
            import traceback

            traceback.print_exc()
        return _report_error(error)


def _report_stop(stop: KeyboardInterrupt, began: float) -> int:
    """One line for the stop (``interrupted after 2.1 s``, a command started at ``began``);
    its exit status."""
    what, status = _stopped_by(stop)
    with contextlib.suppress(OSError):  # (a hung-up terminal refuses the line: EIO)
        print(f"{what} after {time.perf_counter() - began:.1f} s", file=sys.stderr)
    return status


def _stopped_by(stop: KeyboardInterrupt) -> tuple[str, int]:
    """What stopped the command, in a word, and its exit status."""
    if not isinstance(stop, Terminated):
        return "interrupted", EXIT_INTERRUPTED
    if stop.signum == HANG_UP:
        return "hung up", EXIT_HUNG_UP
    return "terminated", EXIT_TERMINATED


def _report_error(error: Exception) -> int:
    from graphvision.errors import GraphvisionError, RunError

    if isinstance(error, RunError):
        print(f"error: {error}", file=sys.stderr)
        return EXIT_FAILED
    if isinstance(error, GraphvisionError):
        print(f"error: {error}", file=sys.stderr)
        return EXIT_USAGE
    if isinstance(error, OSError):  # the environment: disk full, permissions, a vanished file
        where = f": {error.filename}" if error.filename else ""
        print(f"error: {error.strerror or error}{where}", file=sys.stderr)
        return EXIT_FAILED
    print(
        f"error: internal error ({type(error).__name__}: {error}); please report it, "
        "with the output of --debug",
        file=sys.stderr,
    )
    return EXIT_FAILED


def _commands(parser: argparse.ArgumentParser) -> list[str]:
    import argparse

    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            return list(action.choices)
    return []


def _silence_stdout() -> None:
    """Point stdout at /dev/null so that the interpreter's final flush does not fail again."""
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, sys.stdout.fileno())


def entry() -> None:
    """The ``graphvision`` console script: :func:`main`, then exit at once with its status.

    On Ctrl-C the process exits without waiting for worker threads to finish
    the node they run (cache entries and outputs are written atomically, so
    nothing is left half-written; worker processes see their parent go and exit). A
    Ctrl-C (SIGTERM, SIGHUP) during an import stops it once the import is done
    (:func:`~graphvision.execution.batch_signals.defer_signals_in_imports`, set first:
    this module imports only what that needs, and the command's modules are imported
    by :func:`main`); one that comes before, while Python starts, is Python's.
    """
    defer_signals_in_imports()
    terminate = _terminator(os.getpid(), _terminals())
    signal.signal(signal.SIGTERM, terminate)
    if HANG_UP is not None and signal.getsignal(HANG_UP) is not signal.SIG_IGN:
        signal.signal(HANG_UP, terminate)  # (under nohup, the command outlives its terminal)
    import faulthandler

    faulthandler.enable(all_threads=True)  # a node that crashes the process: where it was
    quiet_resource_tracker()
    status = main()
    sys.stdout.flush()
    sys.stderr.flush()
    if status in (EXIT_INTERRUPTED, EXIT_TERMINATED, EXIT_HUNG_UP):
        _release_process_resources()
        os._exit(status)
    # Done and said: a Ctrl-C while Python tears down (half a second) no longer ends it
    # by the signal, with no word (SIG_IGN outlasts the teardown; SIGTERM still ends it)
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    sys.exit(status)


HANG_UP = getattr(signal, "SIGHUP", None)  # (not on Windows)


class Terminated(KeyboardInterrupt):
    """SIGTERM (``kill``, ``timeout``, ``docker stop``, a batch scheduler) or SIGHUP (the
    terminal closed, an ssh connection dropped): stopped as Ctrl-C stops a run, so a batch
    or sweep still writes what it has done. ``signum``: the signal."""

    def __init__(self, signum: int = signal.SIGTERM) -> None:
        super().__init__()
        self.signum = signum


def _terminator(pid: int, terminals: tuple[int, ...]) -> Callable[[int, Any], None]:
    """The handler that stops the command in process ``pid``, whose ``terminals`` (standard
    output, error) are left once hung up; a process forked from it (a worker) that still
    has the handler ends as the signal's default action does, as though the handler were
    not there (SIGHUP reaches the command's whole process group)."""

    def terminate(signum: int, frame: Any) -> None:
        if os.getpid() != pid:
            signal.signal(signum, signal.SIG_DFL)
            os.kill(os.getpid(), signum)
            return
        if signum == HANG_UP:
            _leave_hung_up(terminals)
        raise Terminated(signum)

    return terminate


def _terminals() -> tuple[int, ...]:
    """The descriptors of standard output and error that are a terminal."""
    found = []
    for stream in (sys.stdout, sys.stderr):
        with contextlib.suppress(OSError, ValueError, AttributeError):
            if os.isatty(stream.fileno()):
                found.append(stream.fileno())
    return tuple(found)


def _leave_hung_up(terminals: tuple[int, ...]) -> None:
    """Point each of ``terminals`` that is a terminal no more (hung up: it refuses every
    write, EIO) at /dev/null: the batch being stopped would fail on its first message
    instead of writing its ``batch.csv`` and exiting 129. (A terminal still there, sent
    SIGHUP by ``kill -HUP``, still shows the last lines.)"""
    hung_up = [fd for fd in terminals if not os.isatty(fd)]
    if hung_up:
        devnull = os.open(os.devnull, os.O_WRONLY)
        for fd in hung_up:
            os.dup2(devnull, fd)
        os.close(devnull)


def quiet_resource_tracker() -> None:
    """Have multiprocessing's resource tracker, started later by this process, keep its
    leaked-semaphore warning to itself.

    An interrupt that lands while a process pool is still being made (its
    semaphores registered, the finalizers that unlink them not yet) leaves them
    to the tracker, which unlinks them at its own end and warns first: a second
    and third line after Ctrl-C's one. The tracker is started with this
    process's warning options (``sys.warnoptions``), so the filter reaches it.
    """
    quiet = "ignore:resource_tracker:UserWarning"
    if quiet not in sys.warnoptions:
        sys.warnoptions.append(quiet)


def _release_process_resources() -> None:
    """End the worker processes and unlink a process pool's semaphores before an immediate exit.

    ``os._exit`` skips the finalizers that release them, and multiprocessing's
    resource tracker then prints a warning about leaked semaphores. Running
    the finalizers of priority >= 0 (close queues, unlink semaphores) does not
    wait for the workers, which exit on their own when their parent is gone.
    """
    if "multiprocessing" in sys.modules:  # workers still starting would find the semaphores
        import multiprocessing  # gone and print a traceback: end them first, at once

        for child in multiprocessing.active_children():
            with contextlib.suppress(OSError):
                child.kill()
    util = sys.modules.get("multiprocessing.util")
    if util is not None:
        util._run_finalizers(0)  # private, unchanged since Python 3.4
