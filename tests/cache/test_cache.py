"""The disk and memory stores: format, verification, atomicity, bounds, concurrency."""

from __future__ import annotations

import hashlib
import json
import os
import subprocess
import sys
import textwrap

import numpy as np
import pytest

import graphvision as gv
from graphvision.cache.entries import Encoded
from graphvision.cache.keys import content_key, output_key
from graphvision.nodes.fingerprint import node_fingerprint


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
    assert raw.startswith(b"GVC3") and b"pickle" not in raw and b"\x80\x04" not in raw[:64]


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
    import graphvision.cache.disk as cache_module

    def broken(entry):
        yield b"GVC3"
        raise KeyboardInterrupt  # the run is interrupted mid-write

    monkeypatch.setattr(cache_module, "encode_blob", broken)
    with pytest.raises(KeyboardInterrupt):
        store.put("k", entry([1.0]))
    assert store.get("k") is None
    assert sorted(p.name for p in tmp_path.rglob("*") if p.is_file()) == ["CACHEDIR.TAG"]


def test_unwritable_cache_dir_warns_and_runs_without_it(tmp_path, registry):
    blocker = tmp_path / "file"
    blocker.write_text("not a folder")
    with pytest.warns(gv.CacheWarning, match="cannot be created .*running without the disk cache"):
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
    assert store.path("k0").exists() and not store.path("k1").exists()
    assert store.clear() == info.entries and store.info().entries == 0


def test_puts_keep_the_store_within_its_bound(tmp_path):
    store = gv.DiskStore(tmp_path, max_bytes=10_000)
    for i in range(20):
        store.put(f"k{i}", entry(np.zeros(500)))
    assert store.info().bytes <= 10_000
    assert store.path("k19").exists()


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


@pytest.mark.parametrize("count", [0, 1, 2, 3])
def test_an_output_key_is_the_blake2b_of_its_documented_text(count):
    """Keys stay those of earlier versions (caches on disk stay valid), however many inputs;
    the text: fingerprint, the inputs as name=key sorted by name and joined by '|', port."""
    inputs = {name: f"key-{name}" for name in ["mask", "image", "b"][:count]}
    text = "fp\n" + "|".join(f"{n}={inputs[n]}" for n in sorted(inputs)) + "\nout"
    expected = hashlib.blake2b(text.encode(), digest_size=20).hexdigest()
    assert output_key("fp", inputs, "out") == expected


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
        "  g: {op: colour.to_gray, in: {image: image}}\n"
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


# -- every byte verified (issue 7, item 1) --------------------------------------------


def _int_entry(tmp_path):
    """A small Int entry, as a coin count is stored; its bytes and its store."""
    store = gv.DiskStore(tmp_path / "cache")
    gv.Cache(None, store).put("c" * 40, gv.IntPort, 24)
    return store, store.path("c" * 40).read_bytes()


def test_every_flipped_byte_is_caught_never_a_wrong_value(tmp_path):
    """Flip each byte of an entry in turn (header, digest, length, magic): always dropped."""
    store, blob = _int_entry(tmp_path)
    path = store.path("c" * 40)
    for offset in range(len(blob)):
        damaged = bytearray(blob)
        damaged[offset] ^= 0x01  # one digit of the count: 24 -> 25 in the header, say
        path.write_bytes(bytes(damaged))
        with pytest.warns(gv.CacheWarning, match="is corrupt"):
            assert gv.Cache(None, store).get("c" * 40, gv.IntPort) == (False, None)
    path.write_bytes(blob)
    assert gv.Cache(None, store).get("c" * 40, gv.IntPort) == (True, 24)


def test_every_truncation_is_caught(tmp_path):
    store, blob = _int_entry(tmp_path)
    path = store.path("c" * 40)
    for length in range(len(blob)):
        path.write_bytes(blob[:length])
        with pytest.warns(gv.CacheWarning, match="is corrupt"):
            assert store.get("c" * 40) is None


def _forged(header) -> bytes:
    """An entry with a valid digest around ``header``: only the structure checks can catch it."""
    import xxhash

    from graphvision.cache.format import _PREFIX, MAGIC

    text = json.dumps(header).encode() if not isinstance(header, bytes) else header
    padding = bytes(-(_PREFIX.size + len(text)) % 64)  # the payload starts at 64 bytes
    payload = np.arange(4, dtype=np.float32).tobytes()
    digest = xxhash.xxh3_128(text + padding + payload).digest()
    return _PREFIX.pack(MAGIC, len(text), digest) + text + padding + payload


GOOD = {
    "type": "Array",
    "meta": {},
    "arrays": [{"name": "data", "dtype": "<f4", "shape": [4], "offset": 0, "nbytes": 16}],
    "payload": 16,
}


@pytest.mark.parametrize(
    ("header", "reason"),
    [
        ([1, 2, 3], "not a JSON object"),
        (b"{not json", "unreadable header"),
        ({**GOOD, "type": None}, "'type' is missing"),
        ({k: v for k, v in GOOD.items() if k != "arrays"}, "'arrays' is missing"),
        ({**GOOD, "payload": 12}, "header says 12"),
        ({**GOOD, "arrays": [{**GOOD["arrays"][0], "shape": [5]}]}, "disagrees with 16 bytes"),
        ({**GOOD, "arrays": [{**GOOD["arrays"][0], "shape": [2], "nbytes": 8}]}, "add up to 8"),
        ({**GOOD, "arrays": [{**GOOD["arrays"][0], "dtype": "|O"}]}, "object dtype"),
        ({**GOOD, "arrays": [{"name": "data"}]}, "malformed"),
    ],
)
def test_a_whole_entry_with_a_bad_structure_is_dropped(tmp_path, header, reason):
    store = gv.DiskStore(tmp_path)
    store.path("k0").parent.mkdir()
    store.path("k0").write_bytes(_forged(header))
    with pytest.warns(gv.CacheWarning, match=reason):
        assert gv.Cache(None, store).get("k0", gv.ArrayPort) == (False, None)
    assert store.get("k0") is None  # dropped from disk too


def test_the_forger_itself_is_right(tmp_path):
    store = gv.DiskStore(tmp_path)
    store.path("k0").parent.mkdir()
    store.path("k0").write_bytes(_forged(GOOD))
    hit, value = gv.Cache(None, store).get("k0", gv.ArrayPort)
    assert hit and value.tolist() == [0.0, 1.0, 2.0, 3.0]


def test_a_shard_folder_replaced_by_a_file_costs_a_warning_not_a_traceback(tmp_path, registry):
    cache = gv.Cache(None, gv.DiskStore(tmp_path))
    cache.put("ab" + "0" * 38, gv.FloatPort, 1.5)
    import shutil

    shutil.rmtree(tmp_path / "ab")
    (tmp_path / "ab").write_text("a file where a shard was")
    with pytest.warns(gv.CacheWarning, match="unreadable"):
        assert cache.get("ab" + "0" * 38, gv.FloatPort) == (False, None)
    with pytest.warns(gv.CacheWarning, match="could not write cache entry"):
        cache.put("ab" + "1" * 38, gv.FloatPort, 2.5)


# -- only its own files (issue 7, item 2) ----------------------------------------------


def _user_folder(root):
    (root / "chapter1").mkdir(parents=True)
    (root / "chapter1" / "figure.png").write_bytes(b"png")
    (root / "thesis.tex").write_text("\\documentclass{book}")
    (root / "ab").mkdir()  # looks like a shard, holds the user's notes
    (root / "ab" / "notes.txt").write_text("notes")
    return sorted(p.relative_to(root) for p in root.rglob("*"))


def test_a_folder_of_user_files_is_refused_and_left_alone(tmp_path):
    before = _user_folder(tmp_path / "thesis")
    with pytest.raises(gv.NotACacheError, match=r"thesis is not a graphvision cache.*'ab'"):
        gv.DiskStore(tmp_path / "thesis")
    with pytest.raises(gv.NotACacheError):
        gv.DiskStore.open(tmp_path / "thesis")
    assert (
        sorted(p.relative_to(tmp_path / "thesis") for p in (tmp_path / "thesis").rglob("*"))
        == before
    )
    (tmp_path / "a-file").write_text("x")
    with pytest.raises(gv.NotACacheError, match="is a file, not a folder"):
        gv.DiskStore(tmp_path / "a-file")


def test_prune_and_clear_remove_only_entries(tmp_path):
    store = gv.DiskStore.open(tmp_path / "cache")
    assert store is not None and (tmp_path / "cache" / "CACHEDIR.TAG").is_file()
    for i in range(5):
        store.put(f"ab{i:038d}", entry(np.zeros(500)))
    strays = [
        tmp_path / "cache" / "ab" / "notes.txt",
        tmp_path / "cache" / "ab" / "zz-other.gvc",
        tmp_path / "cache" / "mine" / "keep.gvc",
        tmp_path / "cache" / "ab" / "sub" / "ab-nested.gvc",
    ]
    for stray in strays:
        stray.parent.mkdir(parents=True, exist_ok=True)
        stray.write_text("not the cache's")
    assert store.prune(0) > 0
    store.put("ab" + "9" * 38, entry(np.zeros(5)))
    assert store.clear() == 1
    assert all(stray.read_text() == "not the cache's" for stray in strays)
    assert (tmp_path / "cache" / "CACHEDIR.TAG").is_file()


def test_a_cache_of_the_older_layout_is_adopted(tmp_path):
    store = gv.DiskStore(tmp_path)
    store.put("ab" + "0" * 38, entry([1.0]))
    (tmp_path / "CACHEDIR.TAG").unlink()
    gv.DiskStore(tmp_path)  # only entries of its layout: adopted, marker written
    assert (tmp_path / "CACHEDIR.TAG").is_file()


# -- size bound and read-only mounts (issue 7, item 5) --------------------------------


@pytest.mark.parametrize("size", [0, -1])
def test_a_size_bound_must_be_positive(tmp_path, size):
    with pytest.raises(ValueError, match="must be positive"):
        gv.DiskStore(tmp_path, max_bytes=size)


def test_a_read_only_cache_is_still_read(tmp_path, monkeypatch, registry):
    graph = gv.Graph("ro")
    graph.output("o", graph.add("o", "toy.add", a=graph.input("x", "Float", default=1.0), b="x"))
    warm = gv.Cache(None, gv.DiskStore.open(tmp_path))
    gv.run(graph, registry, cache=warm)
    import graphvision.cache.disk as cache_module

    def read_only(*args, **kwargs):
        raise OSError(30, "Read-only file system")

    monkeypatch.setattr(cache_module.tempfile, "NamedTemporaryFile", read_only)
    monkeypatch.setattr(cache_module.tempfile, "mkstemp", read_only)
    with pytest.warns(gv.CacheWarning, match="is read-only .*read from it, new results are not"):
        store = gv.DiskStore.open(tmp_path)
    assert store is not None and store.read_only
    result = gv.run(graph, registry, cache=gv.Cache(None, store))
    assert result.record.count("cached") == 1 and result.outputs["o"] == 2.0
    changed = gv.Graph("ro2")
    changed.output(
        "o", changed.add("o", "toy.add", a=changed.input("x", "Float", default=5.0), b="x")
    )
    assert gv.run(changed, registry, cache=gv.Cache(None, store)).outputs["o"] == 10.0


def test_a_folder_given_where_a_store_goes_says_how_to_cache_in_a_folder(tmp_path):
    with pytest.raises(TypeError, match=r"use graphvision.Cache.at\(folder\)"):
        gv.Cache(tmp_path / "cache")
    cache = gv.Cache.at(tmp_path / "cache")
    assert cache.memory is not None and cache.disk is not None
    assert (tmp_path / "cache" / "CACHEDIR.TAG").is_file()


def test_a_pipe_where_an_entry_was_is_a_miss_not_a_wait(registry, tmp_path):
    store = gv.DiskStore(tmp_path)
    graph = gv.Graph("p")
    graph.output("o", graph.add("o", "toy.add", a=graph.input("x", "Float", default=1.0), b="x"))
    gv.run(graph, registry, cache=gv.Cache(None, store))
    (path,) = [p for p in tmp_path.rglob("*.gvc")]
    path.unlink()
    os.mkfifo(path)  # opened plainly, a read waits for a writer for ever
    with pytest.warns(gv.CacheWarning, match="not a regular file"):
        result = gv.run(graph, registry, cache=gv.Cache(None, store))
    assert result.outputs == {"o": 2.0}
    assert result.record.nodes[0].status == "computed"
