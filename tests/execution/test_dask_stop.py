"""A stopped Dask batch's folders are whole or absent, as batch.csv says (issue 26 item 1 on
Dask): its workers see the stop flag, in the output folder, so a file a worker finishes
after the stop writes nothing, and one written whole whose result had not reached the client
counts as done. A worker importing an unguarded script is refused, naming the guard."""

from __future__ import annotations

import contextlib
import csv
import multiprocessing
import os
import signal
import subprocess
import sys
import threading
import types
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

import graphvision as gv
from graphvision.execution import dask_files, file_task
from graphvision.execution.batch_guard import UnguardedScriptError, guard_hint

from .test_batch import _counting_graph, photo

distributed = pytest.importorskip(
    "distributed", reason="Dask is an optional extra: graphvision[dask]"
)

from graphvision.execution.dask import DaskExecutor, DaskUnavailableError  # noqa: E402

DEADLINE = 60.0


@pytest.fixture(scope="module")
def in_process() -> Iterator[DaskExecutor]:
    """A cluster whose two worker threads run in this process (started in about a second;
    the tests reach into a worker's file task from here)."""
    client = distributed.Client(
        processes=False, n_workers=1, threads_per_worker=2, dashboard_address=":0"
    )
    executor = DaskExecutor(client)
    yield executor
    executor.shutdown()
    client.close()


def _held_writing(held: dict[str, threading.Event], release: threading.Event) -> Any:
    """file_task.writing, except that file ``c``'s worker waits for ``release`` just before
    it claims its folder, and file ``d``'s just after writing it whole (its result not yet
    sent); each sets its ``held`` event then, and ``held["gone"]`` once all of it is over."""
    real = file_task.writing

    @contextlib.contextmanager
    def writing(stop: Any, folder: Any, stopped: Any) -> Iterator[Any]:
        name = Path(folder).name
        if name == "c":
            held["c"].set()
            assert release.wait(DEADLINE)
        with real(stop, folder, stopped) as claim:
            yield claim
        if name == "d":
            held["d"].set()
            assert release.wait(DEADLINE)
        if name in "cd":
            held["gone " + name].set()

    return writing


def test_a_dask_batch_stopped_while_workers_hold_files_matches_batch_csv(
    in_process, tmp_path, monkeypatch
):
    graph, registry, _ = _counting_graph(tmp_path)
    files = [photo(tmp_path / "in" / f"{name}.png", 50) for name in "abcd"]
    out = tmp_path / "out"
    held = {name: threading.Event() for name in ("c", "d", "gone c", "gone d")}
    release = threading.Event()
    monkeypatch.setattr(file_task, "writing", _held_writing(held, release))
    monkeypatch.setattr(dask_files, "FILES_PER_TASK", 1)  # c and d in tasks of their own

    def ctrl_c() -> None:  # c before its folder, d after it: both on a worker thread
        if held["c"].wait(DEADLINE) and held["d"].wait(DEADLINE):
            os.kill(os.getpid(), signal.SIGINT)

    before = signal.signal(signal.SIGINT, signal.default_int_handler)  # as in a terminal
    threading.Thread(target=ctrl_c, daemon=True).start()
    try:
        with pytest.raises(KeyboardInterrupt):
            gv.run_batch(
                graph,
                [str(f) for f in files],
                input="image",
                output_dir=out,
                registry=registry,
                executor=in_process,
                client_files=False,
            )
    finally:
        release.set()  # c's and d's workers go on, after the client has summarised
        signal.signal(signal.SIGINT, before)
    assert held["gone c"].wait(DEADLINE) and held["gone d"].wait(DEADLINE)
    rows = {Path(r["file"]).stem: r["status"] for r in csv.DictReader((out / "batch.csv").open())}
    # c: finished by its worker after the stop, so not written; d: written whole before
    # the stop, its result never heard of, so counted from its claim
    assert (rows["a"], rows["c"], rows["d"]) == ("ok", "interrupted", "ok")
    for name, listed in rows.items():  # whole and done, or absent and not done
        assert (out / name / "record.json").is_file() == (listed == "ok"), name
        assert (out / name).exists() == (listed == "ok"), name
    assert [path.name for path in out.iterdir() if path.name.startswith(".")] == []


def test_a_batch_started_by_a_worker_importing_the_script_names_the_guard(tmp_path, monkeypatch):
    monkeypatch.setattr(multiprocessing.current_process(), "_inheriting", True, raising=False)
    graph, registry, _ = _counting_graph(tmp_path)
    with pytest.raises(UnguardedScriptError, match='under `if __name__ == "__main__":`'):
        gv.run_batch(
            graph,
            [str(photo(tmp_path / "a.png", 50))],
            input="image",
            output_dir=tmp_path / "out",
            registry=registry,
            executor=DaskExecutor(),
        )
    with pytest.raises(UnguardedScriptError, match="a local Dask cluster started while"):
        DaskExecutor().client  # noqa: B018 - what starts the cluster
    assert not (tmp_path / "out").exists()


def test_a_local_cluster_that_did_not_start_names_a_missing_guard(tmp_path, monkeypatch):
    script = tmp_path / "batch.py"
    script.write_text("import graphvision as gv\ngv.run_batch(...)\n")
    main = types.ModuleType("__main__")
    main.__file__ = str(script)
    monkeypatch.setitem(sys.modules, "__main__", main)
    executor = DaskExecutor()
    executor._start_error = RuntimeError("Nanny failed to start.")  # as a refused worker's
    executor._started.set()
    with pytest.raises(DaskUnavailableError, match=f"{script} has no `if __name__ =="):
        executor.client  # noqa: B018
    script.write_text('if __name__ == "__main__":\n    gv.run_batch(...)\n')
    assert guard_hint() == ""  # guarded: the cluster failed for another reason


UNGUARDED = """
import multiprocessing

from graphvision.execution.batch_guard import refuse_in_bootstrap

refuse_in_bootstrap("a batch")  # the batch an unguarded script starts at import
worker = multiprocessing.get_context("spawn").Process(target=print)
worker.start()
worker.join(60)
print("worker exit", worker.exitcode)
"""


def test_a_spawned_worker_importing_an_unguarded_script_stops_there_naming_the_guard(tmp_path):
    script = tmp_path / "unguarded.py"
    script.write_text(UNGUARDED)
    done = subprocess.run(
        [sys.executable, str(script)], capture_output=True, text=True, timeout=DEADLINE
    )
    assert "worker exit 1" in done.stdout, done.stderr
    assert f"a batch started while this worker process imports {script}" in done.stderr
    assert 'under `if __name__ == "__main__":`' in done.stderr


def test_a_process_worker_that_died_twice_names_a_missing_guard(tmp_path, monkeypatch):
    """A process pool's retry comes from the fork server, which imports the client's script
    first: an unguarded script dies there, and the node's error says why."""
    from graphvision.execution.worker_died import died

    script = tmp_path / "run.py"
    script.write_text("import graphvision as gv\ngv.run(...)\n")
    main = types.ModuleType("__main__")
    main.__file__ = str(script)
    monkeypatch.setitem(sys.modules, "__main__", main)
    error = died("and again when retried alone")
    assert str(error).startswith("the worker process running this node died")
    assert f"{script} has no `if __name__ ==" in str(error)
    script.write_text('if __name__ == "__main__":\n    gv.run(...)\n')
    assert str(died("and again when retried alone")).endswith("and again when retried alone")
