"""A cached kernel is compiled again when a kernel it calls in another file changes.

numba's own cache keys a kernel on its file alone: a caller whose callee (in another file)
changed kept loading its old machine code, with the old callee in it, in every new process
(found this session: a kernel measured after an edit ran the code before it).
``graphvision_plugins.shared.jit.njit`` keys the cache on the callees' files too.
"""

from __future__ import annotations

import importlib
import pkgutil
import subprocess
import sys
from pathlib import Path

import pytest
from numba.core.dispatcher import Dispatcher

import graphvision_plugins
from graphvision_plugins.shared.jit import _CalleeAwareCache, _reachable

CALLEE = """from graphvision_plugins.shared.jit import njit


@njit(cache=True, nogil=True)
def leaf(x):
    return x + {step}
"""

MIDDLE = """from graphvision_plugins.shared.jit import njit
from kernels_under_test.leaf import leaf


@njit(cache=True, nogil=True, inline="always")
def middle(x):
    return 2.0 * leaf(x)
"""

CALLER = """from graphvision_plugins.shared.jit import njit
from kernels_under_test import leaf as leaves
from kernels_under_test.middle import middle


@njit(cache=True, nogil=True)
def top(x):
    return middle(x) + leaves.leaf(x)
"""

ASK = "from kernels_under_test.top import top; print(top(1.0), sum(top.stats.cache_hits.values()))"


def _top_in_a_new_process(root: Path) -> tuple[float, int]:
    """``top(1.0)`` and its cache hits, in a fresh interpreter (as a later run would)."""
    done = subprocess.run(
        [sys.executable, "-c", ASK],
        cwd=root,
        capture_output=True,
        text=True,
        check=True,
    )
    value, hits = done.stdout.split()
    return float(value), int(hits)


def test_a_changed_callee_two_files_away_is_compiled_in_again(tmp_path):
    package = tmp_path / "kernels_under_test"
    package.mkdir()
    (package / "__init__.py").write_text("")
    (package / "leaf.py").write_text(CALLEE.format(step="1.0"))
    (package / "middle.py").write_text(MIDDLE)
    (package / "top.py").write_text(CALLER)
    # top(1) = 2 * leaf(1) + leaf(1) = 3 * (1 + step)
    assert _top_in_a_new_process(tmp_path) == (6.0, 0)  # compiled, cached
    assert _top_in_a_new_process(tmp_path) == (6.0, 1)  # loaded from the cache
    (package / "leaf.py").write_text(CALLEE.format(step="10.0"))
    assert _top_in_a_new_process(tmp_path) == (33.0, 0)  # numba's own cache: 6.0, a hit
    assert _top_in_a_new_process(tmp_path) == (33.0, 1)


CONSTANT_READER = """from graphvision_plugins.shared.jit import njit
from kernels_under_test.constants import FACTOR


@njit(cache=True, nogil=True)
def top(x):
    return FACTOR * x
"""


def test_a_changed_constant_imported_from_another_file_is_compiled_in_again(tmp_path):
    """numba compiles a global's value into the kernel: an adversary's case, a constant
    changed in its own file, gave the old value (and graphvision's cache, whose key did
    follow the edit, kept it)."""
    package = tmp_path / "kernels_under_test"
    package.mkdir()
    (package / "__init__.py").write_text("")
    (package / "constants.py").write_text("FACTOR = 2.0\n")
    (package / "top.py").write_text(CONSTANT_READER)
    assert _top_in_a_new_process(tmp_path) == (2.0, 0)
    assert _top_in_a_new_process(tmp_path) == (2.0, 1)
    (package / "constants.py").write_text("FACTOR = 7.0\n")
    assert _top_in_a_new_process(tmp_path) == (7.0, 0)  # numba's own cache: 2.0, a hit


def _plugin_kernels() -> list[tuple[str, str, Dispatcher]]:
    found = []
    for module_info in pkgutil.walk_packages(
        graphvision_plugins.__path__, graphvision_plugins.__name__ + "."
    ):
        if "opencv_backend" in module_info.name:
            continue  # needs OpenCV; it holds no numba kernel
        module = importlib.import_module(module_info.name)
        for name, value in vars(module).items():
            if isinstance(value, Dispatcher) and value.__module__ == module.__name__:
                found.append((module.__name__, name, value))
    return found


def test_every_cached_plugin_kernel_keys_its_cache_on_its_callees():
    kernels = _plugin_kernels()
    assert len(kernels) > 100
    plain = [
        f"{module}.{name}"
        for module, name, kernel in kernels
        if kernel.targetoptions.get("cache", True) is not False
        and type(kernel._cache).__name__ != "NullCache"
        and not isinstance(kernel._cache, _CalleeAwareCache)
    ]
    assert not plain, f"compiled with numba.njit, not graphvision_plugins.shared.jit: {plain}"


@pytest.mark.parametrize(
    ("module", "callee_file"),
    [
        ("geometry._kernels", ("fitting", "_kernels.py")),  # RANSAC's sampling
        ("filters._median_select5", ("filters", "_padded_rows.py")),  # two calls away
    ],
)
def test_the_digest_follows_calls_into_other_files(module, callee_file):
    loaded = importlib.import_module(f"graphvision_plugins.{module}")
    reached = {
        Path(callee.py_func.__code__.co_filename).parts[-2:]
        for kernel in vars(loaded).values()
        if isinstance(kernel, Dispatcher)
        for callee in _reachable(kernel.py_func)
    }
    assert callee_file in reached
