"""The disk and memory stores: format, verification, atomicity, bounds, concurrency."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap

import numpy as np
import pytest

import graphvision as gv
from graphvision._cache import Encoded, content_key, node_fingerprint, output_key


def entry(values):
    return Encoded("Array", {"data": np.asarray(values, dtype=np.float32)}, {})


def test_disk_round_trip_and_no_pickle(tmp_path):
    store = gv.DiskStore(tmp_path)
    table = {"x": np.arange(3, dtype=np.int64), "y": np.array([0.5, 1.5, 2.5])}
    cache = gv.Cache(None, store)
    cache.put("k1", gv.TablePort, table)
    hit, value = gv.Cache(None, store).get("k1", gv.TablePort)
    assert hit and list(value) == ["x", "y"]
    np.testing.assert_array_equal(value["y"], table["y"])
    assert not value["x"].flags.writeable
    raw = store.path("k1").read_bytes()
    assert raw.startswith(b"GVC1") and b"pickle" not in raw and b"\x80\x04" not in raw[:64]


def test_object_arrays_are_refused(tmp_path):
    with pytest.raises(TypeError, match="cannot cache object array"):
        gv.DiskStore(tmp_path).put("k", Encoded("Array", {"data": np.array([None])}, {}))


@pytest.mark.parametrize("damage", ["truncate", "flip", "garbage"])
def test_a_corrupt_entry_is_dropped_with_a_warning(tmp_path, damage):
    store = gv.DiskStore(tmp_path)
    store.put("k", entry(np.arange(100)))
    path = store.path("k")
    blob = bytearray(path.read_bytes())
    if damage == "truncate":
        blob = blob[:-10]
    elif damage == "flip":
        blob[-5] ^= 0xFF
    else:
        blob = bytearray(b"not a cache entry at all")
    path.write_bytes(bytes(blob))
    with pytest.warns(gv.CacheWarning, match=r"cache entry .* is corrupt .*recomputed"):
        assert store.get("k") is None
    assert not path.exists()


def test_a_corrupt_entry_is_recomputed_in_a_run(registry, tmp_path):
    store = gv.DiskStore(tmp_path)
    graph = gv.Graph("c")
    graph.output("o", graph.add("o", "toy.add", a=graph.input("x", "Float", default=1.0), b="x"))
    gv.run(graph, registry, cache=gv.Cache(None, store))
    (path,) = [p for p in tmp_path.rglob("*.gvc")]
    path.write_bytes(path.read_bytes()[:-3])
    with pytest.warns(gv.CacheWarning, match="corrupt"):
        result = gv.run(graph, registry, cache=gv.Cache(None, store))
    assert result.outputs == {"o": 2.0}
    assert result.record.nodes[0].status == "computed"


def test_an_interrupted_write_leaves_no_entry(tmp_path, monkeypatch):
    store = gv.DiskStore(tmp_path)
    import graphvision._cache as cache_module

    def broken(entry):
        yield b"GVC1"
        raise KeyboardInterrupt  # the run is interrupted mid-write

    monkeypatch.setattr(cache_module, "_encode_blob", broken)
    with pytest.raises(KeyboardInterrupt):
        store.put("k", entry([1.0]))
    assert store.get("k") is None
    assert list(tmp_path.rglob("*")) == [tmp_path / "k"] or not any(
        p.is_file() for p in tmp_path.rglob("*")
    )


def test_unwritable_cache_dir_warns_and_runs_without_it(tmp_path, registry):
    blocker = tmp_path / "file"
    blocker.write_text("not a folder")
    with pytest.warns(gv.CacheWarning, match="not writable .*running without the disk cache"):
        assert gv.DiskStore.open(blocker / "cache") is None


def test_disk_store_is_bounded_lru(tmp_path):
    store = gv.DiskStore(tmp_path)
    for i in range(8):
        store.put(f"k{i}", entry(np.zeros(500)))  # ~2 KB each
        os.utime(store.path(f"k{i}"), (1000 + i, 1000 + i))
    store.get("k0")  # touched: now the most recent
    store.prune(10_000)
    info = store.info()
    assert info.bytes <= 10_000
    assert store.contains("k0") and not store.contains("k1")
    assert store.clear() == info.entries and store.info().entries == 0


def test_puts_keep_the_store_within_its_bound(tmp_path):
    store = gv.DiskStore(tmp_path, max_bytes=10_000)
    for i in range(20):
        store.put(f"k{i}", entry(np.zeros(500)))
    assert store.info().bytes <= 10_000
    assert store.contains("k19")


def test_prune_removes_stale_temporary_files(tmp_path):
    store = gv.DiskStore(tmp_path)
    (tmp_path / "ab").mkdir()
    stale = tmp_path / "ab" / ".tmp-x.gvc"
    stale.write_bytes(b"half")
    os.utime(stale, (0, 0))
    store.prune()
    assert not stale.exists()


def test_memory_store_is_bounded_in_bytes():
    store = gv.MemoryStore(max_bytes=1000)
    store.put("a", "A", 400)
    store.put("b", "B", 400)
    store.get("a")
    store.put("c", "C", 400)
    assert store.get("b") is None and store.get("a") == "A" and store.nbytes == 800
    store.put("huge", "H", 5000)
    assert store.get("huge") is None


def test_keys_depend_on_dtype_shape_and_bytes():
    a = np.zeros((4, 4), np.float32)
    keys = {
        content_key(gv.ArrayPort, a),
        content_key(gv.ArrayPort, a.reshape(2, 8)),
        content_key(gv.ArrayPort, a.astype(np.float64)),
        content_key(gv.ArrayPort, a + 1),
    }
    assert len(keys) == 4
    assert content_key(gv.ArrayPort, a) == content_key(gv.ArrayPort, a.copy())

    def key(op="f.g", version=1, code="h", params=None, inputs=None, port="out"):
        fingerprint = node_fingerprint(op, version, code, params or {"s": 1.0, "t": [1, 2]})
        return output_key(fingerprint, inputs or {"image": "k", "mask": "m"}, port)

    base = key()
    assert base == key(params={"t": [1, 2], "s": 1.0}, inputs={"mask": "m", "image": "k"})
    changed = [
        key(op="f.h"),
        key(version=2),
        key(code="h2"),
        key(params={"s": 2.0}),
        key(inputs={"image": "k2", "mask": "m"}),
        key(port="other"),
    ]
    assert len({base, *changed}) == 7


def test_two_processes_share_one_cache_directory(tmp_path):
    """Two runs at once on one folder: both succeed, the entries are whole and agree."""
    script = textwrap.dedent(f"""
        import sys
        import numpy as np
        import graphvision as gv
        graph = gv.load_pipeline({str(tmp_path / "p.yaml")!r})
        cache = gv.Cache(None, gv.DiskStore({str(tmp_path / "cache")!r}))
        result = gv.run(graph, cache=cache, executor="sync")
        np.save(sys.argv[1], result.outputs["smooth"])
    """)
    (tmp_path / "p.yaml").write_text(
        "name: p\ninputs:\n  image: {type: Image, default: 'sample:astronaut'}\nnodes:\n"
        "  g: {op: color.to_gray, in: {image: image}}\n"
        + "".join(
            f"  s{i}: {{op: filters.gaussian, in: {{image: {'g' if i == 0 else f's{i - 1}'}}}}}\n"
            for i in range(6)
        )
        + "outputs: {smooth: s5}\n"
    )
    runs = [
        subprocess.Popen(
            [sys.executable, "-c", script, str(tmp_path / f"out{i}.npy")],
            stderr=subprocess.PIPE,
            text=True,
        )
        for i in range(2)
    ]
    for proc in runs:
        _, err = proc.communicate(timeout=120)
        assert proc.returncode == 0, err
        assert "corrupt" not in err
    np.testing.assert_array_equal(np.load(tmp_path / "out0.npy"), np.load(tmp_path / "out1.npy"))
    store = gv.DiskStore(tmp_path / "cache")
    for path in (tmp_path / "cache").rglob("*.gvc"):
        assert store.get(path.stem) is not None
