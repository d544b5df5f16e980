"""One BLAS thread while nodes run (graphvision.execution.blas): a node's bits do not depend on
what runs beside it, on any executor, and the process gets its threads back."""

from __future__ import annotations

import threading

import numpy as np
import pytest
from threadpoolctl import threadpool_info

import graphvision as gv

PLUGIN = '''
import numpy as np
from threadpoolctl import threadpool_info
from graphvision import Array, Int, node

@node("blas.threads")
def threads(*, seed: int = 0) -> Int:
    """The BLAS threads this node runs with."""
    return max(p["num_threads"] for p in threadpool_info() if p["user_api"] == "blas")

@node("blas.product")
def product(*, seed: int = 0) -> Array:
    """A product whose last digits depend on how BLAS splits it."""
    rng = np.random.default_rng(seed)
    return rng.normal(size=(300, 256)) @ rng.normal(size=(256, 64))
'''


def blas_threads() -> list[int]:
    return [pool["num_threads"] for pool in threadpool_info() if pool["user_api"] == "blas"]


@pytest.fixture
def blas_registry(tmp_path):
    plugin = tmp_path / "blas_plugin.py"
    plugin.write_text(PLUGIN)
    return gv.discover([plugin], entry_points=False)


def graph() -> gv.Graph:
    g = gv.Graph("blas")
    g.output("threads", g.add("threads", "blas.threads"))
    g.output("product", g.add("product", "blas.product"))
    return g


@pytest.mark.parametrize("executor", ["sync", "threads", "processes"])
def test_nodes_run_with_one_blas_thread_on_every_executor(blas_registry, executor):
    before = blas_threads()
    result = gv.run(graph(), blas_registry, executor=executor, cache=None)
    assert result.outputs["threads"] == 1
    assert blas_threads() == before  # given back after the run


def test_a_product_has_the_same_bits_on_every_executor_and_alone(blas_registry):
    rng = np.random.default_rng(0)
    alone = rng.normal(size=(300, 256)) @ rng.normal(size=(256, 64))  # with the process's threads
    values = [
        gv.run(graph(), blas_registry, executor=e, cache=None).outputs["product"]
        for e in ("sync", "threads", "processes")
    ]
    assert all(v.tobytes() == values[0].tobytes() for v in values)
    with gv.one_blas_thread():
        rng = np.random.default_rng(0)
        assert (rng.normal(size=(300, 256)) @ rng.normal(size=(256, 64))).tobytes() == (
            values[0].tobytes()
        )
    np.testing.assert_allclose(alone, values[0], rtol=1e-12)


def test_overlapping_limits_restore_the_original_threads():
    """Two users enter and leave interleaved; the process gets its BLAS threads back (a
    save-and-restore per user would leave it on one)."""
    before = blas_threads()
    first, second = gv.one_blas_thread(), gv.one_blas_thread()
    first.__enter__()
    second.__enter__()
    assert set(blas_threads()) == {1}
    first.__exit__(None, None, None)
    assert set(blas_threads()) == {1}  # the second user still runs
    second.__exit__(None, None, None)
    assert blas_threads() == before


def test_a_limit_entered_in_the_main_thread_and_left_in_another_restores():
    """threadpoolctl ignores a raise of OpenBLAS's thread count from any thread but the first
    that set it; the limit sets the count itself, from whichever thread enters or leaves."""
    before = blas_threads()
    here, there = gv.one_blas_thread(), gv.one_blas_thread()
    here.__enter__()
    worker = threading.Thread(target=there.__enter__)
    worker.start()
    worker.join()
    assert set(blas_threads()) == {1}
    here.__exit__(None, None, None)
    worker = threading.Thread(target=lambda: there.__exit__(None, None, None))
    worker.start()
    worker.join()
    assert blas_threads() == before


def test_a_limit_entered_in_a_thread_lowers_after_another_thread_took_threadpoolctl():
    """A user's thread that set BLAS threads through threadpoolctl first becomes its
    "controlling thread"; a run in another thread still gets one BLAS thread (the same
    bits) and gives the count back."""
    from threadpoolctl import ThreadpoolController

    libraries = ThreadpoolController().select(user_api="blas").lib_controllers
    before = blas_threads()
    for library in libraries:
        library.set_num_threads(library.num_threads)  # this thread controls threadpoolctl now
    inside: list[list[int]] = []

    def limited() -> None:
        with gv.one_blas_thread():
            inside.append(blas_threads())

    try:
        worker = threading.Thread(target=limited)
        worker.start()
        worker.join()
    finally:
        type(libraries[0]).clear_controlling_thread(force=True)
    assert [set(threads) for threads in inside] == [{1}]
    assert blas_threads() == before


def test_a_run_and_a_user_in_another_thread_share_one_limit():
    """A run holds the limit from its first node to its last; a user entering meanwhile only
    counts, and the threads come back when the last leaves."""
    from graphvision.execution.blas import BlasLimit

    before = blas_threads()
    run = BlasLimit()
    run.hold()
    assert set(blas_threads()) == {1}
    with gv.one_blas_thread():
        run.release()
        assert set(blas_threads()) == {1}  # the user still holds it
    assert blas_threads() == before
    run.release()  # (again, in the run's finally: nothing more)
    assert blas_threads() == before


def test_a_run_that_fails_to_compile_gives_the_blas_threads_back(blas_registry):
    before = blas_threads()
    g = gv.Graph("bad")
    g.output("x", g.add("x", "blas.no_such_op"))
    with pytest.raises(gv.PipelineError):
        gv.run(g, blas_registry, executor="sync", cache=None)
    assert blas_threads() == before


def test_a_batch_holds_one_blas_thread_from_file_to_file_and_gives_it_back(tmp_path):
    """Between two files (where the batch calls ``on_item``) BLAS stays at one thread, so a
    file's run only counts itself in; the threads come back when the batch ends, also
    when it fails."""
    import imageio.v3 as iio

    from ..conftest import PIPELINES

    for k in range(3):
        iio.imwrite(tmp_path / f"p{k}.png", np.full((8, 8), 40 * k, np.uint8))
    before, between = blas_threads(), []
    batch = gv.run_batch(
        gv.load_pipeline(PIPELINES / "denoise.yaml"),
        str(tmp_path / "*.png"),
        input="image",
        output_dir=tmp_path / "out",
        outputs=["psnr_noisy_gaussian"],
        executor="sync",
        on_item=lambda *_: between.append(blas_threads()),
    )
    assert [item.status for item in batch.items] == ["ok"] * 3
    assert [set(threads) for threads in between] == [{1}] * 3
    assert set(blas_threads()) == set(before)  # (the plugins may load scipy's BLAS too)

    def stop(*_: object) -> None:
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        gv.run_batch(
            gv.load_pipeline(PIPELINES / "denoise.yaml"), str(tmp_path / "*.png"),
            input="image", output_dir=tmp_path / "stopped", executor="sync", on_item=stop,
        )  # fmt: skip
    assert set(blas_threads()) == set(before)


def test_each_library_is_read_and_set_through_the_calls_threadpoolctl_makes():
    """The getter and setter found once per library (C functions for OpenBLAS) read what
    threadpoolctl reads and set what it then reports."""
    from threadpoolctl import ThreadpoolController

    from graphvision.execution.blas import _switch

    libraries = ThreadpoolController().select(user_api="blas").lib_controllers
    assert libraries
    for library in libraries:
        getter, setter = _switch(library)
        had = library.get_num_threads()
        assert getter() == had
        setter(1)
        try:
            assert library.get_num_threads() == 1
            assert getter() == 1
        finally:
            setter(had)
        assert library.get_num_threads() == had


def test_a_library_threadpoolctl_does_not_call_openblas_is_set_through_its_methods():
    from graphvision.execution.blas import _switch

    class OtherController:  # (an MKL or BLIS controller: no OpenBLAS symbols)
        threads = 4

        def get_num_threads(self) -> int:
            return self.threads

        def set_num_threads(self, count: int) -> None:
            self.threads = count

    other = OtherController()
    getter, setter = _switch(other)
    setter(1)
    assert (getter(), other.threads) == (1, 1)
