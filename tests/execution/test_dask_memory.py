"""A Dask worker (started with ``MALLOC_TRIM_THRESHOLD_``, as Dask's nanny does) serves
arrays from freed memory instead of a fresh mapping each (graphvision.execution.dask_worker)."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

FAULTS = """
import resource
import numpy as np
from graphvision.execution.dask_worker import keep_freed_memory

def faults():
    began = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
    for _ in range(40):
        np.ones(2**17)  # 1 MiB, made and freed
    return resource.getrusage(resource.RUSAGE_SELF).ru_minflt - began

before = faults()
keep_freed_memory()
faults()  # the heap grows once
print(before, faults())
"""


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="glibc's allocator")
def test_arrays_reuse_freed_memory_on_a_worker_started_with_a_trim_threshold():
    environment = {**os.environ, "MALLOC_TRIM_THRESHOLD_": "65536"}
    done = subprocess.run(
        [sys.executable, "-c", FAULTS], env=environment, capture_output=True, text=True, check=True
    )
    before, after = map(int, done.stdout.split())
    assert before >= 40 * 200  # each 1 MiB array faulted its 256 pages in again
    assert after < 40 * 20  # served from the memory the previous one freed
