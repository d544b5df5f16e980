"""What a batch's worker server imports once for every worker
(graphvision.execution.batch_preload): the modules node functions import inside their
bodies, found from their code before the first file runs."""

from __future__ import annotations

import sys
import textwrap

import pytest

from graphvision.execution.batch_preload import import_modules, lazy_imports

PACKAGE = {
    "__init__.py": "",
    "_kernels.py": "def kernel(x):\n    return x\n",
    "nodes.py": textwrap.dedent(
        """
        import os

        def helper(x):
            from ._kernels import kernel  # a kernel module, on first use
            import json.decoder as decoder
            return kernel(x), decoder

        def node(x):
            return [helper(v) for v in x]  # through a comprehension and a helper

        def other(x):
            import colorsys
            return colorsys
        """
    ),
}


@pytest.fixture
def lazy_package(tmp_path, monkeypatch):
    root = tmp_path / "lazy_pkg_b3"
    root.mkdir()
    for name, text in PACKAGE.items():
        (root / name).write_text(text)
    monkeypatch.syspath_prepend(str(tmp_path))
    import lazy_pkg_b3.nodes

    yield lazy_pkg_b3.nodes
    for name in [m for m in sys.modules if m.startswith("lazy_pkg_b3")]:
        del sys.modules[name]


def test_the_modules_a_node_imports_in_its_body_are_found_through_its_helpers(lazy_package):
    found = lazy_imports([lazy_package.node])
    assert "lazy_pkg_b3._kernels" in found  # relative, in a helper the node calls
    assert "lazy_pkg_b3._kernels.kernel" in found  # may be a module: skipped where imported
    assert "json.decoder" in found
    assert "colorsys" not in found  # a function the node never names
    assert "os" not in found  # imported by the module itself, not in a body


def test_a_second_batch_finds_the_same_modules_without_reading_the_bytecode_again(
    lazy_package, monkeypatch
):
    first = lazy_imports([lazy_package.node])

    def unread(*_: object) -> None:
        raise AssertionError("bytecode read again")

    monkeypatch.setattr("graphvision.execution.batch_preload.dis.get_instructions", unread)
    again = lazy_imports([lazy_package.node])
    assert again == first
    assert again == ["lazy_pkg_b3._kernels", "lazy_pkg_b3._kernels.kernel", "json.decoder"]


def test_each_module_is_imported_on_its_own_whatever_it_raises(tmp_path, monkeypatch):
    (tmp_path / "raising_b3.py").write_text("raise RuntimeError('broken plugin module')\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    names = ["raising_b3", "no_such_module_b3", "json.no_such_part", "colorsys"]
    found = import_modules(names)
    assert [module.__name__ for module in found] == ["colorsys"]


def test_the_coins_nodes_need_scipy_ndimage_and_their_numba_kernel_modules():
    from graphvision.views.report import RUN_PAGES
    from graphvision_plugins.morphology._operators import close
    from graphvision_plugins.regions._label import label
    from graphvision_plugins.threshold._local import local

    modules = lazy_imports([close, label, local, *RUN_PAGES])
    assert "scipy.ndimage" in modules  # morphology's helper imports it in its body
    assert "graphvision_plugins.regions._kernels" in modules  # label's numba kernels
    assert "graphvision_plugins.threshold._kernels" in modules
    assert "graphvision.values.pictures" in modules  # the report pages' thumbnails


def test_the_server_imports_the_batch_modules_and_compiles_its_graph_once(monkeypatch):
    import graphvision as gv
    from graphvision.execution.worker_start import _encoded

    monkeypatch.setattr(sys, "excepthook", sys.excepthook)  # _preload sets the server's
    monkeypatch.delitem(sys.modules, "colorsys", raising=False)
    from graphvision.execution import _preload

    warmed = []
    monkeypatch.setattr(_preload, "warm_graph", lambda *args: warmed.append(args))
    graph = gv.Graph("g")
    graph.output("gray", graph.add("gray", "colour.to_gray", image=graph.input("image", "Image")))
    _preload.start_batch(_encoded(["colorsys", "no_such_module_b3"], (graph, ("p",), ("image",))))
    assert "colorsys" in sys.modules  # and the module that does not exist is skipped
    [(sent, paths, provided)] = warmed
    assert (sent.nodes, sent.outputs, paths, provided) == (
        graph.nodes,
        graph.outputs,
        ("p",),
        ("image",),
    )
