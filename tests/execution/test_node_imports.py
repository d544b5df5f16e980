"""Two nodes importing one package at once, on two threads (graphvision.execution.node_imports).

The fixture is the case met in a cold process (numba's import importing scipy while
another thread imports scipy.ndimage), made deterministic: a package whose ``__init__``
imports a submodule that imports names of the package, imported by one node while the
other imports that submodule. Without the imports made first, in the calling thread, one
node fails on the half-made module and the other with ``KeyError`` naming the package.
"""

from __future__ import annotations

import sys
import uuid
from pathlib import Path

import pytest

import graphvision as gv
from graphvision.execution.executors import call_node_encoded
from graphvision.execution.node_imports import import_ahead

GATE = '''
import sys
import threading
import time

WHOLE_RUNNING = threading.Event()  # the node ``whole`` runs: it imports the package itself


def wait_for(module):
    """Until ``module`` is being imported (by the other node), ten seconds at most."""
    deadline = time.monotonic() + 10
    while module not in sys.modules and time.monotonic() < deadline:
        time.sleep(0.001)
'''

LIBRARY_INIT = """
from {gate} import WHOLE_RUNNING, wait_for

VALUE = 1.0
if WHOLE_RUNNING.is_set():  # imported by the node, not ahead: the other node is next
    wait_for("{lib}.part")  # (a package slow to import, such as scipy on a loaded machine)
from {lib}.part import PART
"""

LIBRARY_PART = """
from {lib} import VALUE

PART = VALUE + 1.0
"""

PLUGIN = '''
from graphvision import Float, node

from {gate} import WHOLE_RUNNING, wait_for


@node("racing.whole")
def whole(x: Float) -> Float:
    """Imports the package in its body.

    Parameters
    ----------
    x : the value
    """
    WHOLE_RUNNING.set()
    from {lib} import VALUE

    return x + VALUE


@node("racing.part")
def part(x: Float) -> Float:
    """Imports the package's submodule in its body, once the package is being imported.

    Parameters
    ----------
    x : the value
    """
    wait_for("{lib}")
    from {lib}.part import PART

    return x + PART
'''


def _racing(tmp_path: Path) -> tuple[gv.Registry, str]:
    """A plugin of the two nodes, over a package and a gate of names of their own."""
    tag = uuid.uuid4().hex[:8]
    lib, gate = f"racing_lib_{tag}", f"racing_gate_{tag}"
    names = {"lib": lib, "gate": gate}
    (tmp_path / lib).mkdir()
    (tmp_path / lib / "__init__.py").write_text(LIBRARY_INIT.format(**names))
    (tmp_path / lib / "part.py").write_text(LIBRARY_PART.format(**names))
    (tmp_path / f"{gate}.py").write_text(GATE)
    plugin = tmp_path / f"racing_{tag}"
    plugin.mkdir()
    (plugin / "__init__.py").write_text(PLUGIN.format(**names))
    sys.path.insert(0, str(tmp_path))
    return gv.discover([plugin], entry_points=False), lib


@pytest.fixture
def racing(tmp_path):
    made = []

    def make() -> tuple[gv.Registry, str]:
        where = tmp_path / f"trial{len(made)}"
        where.mkdir()
        found = _racing(where)
        made.append(str(where))
        return found

    yield make
    for folder in made:
        sys.path.remove(folder)
    for name in [m for m in sys.modules if m.startswith("racing_")]:
        del sys.modules[name]


def _both() -> gv.Graph:
    graph = gv.Graph("racing")
    x = graph.input("x", "Float", default=1.0)
    graph.output("whole", graph.add("whole", "racing.whole", x=x))
    graph.output("part", graph.add("part", "racing.part", x=x))
    return graph


@pytest.mark.parametrize("trial", range(3))
def test_two_nodes_importing_one_package_at_once_on_threads_both_succeed(racing, trial):
    registry, lib = racing()
    result = gv.run(_both(), registry, executor="threads", workers=2, cache=None)
    assert result.outputs == {"whole": 2.0, "part": 3.0}  # VALUE + 1, VALUE + 1 + 1
    assert lib in sys.modules and f"{lib}.part" in sys.modules


def test_the_same_two_nodes_in_a_worker_s_threads_both_succeed(racing):
    """A Dask worker runs tasks on threads of its own: the node's imports are made first
    there too, one thread at a time."""
    from concurrent.futures import ThreadPoolExecutor

    from graphvision.values.scalars import FloatPort

    registry, _ = racing()
    payload = {"x": (FloatPort, *FloatPort.encode(1.0))}
    with ThreadPoolExecutor(2) as pool:
        futures = [
            pool.submit(
                call_node_encoded, registry.nodes[op].ref, {}, payload, {"out": FloatPort}, False
            )
            for op in ("racing.whole", "racing.part")
        ]
        results = [future.result() for future in futures]
    values = [FloatPort.decode(*encoded["out"][1:]) for encoded, _ in results]
    assert values == [2.0, 3.0]


def test_a_cached_node_imports_nothing(racing):
    """Only the nodes that will compute have their modules imported: a warm run does not."""
    registry, lib = racing()
    cache = gv.Cache(gv.MemoryStore())
    gv.run(_both(), registry, cache=cache, executor="threads", workers=2)
    for name in (lib, f"{lib}.part"):
        del sys.modules[name]
    result = gv.run(_both(), registry, cache=cache, executor="threads", workers=2)
    assert result.record.count("cached") == 2
    assert lib not in sys.modules


def test_import_ahead_imports_what_the_bodies_name_and_skips_names_that_are_no_module(
    racing, monkeypatch
):
    registry, lib = racing()
    monkeypatch.delitem(sys.modules, "colorsys", raising=False)
    whole = registry.nodes["racing.whole"].func
    import_ahead([whole], ["colorsys"])
    assert lib in sys.modules and f"{lib}.part" in sys.modules  # the package imports it
    assert "colorsys" in sys.modules  # a library the implementation declares
    assert f"{lib}.VALUE" not in sys.modules  # ``from lib import VALUE``: a name, not a module


TRACED_RUN = """
import sys, threading

first = {}


class Tracer:
    def find_spec(self, name, path=None, target=None):
        first.setdefault(name, threading.current_thread().name)


sys.meta_path.insert(0, Tracer())
import numpy as np
import graphvision as gv

graph = gv.Graph("two")
image = graph.input("image", "GrayImage")
graph.output("local", graph.add("local", "threshold.local", image=image))
graph.output("adaptive", graph.add("adaptive", "threshold.adaptive", image=image))
gray = np.random.default_rng(0).random((64, 64), dtype=np.float32)
gv.run(graph, inputs={"image": gray}, executor="threads", workers=2, cache=None)
names = ["numba", "scipy", "scipy.ndimage", "graphvision_plugins.threshold._kernels"]
print(" ".join(first.get(name, "-") for name in names))
"""


def test_the_threshold_nodes_modules_are_imported_by_the_calling_thread():
    """The case met, on the built-in plugins: ``threshold.local`` imports its kernel module
    (numba, which imports scipy) and ``threshold.adaptive`` scipy.ndimage; both start at
    once on threads. In a fresh process, each of those modules is first imported by the
    thread that called the run (15 runs in 100 failed with ``KeyError: 'scipy'`` before)."""
    import subprocess

    done = subprocess.run(
        [sys.executable, "-c", TRACED_RUN], capture_output=True, text=True, timeout=600
    )
    assert done.stdout.split() == ["MainThread"] * 4, done.stderr


def test_a_graph_run_again_imports_again_what_left_sys_modules_and_only_for_its_steps(racing):
    """The modules of a compiled graph's steps are listed once (``import_ahead_of`` keeps
    the list), and still imported at each run that lacks them; another list of steps of the
    same graph lists its own."""
    from graphvision.execution.node_imports import import_ahead_of

    registry, lib = racing()
    compiled = gv.compile_graph(_both(), registry)
    for _ in range(2):  # the second time from the list made the first
        import_ahead_of(compiled.steps, ["whole", "part"])
        assert lib in sys.modules and f"{lib}.part" in sys.modules
        for name in (lib, f"{lib}.part"):
            del sys.modules[name]
    import_ahead_of(compiled.steps, [])  # no step: nothing (not the list of two)
    assert lib not in sys.modules
    import_ahead_of(compiled.steps, ["whole"])  # ``from lib import VALUE``: the package
    assert lib in sys.modules
