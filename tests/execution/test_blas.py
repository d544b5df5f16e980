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
    """OpenBLAS ignores a raise of its thread count from a worker once the main thread
    lowered it; the limit is therefore set and lifted from a helper thread."""
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


def test_a_user_entering_while_a_restore_is_on_its_way_still_gets_one_thread():
    """A run sends the restore after its last node and waits for it only before it returns
    (execution.blas.BlasLimit): a user who enters in between, seeing one thread still set,
    must not take the limit for held; the helper restores, then lowers again, in order."""
    from graphvision.execution.blas import BlasLimit

    before = blas_threads()
    run = BlasLimit()
    run.hold()
    assert set(blas_threads()) == {1}
    run.release()  # the restore is sent, not waited for
    with gv.one_blas_thread():
        assert set(blas_threads()) == {1}
    run.restored()
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
