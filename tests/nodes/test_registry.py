"""Node registration, plugin discovery, overrides and failures."""

from __future__ import annotations

import os
import subprocess
import sys
import types
from typing import Annotated

import pytest
from pydantic import Field

import graphvision as gv

from ..conftest import FIXTURES


def plugin(**members) -> types.ModuleType:
    module = types.ModuleType("fake_plugin")
    module.__dict__.update(members)
    return module


def reg(func, name="p"):
    registry = gv.Registry()
    registry.add_plugin(plugin(f=func), name)
    return registry


def test_a_node_is_described_without_running(registry):
    spec = registry.node("filters.gaussian")
    info = spec.describe()
    assert info["inputs"] == {"image": {"type": "Image", "optional": False}}
    assert info["outputs"] == {"out": "Image (as connected)"}
    sigma = info["params"]["properties"]["sigma"]
    assert sigma["exclusiveMinimum"] == 0 and sigma["default"] == 1.0
    assert info["params"]["properties"]["boundary"]["enum"] == [
        "mirror",
        "replicate",
        "wrap",
        "zero",
        "crop",
    ]
    assert "3\\sigma" in info["doc"] and spec.version == 1 and spec.plugin == "filters"


@pytest.mark.parametrize(
    ("source", "message"),
    [
        (
            "@gv.node('Bad')\ndef f(x: gv.Float) -> gv.Float:\n    'd'\n",
            "node id must be 'family.name'",
        ),
        ("@gv.node('a.b')\ndef f(x: gv.Float) -> gv.Float:\n    pass\n", "needs a docstring"),
        (
            "@gv.node('a.b')\ndef f(x: int) -> gv.Float:\n    'd'\n",
            "input 'x' must be annotated with a port type",
        ),
        (
            "@gv.node('a.b')\ndef f(x: gv.Float, *, s: float) -> gv.Float:\n    'd'\n",
            "parameter 's' needs a default value",
        ),
        (
            "@gv.node('a.b')\ndef f(x: gv.Float, *, s=1) -> gv.Float:\n    'd'\n",
            "parameter 's' needs a type annotation",
        ),
        ("@gv.node('a.b')\ndef f(x: gv.Float, **kw) -> gv.Float:\n    'd'\n", "are not allowed"),
        (
            "@gv.node('a.b')\ndef f(x: gv.Float) -> float:\n    'd'\n",
            "return annotation must be a port type",
        ),
        (
            "@gv.node('a.b', version=0)\ndef f(x: gv.Float) -> gv.Float:\n    'd'\n",
            "version must be a positive integer",
        ),
        (
            "@gv.node('a.b')\ndef f(x: gv.Float, *, s: int = 'x') -> gv.Float:\n    'd'\n",
            "parameters cannot be validated",
        ),
    ],
)
def test_bad_nodes_are_rejected_naming_plugin_and_function(source, message):
    namespace = {"gv": gv}
    exec(source, namespace)
    with pytest.raises(gv.RegistrationError, match=message) as info:
        reg(namespace["f"], "myplugin")
    assert "plugin 'myplugin', function f at <string>:" in str(info.value)


def test_a_bad_node_registers_nothing_of_its_plugin():
    @gv.node("a.good")
    def good(x: gv.Float) -> gv.Float:
        """Fine."""
        return x

    @gv.node("a.bad")
    def bad(x: int) -> gv.Float:
        """Broken."""
        return x

    registry = gv.Registry()
    with pytest.raises(gv.RegistrationError):
        registry.add_plugin(plugin(good=good, bad=bad), "mixed")
    assert "a.good" not in registry.nodes


def make(id, overrides=False, value=1.0):
    @gv.node(id, overrides=overrides)
    def f(*, v: Annotated[float, Field(ge=0)] = value) -> gv.Float:
        """Constant."""
        return v

    return f


def test_duplicate_ids_name_both_plugins():
    registry = gv.Registry()
    registry.add_plugin(plugin(f=make("x.same")), "first")
    with pytest.raises(
        gv.DuplicateNodeError,
        match=r"defined by plugin 'first' .* and by plugin "
        r"'second' .*overrides=True",
    ):
        registry.add_plugin(plugin(f=make("x.same")), "second")


@pytest.mark.parametrize("override_first", [True, False])
def test_an_override_wins_in_either_order(override_first):
    registry = gv.Registry()
    plugins = [("base", make("x.same", value=1.0)), ("mine", make("x.same", True, value=2.0))]
    for name, func in reversed(plugins) if override_first else plugins:
        registry.add_plugin(plugin(f=func), name)
    assert registry.node("x.same").plugin == "mine"


def test_a_plugin_that_fails_to_import_is_reported_and_others_work(tmp_path):
    (tmp_path / "broken.py").write_text("import not_a_module_anywhere\n")
    (tmp_path / "fine.py").write_text(
        "from graphvision import Float, node\n@node('fine.one')\n"
        "def one() -> Float:\n    'One.'\n    return 1.0\n"
    )
    registry = gv.discover([tmp_path])
    failed = {p.name: p.error for p in registry.failed_plugins()}
    assert list(failed) == [str(tmp_path / "broken.py")]
    assert (
        "ModuleNotFoundError: No module named 'not_a_module_anywhere'"
        in failed[str(tmp_path / "broken.py")]
    )
    assert "fine.one" in registry.nodes and "filters.gaussian" in registry.nodes


def test_missing_plugin_path_is_reported(tmp_path):
    registry = gv.discover([tmp_path / "nope.py"], entry_points=False)
    assert "does not exist" in registry.failed_plugins()[0].error


def test_unknown_op_suggests(registry):
    with pytest.raises(
        gv.UnknownNameError,
        match=r"unknown op 'filters.gausian' \(did you mean "
        r"'filters.gaussian'\?\)",
    ):
        registry.node("filters.gausian")


def test_builtins_come_through_entry_points(registry):
    assert {"io", "colour", "filters", "metrics"} <= set(registry.plugins)
    assert registry.plugins["filters"].origin == "graphvision_plugins.filters"


def test_listing_nodes_does_not_import_heavy_modules():
    code = (
        "import sys, graphvision as gv; r = gv.discover(); assert r.nodes; "
        "print(sorted(m for m in ('scipy.ndimage', 'skimage', 'imageio') if m in sys.modules))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


def test_a_third_party_package_installed_with_pip_is_found(tmp_path):
    target = tmp_path / "site"
    subprocess.run(
        [
            sys.executable,
            "-m",
            "pip",
            "install",
            "--quiet",
            "--no-deps",
            "--no-build-isolation",
            "--target",
            str(target),
            str(FIXTURES / "toy_pkg"),
        ],
        check=True,
        capture_output=True,
    )
    pipeline = tmp_path / "p.yaml"
    pipeline.write_text(
        "name: third\ninputs:\n  image: {type: Image, default: 'sample:camera'}\nnodes:\n"
        "  g: {op: colour.to_gray, in: {image: image}}\n"
        "  inv: {op: thirdparty.invert, in: {image: g}}\n"
        "  again: {op: thirdparty.invert, in: {image: inv}}\n"
        "  diff: {op: metrics.mse, in: {a: g, b: again}}\noutputs: {mse: diff}\n"
    )
    env = dict(os.environ, PYTHONPATH=str(target))
    out = subprocess.run(
        [sys.executable, "-m", "graphvision.cli", "run", str(pipeline), "--no-cache"],
        capture_output=True,
        text=True,
        env=env,
    )
    assert out.returncode == 0, out.stderr
    label, kind, value = out.stdout.split()
    assert (label, kind) == ("mse:", "Float") and float(value) < 1e-12  # 1 - (1 - x) == x
    listing = subprocess.run(
        [sys.executable, "-m", "graphvision.cli", "nodes"], capture_output=True, text=True, env=env
    )
    assert "thirdparty.invert" in listing.stdout


SEVERAL_BAD = '''\
import numpy as np
from graphvision import GrayImage, node


@node("bad.one")
def one(image: np.ndarray) -> GrayImage:
    """One."""


@node("bad.two")
def two(image: GrayImage, sigma: float = 1.0) -> GrayImage:
    """Two."""


@node("bad.three")
def three(image: GrayImage) -> GrayImage:
    return image
'''


def test_every_bad_node_of_a_plugin_is_reported_with_readable_types(tmp_path):
    plugin = tmp_path / "several.py"
    plugin.write_text(SEVERAL_BAD)
    registry = gv.discover([plugin], entry_points=False)
    (failure,) = registry.failed_plugins()
    assert "3 nodes of plugin" in failure.error
    assert f"function one at {plugin}:5" in failure.error and "got numpy.ndarray;" in failure.error
    assert (
        "input 'sigma' must be annotated with a port type (e.g. Image), got float;" in failure.error
    )
    assert "function three" in failure.error and "needs a docstring" in failure.error


def test_an_op_of_a_family_no_plugin_provides_says_how_to_load_one(registry):
    """A forgotten --plugins: the family is named, with the three ways to load a plugin
    (before, the closest op of another family was suggested)."""
    with pytest.raises(gv.UnknownNameError) as caught:
        registry.node("mine.vignette")
    message = str(caught.value)
    assert "no loaded plugin provides the family 'mine'" in message
    assert "--plugins PATH" in message and "gv.discover([PATH])" in message
    assert "formation.vignette" not in message


def test_a_renamed_op_names_its_new_id(tmp_path):
    plugin = tmp_path / "renaming.py"
    plugin.write_text(
        "from graphvision import Float, node\n"
        'RENAMED_OPS = {"old.one": "renaming.one"}\n'
        '__all__ = ["one", "RENAMED_OPS"]\n'
        '@node("renaming.one")\n'
        "def one() -> Float:\n"
        '    """One."""\n'
        "    return 1.0\n"
    )
    registry = gv.discover([plugin], entry_points=False)
    with pytest.raises(gv.UnknownNameError, match=r"op 'old\.one' was renamed 'renaming\.one'"):
        registry.node("old.one")
    graph = gv.Graph("g")
    graph.output("o", graph.add("o", "old.one"))
    with pytest.raises(gv.PipelineError, match=r"was renamed 'renaming\.one'"):
        gv.compile_graph(graph, registry)
