"""The store a cluster shares (fsspec; S3 through a server the test starts): the disk
store's guarantees, over an object store."""

from __future__ import annotations

import uuid
import warnings

import numpy as np
import pytest

import graphvision as gv
from graphvision.cache.entries import CacheWarning, Encoded
from graphvision.cache.format import encode_blob


def _entry(seed: int = 0) -> Encoded:
    values = np.random.default_rng(seed).random((20, 30)).astype(np.float32)
    return Encoded("GrayImage", {"data": values}, {"note": seed})


@pytest.fixture
def store(s3_options):
    return gv.FsspecStore(f"s3://gv-tests/{uuid.uuid4().hex}", storage_options=s3_options)


KEY = "ab" + "0123456789abcdef" * 2


def test_an_entry_comes_back_whole_from_s3_and_in_another_process_form(store):
    entry = _entry(1)
    store.put(KEY, entry)
    got = store.get(KEY)
    np.testing.assert_array_equal(got.arrays["data"], entry.arrays["data"])
    assert got.meta == {"note": 1}  # at the offset modulo 64 the array had when it was stored
    assert got.arrays["data"].ctypes.data % 64 == entry.arrays["data"].ctypes.data % 64
    import pickle

    again = pickle.loads(pickle.dumps(store))  # as it reaches a worker: its URL and options
    np.testing.assert_array_equal(again.get(KEY).arrays["data"], entry.arrays["data"])
    assert store.get("cd" + KEY[2:]) is None
    assert store.info().entries == 1


def test_an_altered_entry_is_dropped_with_a_warning_and_removed(store):
    store.put(KEY, _entry(2))
    blob = bytearray(store.fs.cat_file(store.path(KEY)))
    blob[-1] ^= 0xFF  # one bit of the payload
    store.fs.pipe_file(store.path(KEY), bytes(blob))
    with pytest.warns(CacheWarning, match=r"is corrupt \(digest mismatch"):
        assert store.get(KEY) is None
    assert not store.fs.exists(store.path(KEY))


def test_a_writer_killed_mid_write_leaves_nothing_readable_and_its_leftover_is_pruned(
    store, monkeypatch
):
    blob = b"".join(bytes(c) for c in encode_blob(_entry(3)))
    leftover = f"{store.root}/{KEY[:2]}/.tmp-{uuid.uuid4().hex}.gvc"
    store.fs.pipe_file(leftover, blob[: len(blob) // 2])  # what a killed writer leaves
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # nothing is read from it, so nothing is dropped
        assert store.get(KEY) is None
    assert store.info().entries == 0
    monkeypatch.setattr("graphvision.cache.shared.STALE_TEMP_SECONDS", -1.0)
    store.prune()
    assert not store.fs.exists(leftover)


def test_a_folder_holding_other_files_is_refused_and_left_alone(s3_options):
    import s3fs

    fs = s3fs.S3FileSystem(**s3_options)
    folder = f"gv-tests/{uuid.uuid4().hex}"
    fs.pipe_file(f"{folder}/thesis.tex", b"\\documentclass{article}")
    refused = r"is not a graphvision cache: it holds 'thesis\.tex'"
    with pytest.raises(gv.NotACacheError, match=refused):
        gv.FsspecStore(f"s3://{folder}", storage_options=s3_options)
    assert fs.cat_file(f"{folder}/thesis.tex").startswith(b"\\document")


def test_clear_and_prune_remove_only_the_stores_own_files(store):
    for seed in range(3):
        store.put(f"{seed:02d}" + KEY[2:], _entry(seed))
    store.fs.pipe_file(f"{store.root}/ab/notes.txt", b"mine")  # not of the layout
    size = store.info().bytes
    assert store.prune(max_bytes=size - 1) > 0 and store.info().entries == 2
    assert store.clear() == 2
    assert store.fs.exists(f"{store.root}/ab/notes.txt")


def test_a_run_caches_in_s3_and_a_second_cache_on_the_same_url_reads_it(s3_options):
    url = f"s3://gv-tests/{uuid.uuid4().hex}"
    graph = gv.load_pipeline(gv.__path__[0] + "/../pipelines/coins.yaml")
    first = gv.run(graph, outputs=["count"], cache=gv.Cache.at(url, **s3_options))
    second = gv.run(graph, outputs=["count"], cache=gv.Cache.at(url, **s3_options))
    assert first.outputs["count"] == second.outputs["count"] == 24
    assert {n.status for n in second.record.nodes} == {"cached", "unneeded"}
