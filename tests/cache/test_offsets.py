"""A value read from the cache, or sent to another process, lies at the offset modulo 64 it
had when it was computed: a node reading it sees the same layout cold and warm."""

from __future__ import annotations

import pickle
from concurrent.futures import Future

import numpy as np
import pytest

import graphvision as gv
from graphvision.values.memory import alignment_offset, frozen_copy
from graphvision.values.ports import is_frozen

from .test_cache import _forged


@pytest.mark.parametrize("dtype", [np.bool_, np.uint8, np.int32, np.float32, np.float64])
def test_every_offset_comes_back_from_the_disk_with_the_same_bits(tmp_path, dtype):
    store = gv.DiskStore(tmp_path)
    values = (np.random.default_rng(3).random((5, 6)) * 9).astype(dtype)
    for offset in range(0, 64, np.dtype(dtype).alignment):
        key = f"k{offset:02d}" + "0" * 30
        gv.Cache(None, store).put(key, gv.ArrayPort, frozen_copy(values, offset))
        hit, back = gv.Cache(None, store).get(key, gv.ArrayPort)
        assert hit and alignment_offset(back) == offset and back.tobytes() == values.tobytes()
        assert is_frozen(back)


def test_a_tables_columns_come_back_each_at_its_offset(tmp_path):
    store = gv.DiskStore(tmp_path)
    table = {
        "x": frozen_copy(np.arange(7, dtype=np.int64), 24),
        "y": frozen_copy(np.linspace(0, 1, 5, dtype=np.float32), 52),
        "z": frozen_copy(np.zeros(0), 8),
    }
    gv.Cache(None, store).put("t" * 32, gv.TablePort, table)
    hit, back = gv.Cache(None, store).get("t" * 32, gv.TablePort)
    assert hit and [alignment_offset(back[c]) for c in "xyz"] == [24, 52, 0]
    assert all(back[c].tobytes() == table[c].tobytes() for c in "xyz")


GOOD_AT_4 = {
    "type": "Array",
    "meta": {},
    "arrays": [{"name": "data", "dtype": "<f4", "shape": [3], "offset": 4, "nbytes": 12}],
    "payload": 16,
}


def test_an_entry_at_an_offset_reads_there_and_one_its_dtype_cannot_lie_at_is_dropped(
    tmp_path,
):
    store = gv.DiskStore(tmp_path)
    store.path("k0").parent.mkdir()
    store.path("k0").write_bytes(_forged(GOOD_AT_4))
    hit, value = gv.Cache(None, store).get("k0", gv.ArrayPort)
    assert hit and value.tolist() == [1.0, 2.0, 3.0] and alignment_offset(value) == 4
    for offset in (2, 65):  # not a multiple of 4; past the 64-byte boundary
        spec = {**GOOD_AT_4["arrays"][0], "offset": offset, "shape": [1], "nbytes": 4}
        store.path("k0").write_bytes(_forged({**GOOD_AT_4, "arrays": [spec]}))
        with pytest.warns(gv.CacheWarning, match="bad shape or offset"):
            assert gv.Cache(None, store).get("k0", gv.ArrayPort) == (False, None)


class _Pickling:
    """Nodes 'in another process' run here: every task's arguments and result go through
    pickle, as a process pool's do."""

    encodes_values = True
    width = 1
    name = "pickling"

    def submit(self, fn, /, *args):
        future: Future = Future()
        try:
            result = fn(*pickle.loads(pickle.dumps(args)))
            future.set_result(pickle.loads(pickle.dumps(result)))
        except Exception as error:
            future.set_exception(error)
        return future

    def shutdown(self, wait=True, *, cancel_futures=False):
        return None


@pytest.mark.parametrize("offset", [16, 40])
def test_a_node_sees_its_input_at_the_same_offset_cold_warm_and_in_another_process(
    registry, tmp_path, offset
):
    graph = gv.Graph("offsets")
    made = graph.add("a", "toy.at_offset", x=graph.input("x", "Float", default=2.0),
                     params={"offset": offset})  # fmt: skip
    graph.output("seen", graph.add("b", "toy.offset_of", a=made))
    graph.output("a", made)
    store = gv.DiskStore(tmp_path / "cache")
    cold = gv.run(graph, registry, executor="sync", cache=gv.Cache(None, store))
    assert cold.outputs["seen"] == offset  # frozen where the node made it: no copy
    assert alignment_offset(cold.outputs["a"]) == offset
    b_key = next(n.keys["out"] for n in cold.record.nodes if n.name == "b")
    for executor in ("sync", _Pickling()):  # b again, a read from the disk
        store.path(b_key).unlink()
        warm = gv.run(graph, registry, executor=executor, cache=gv.Cache(None, store))
        assert {n.name: n.status for n in warm.record.nodes} == {"a": "cached", "b": "computed"}
        assert warm.outputs["seen"] == offset
        assert alignment_offset(warm.outputs["a"]) == offset
        assert warm.outputs["a"].tobytes() == cold.outputs["a"].tobytes()
