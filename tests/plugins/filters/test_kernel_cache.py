"""The compiled kernels of the filters (and of the colour, pyramid, Hough circle and
demosaicing nodes) are cached on disk by numba, so only the first process of a fresh install
compiles them: every dispatcher caches, and a call leaves its index file where numba looks
for it in the next process."""

from __future__ import annotations

import importlib
from pathlib import Path

import numpy as np
import pytest
from numba.core.caching import FunctionCache
from numba.core.registry import CPUDispatcher

from graphvision_plugins import filters

KERNEL_MODULES = [
    "graphvision_plugins.filters._median_kernels",
    "graphvision_plugins.filters._median_select5",
    "graphvision_plugins.filters._median_histogram",
    "graphvision_plugins.filters._correlate_kernels",
    "graphvision_plugins.filters._padded_rows",
    "graphvision_plugins.colour._spaces_kernels",
    "graphvision_plugins.pyramids._pyramid_kernels",
    "graphvision_plugins.hough._circle_kernels",
    "graphvision_plugins.formation._bayer_kernels",
    "graphvision_plugins.shared.separable_kernels",
]


@pytest.mark.parametrize("name", KERNEL_MODULES)
def test_every_kernel_is_cached_on_disk(name):
    module = importlib.import_module(name)
    dispatchers = [
        value
        for value in vars(module).values()
        if isinstance(value, CPUDispatcher) and value.py_func.__module__ == name
    ]
    assert dispatchers, f"no numba kernel found in {name}"
    uncached = [d.py_func.__name__ for d in dispatchers if not isinstance(d._cache, FunctionCache)]
    assert not uncached, f"{name}: compiled again in every process (no cache=True): {uncached}"


@pytest.mark.parametrize(
    ("size", "level"), [(3, 0.3), (5, 0.3), (7, 0.3), (7, 0.0)], ids=["3", "5", "7", "7-levels"]
)
def test_a_median_call_leaves_the_cache_index_the_next_process_reads(size, level):
    """0.3 is no 8-bit level (76.5/255): the 7×7 median takes the network; 0.0 is one,
    and an image of 8-bit levels takes the sliding histogram from 7×7 up."""
    from graphvision_plugins.filters._median_histogram import median_by_histogram
    from graphvision_plugins.filters._median_kernels import median_3x3, median_by_network
    from graphvision_plugins.filters._median_select5 import median_5x5

    filters.median(np.full((9, 9), level, np.float32), size=size)
    kernels = {3: median_3x3, 5: median_5x5, 7: median_by_network}
    kernel = median_by_histogram if level == 0.0 else kernels[size]
    index = Path(kernel._cache._cache_file._index_path)
    assert index.is_file(), f"no numba cache index at {index}"
    # the signature of the call is the one saved (a hit now or a miss written then)
    assert sum(kernel.stats.cache_hits.values()) + sum(kernel.stats.cache_misses.values()) >= 1


def test_the_comparators_are_not_inlined_by_numba_at_each_use():
    """The 5×5 network calls ``lower``/``upper`` at 200 comparators: as numba functions with
    ``inline="always"`` numba copied their code at each (20 s of CPU at the first call in a
    fresh install); as intrinsics they are one compare and select written into the caller."""
    from numba.core.dispatcher import Dispatcher

    from graphvision_plugins.filters import _median_kernels, _median_select5

    for comparator in (_median_kernels.lower, _median_kernels.upper):
        inlined = isinstance(comparator, Dispatcher) and (
            comparator.targetoptions.get("inline") == "always"
        )
        assert not inlined
    assert _median_select5.lower is _median_kernels.lower
