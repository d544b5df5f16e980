"""Running graphs: pruning, parallelism, failures, caching, executors."""

from __future__ import annotations

import numpy as np
import pytest

import graphvision as gv


def chain(registry):
    graph = gv.Graph("chain")
    x = graph.input("x", "Float", default=1.0)
    a = graph.add("a", "toy.add", a=x, b=x)  # 2
    b = graph.add("b", "toy.add", params={"offset": 1.0}, a=a, b=a)  # 5
    c = graph.add("c", "toy.add", a=x, b=x, params={"offset": 10.0})  # 12
    graph.output("b", b)
    graph.output("c", c)
    return graph


def statuses(record):
    return {n.name: n.status for n in record.nodes}


def test_values_and_record(registry):
    result = gv.run(chain(registry), registry)
    assert result.outputs == {"b": 5.0, "c": 12.0}
    assert statuses(result.record) == {"a": "computed", "b": "computed", "c": "computed"}
    assert all(n.seconds >= 0 for n in result.record.nodes)


def test_only_what_requested_outputs_need_runs(registry):
    result = gv.run(chain(registry), registry, outputs=["c"])
    assert result.outputs == {"c": 12.0}
    assert statuses(result.record) == {"c": "computed"}
    with pytest.raises(gv.UnknownNameError, match=r"unknown output 'cc' \(did you mean 'c'\?\)"):
        gv.run(chain(registry), registry, outputs=["cc"])


def test_a_compiled_graph_runs_every_output_and_refuses_an_unknown_input(registry):
    """Run as compiled, with no output named: every output, and an input it does not declare
    named (as on a graph compiled for the run)."""
    compiled = gv.compile_graph(chain(registry), registry)
    for _ in range(2):  # (the second from what the first made once)
        result = gv.run(compiled, registry, inputs={"x": 2.0})
        assert result.outputs == {"b": 9.0, "c": 14.0} and list(result.outputs) == ["b", "c"]
    with pytest.raises(gv.UnknownNameError, match=r"unknown input 'y'; inputs: x$"):
        gv.run(compiled, registry, inputs={"x": 2.0, "y": 1.0})


def test_inputs_override_defaults(registry):
    assert gv.run(chain(registry), registry, inputs={"x": 2.0}).outputs == {"b": 9.0, "c": 14.0}
    assert gv.run(chain(registry), registry, inputs={"x": "3"}).outputs["c"] == 16.0
    with pytest.raises(gv.InputError, match=r"input 'x': expected Float \(float\), got str 'a'"):
        gv.run(chain(registry), registry, inputs={"x": "'a'"})


def test_multi_output_ports(registry):
    graph = gv.Graph("split")
    s = graph.add("s", "toy.split", x=graph.input("x", "Float", default=5.0))
    graph.output("low", s["low"])
    graph.output("high", s["high"])
    assert gv.run(graph, registry).outputs == {"low": 4.0, "high": 6.0}


def test_independent_branches_run_at_the_same_time(registry):
    graph = gv.Graph("par")
    x = graph.input("x", "Float", default=1.0)
    graph.output("p", graph.add("p", "toy.rendezvous", x=x))
    graph.output("q", graph.add("q", "toy.rendezvous", x=x))
    # Each node blocks until the other one runs: a serial scheduler would time out.
    result = gv.run(graph, registry, executor="threads", workers=2)
    assert result.outputs == {"p": 1.0, "q": 1.0}


def failing_graph():
    graph = gv.Graph("fails")
    x = graph.input("x", "Float", default=1.0)
    bad = graph.add("bad", "toy.fail", params={"message": "no luck"}, x=x)
    graph.output("after", graph.add("after", "toy.add", a=bad, b=x))
    graph.output("slow", graph.add("slow", "toy.sleep", params={"seconds": 0.1}, x=x))
    graph.output("other", graph.add("other", "toy.add", a=graph.add("o1", "toy.const"), b=x))
    return graph


def test_a_failing_node_is_named_with_params_and_inputs(registry):
    with pytest.raises(gv.RunError) as info:
        gv.run(failing_graph(), registry, executor="sync")
    error = info.value.failures["bad"]
    assert isinstance(error, gv.NodeExecutionError)
    assert "node 'bad' (op toy.fail) failed: RuntimeError: no luck" in str(error)
    assert "params: {'message': 'no luck'}" in str(error)
    assert "inputs: x=Float 1.0" in str(error)
    assert isinstance(error.__cause__, RuntimeError)
    assert statuses(info.value.record)["after"] == "skipped"


def test_keep_going_finishes_and_caches_independent_branches(registry, cache):
    with pytest.raises(gv.RunError) as info:
        gv.run(failing_graph(), registry, keep_going=True, cache=cache)
    result = info.value.result
    assert result.outputs == {"slow": 1.0, "other": 2.0}
    assert statuses(result.record) == {
        "bad": "failed",
        "after": "skipped",
        "slow": "computed",
        "o1": "computed",
        "other": "computed",
    }
    again = gv.run(failing_graph(), registry, outputs=["other"], cache=cache)
    assert statuses(again.record) == {"o1": "unneeded", "other": "cached"}


def test_invalid_node_output_is_a_node_failure(registry):
    graph = gv.Graph("bad")
    graph.output("o", graph.add("o", "toy.bad_output", x=graph.input("x", "Float", default=1.0)))
    with pytest.raises(gv.RunError, match=r"invalid output 'out': expected GrayImage"):
        gv.run(graph, registry)


@pytest.mark.parametrize("executor", ["sync", "threads", "processes"])
def test_nodes_cannot_change_their_inputs(registry, executor):
    graph = gv.Graph("mutate")
    image = graph.input("image", "GrayImage")
    graph.output("o", graph.add("o", "toy.mutate", image=image))
    with pytest.raises(gv.RunError, match="read-only"):
        gv.run(graph, registry, inputs={"image": np.ones((4, 4), np.float32)}, executor=executor)


@pytest.mark.parametrize("executor", ["sync", "threads", "processes"])
def test_nodes_cannot_change_their_inputs_in_any_file_of_a_batch(registry, executor, tmp_path):
    """On processes, arrays arrive unpickled over writable bytes: they are copied into
    immutable memory too (the first file failed, the others wrote zeros and succeeded)."""
    import imageio.v3 as iio

    for i in range(3):
        iio.imwrite(tmp_path / f"{i}.png", np.full((4, 5), 60 * i + 10, np.uint8))
    graph = gv.Graph("mutate")
    graph.output("o", graph.add("o", "toy.mutate", image=graph.input("image", "GrayImage")))
    batch = gv.run_batch(
        graph, str(tmp_path / "*.png"), input="image", output_dir=tmp_path / "out",
        registry=registry, executor=executor,
    )  # fmt: skip
    assert [item.status for item in batch.items] == ["failed"] * 3
    assert all("read-only" in (item.error or "") for item in batch.items)


@pytest.mark.parametrize("executor", ["threads", "processes"])
def test_a_node_that_forces_its_input_writable_fails_alone(registry, executor, tmp_path):
    """Setting flags on the value and its bases cannot make it writable: the node fails,
    naming itself; the sibling branch, the cache and the caller's array are untouched."""
    graph = gv.Graph("force")
    gray = graph.add("gray", "toy.darken", image=graph.input("image", "GrayImage"))
    graph.output("bad", graph.add("bad", "toy.force_mutate", image=gray))
    graph.output("good", graph.add("good", "toy.darken", image=gray, params={"factor": 1.0}))
    given = np.full((4, 4), 0.5, np.float32)
    cache = gv.Cache(gv.MemoryStore(), gv.DiskStore(tmp_path))
    with pytest.raises(gv.RunError) as caught:
        gv.run(
            graph,
            registry,
            inputs={"image": given},
            cache=cache,
            executor=executor,
            keep_going=True,
        )
    assert list(caught.value.failures) == ["bad"]
    assert "toy.force_mutate" in str(caught.value.failures["bad"])
    result = caught.value.result
    np.testing.assert_array_equal(result.outputs["good"], np.full((4, 4), 0.25, np.float32))
    np.testing.assert_array_equal(given, np.full((4, 4), 0.5, np.float32))
    again = gv.run(
        graph,
        registry,
        inputs={"image": given},
        cache=gv.Cache(None, gv.DiskStore(tmp_path)),
        outputs=["good"],
    )
    np.testing.assert_array_equal(again.outputs["good"], np.full((4, 4), 0.25, np.float32))
    assert statuses(again.record) == {"gray": "unneeded", "good": "cached"}


def test_changing_one_parameter_recomputes_only_what_depends_on_it(registry, cache):
    graph = chain(registry)
    gv.run(graph, registry, cache=cache)
    result = gv.run(graph, registry, cache=cache, overrides={"b.offset": 2.0})
    assert result.outputs == {"b": 6.0, "c": 12.0}
    assert statuses(result.record) == {"a": "cached", "b": "computed", "c": "cached"}


def test_a_warm_run_reads_only_the_requested_outputs(registry, cache):
    graph = chain(registry)
    gv.run(graph, registry, cache=cache)
    fresh = gv.Cache(None, cache.disk)  # a new process: memory empty, disk warm
    result = gv.run(graph, registry, cache=fresh)
    assert statuses(result.record) == {"a": "unneeded", "b": "cached", "c": "cached"}
    assert result.outputs == {"b": 5.0, "c": 12.0}  # 'a' is never read


def test_a_warm_runs_record_lists_the_cached_nodes_ancestors_as_unneeded(registry, cache):
    """A tryer's finding: a warm run's record listed only 'b' and 'c'; 'a', which the run
    needed no more once 'b' was loaded, was missing from the record and its table."""
    graph = chain(registry)
    cold = gv.run(graph, registry, cache=cache)
    warm = gv.run(graph, registry, cache=cache)
    assert [(n.name, n.status) for n in warm.record.nodes] == [
        ("a", "unneeded"), ("b", "cached"), ("c", "cached"),
    ]  # fmt: skip
    a = warm.record.nodes[0]
    assert (a.seconds, a.output_bytes, a.error) == (0.0, 0, "")
    assert a.keys == cold.record.nodes[0].keys  # the key it would have had
    assert "0 computed, 2 cached, 0 failed, 0 skipped, 1 unneeded" in warm.record.table()
    only_c = gv.run(graph, registry, cache=cache, outputs=["c"])  # 'a' is not in this run
    assert statuses(only_c.record) == {"c": "cached"}


def test_cache_opt_out(registry, cache):
    graph = gv.Graph("v")
    graph.output("o", graph.add("o", "toy.volatile", x=graph.input("x", "Float", default=2.0)))
    gv.run(graph, registry, cache=cache)
    assert statuses(gv.run(graph, registry, cache=cache).record) == {"o": "computed"}


def test_input_content_is_the_key(registry, cache):
    graph = gv.Graph("k")
    graph.output("o", graph.add("o", "toy.darken", image=graph.input("image", "GrayImage")))
    image = np.full((8, 8), 0.5, np.float32)
    gv.run(graph, registry, cache=cache, inputs={"image": image})
    same = gv.run(graph, registry, cache=cache, inputs={"image": image.copy()})
    assert statuses(same.record) == {"o": "cached"}
    changed = image.copy()
    changed[3, 3] = 0.25
    assert statuses(gv.run(graph, registry, cache=cache, inputs={"image": changed}).record) == {
        "o": "computed"
    }
    reshaped = gv.run(graph, registry, cache=cache, inputs={"image": image.reshape(4, 16)})
    assert statuses(reshaped.record) == {"o": "computed"}


def test_editing_a_node_invalidates_its_entries(tmp_path, cache):
    plugin = tmp_path / "editable.py"
    source = (
        "from graphvision import Float, node\n\n@node('edit.f')\n"
        "def f(x: Float) -> Float:\n    '''Doc.'''\n    return x + {}\n"
    )
    graph = gv.Graph("e")
    graph.output("o", graph.add("o", "edit.f", x=graph.input("x", "Float", default=1.0)))
    plugin.write_text(source.format(1))
    first = gv.discover([plugin], entry_points=False)
    assert gv.run(graph, first, cache=cache).outputs["o"] == 2.0
    plugin.write_text(source.format(5).replace("'''Doc.'''", "'''Edited doc.'''  # comment"))
    second = gv.discover([plugin], entry_points=False)
    result = gv.run(graph, second, cache=cache)
    assert result.outputs["o"] == 6.0
    assert statuses(result.record) == {"o": "computed"}


def test_docstring_comment_and_position_edits_keep_the_fingerprint(registry):
    from graphvision.nodes.fingerprint import code_fingerprint

    def add(a, b, *, offset=0.0):
        return a + b + offset

    def add_documented(a, b, *, offset=0.0):
        """Documented."""
        # a comment

        return a + b + offset

    def add_changed(a, b, *, offset=0.0):
        return a + b - offset

    assert code_fingerprint(add) == code_fingerprint(add_documented)
    assert code_fingerprint(add) != code_fingerprint(add_changed)
    assert len(registry.node("toy.add").source_hash) == 32


HELPERS = """
from graphvision import Float, node

SCALE = {scale}


def helper(x):
    return x * SCALE


def other_helper(x):
    return x - 1.0


@node("helped.uses_helper")
def uses_helper(x: Float) -> Float:
    \"\"\"Calls the helper.

    Parameters
    ----------
    x : the value
    \"\"\"
    return helper(x) + {offset}


@node("helped.independent")
def independent(x: Float) -> Float:
    \"\"\"Calls another helper.

    Parameters
    ----------
    x : the value
    \"\"\"
    return other_helper(x)
"""


@pytest.mark.parametrize(
    ("edit", "changed"),
    [
        ({"scale": 3.0, "offset": 0.0}, {"helped.uses_helper"}),  # a constant a helper reads
        ({"scale": 2.0, "offset": 1.0}, {"helped.uses_helper"}),  # the node itself
        ({"scale": 2.0, "offset": 0.0}, set()),  # nothing
    ],
)
def test_editing_a_helper_invalidates_its_callers_and_no_others(tmp_path, edit, changed):
    """Edit a local plugin and discover() again in the same process: keys follow the code."""
    plugin = tmp_path / "helped.py"
    plugin.write_text(HELPERS.format(scale=2.0, offset=0.0))
    before = gv.discover([plugin], entry_points=False)
    plugin.write_text(HELPERS.format(**edit) + "\n# an edit elsewhere in the file\n")
    after = gv.discover([plugin], entry_points=False)
    differ = {
        op
        for op in ("helped.uses_helper", "helped.independent")
        if before.node(op).source_hash != after.node(op).source_hash
    }
    assert differ == changed
    graph = gv.Graph("h")
    graph.output(
        "o", graph.add("o", "helped.uses_helper", x=graph.input("x", "Float", default=1.0))
    )
    expected = 1.0 * edit["scale"] + edit["offset"]
    assert gv.run(graph, after, cache=None).outputs["o"] == expected


def test_an_installed_plugin_fingerprint_includes_its_distribution_version(registry):
    from graphvision.nodes.fingerprint import _distribution_version

    assert _distribution_version("graphvision_plugins").startswith("graphvision==")


@pytest.mark.parametrize("executor", ["sync", "threads", "processes"])
def test_every_executor_gives_the_same_results(registry, executor):
    graph = gv.parse_pipeline(
        "name: p\ninputs:\n  image: {type: Image, default: 'sample:camera'}\nnodes:\n"
        "  g: {op: colour.to_gray, in: {image: image}}\n"
        "  s: {op: filters.gaussian, in: {image: g}, params: {sigma: 2.0}}\n"
        "  m: {op: filters.median, in: {image: g}}\n"
        "  q: {op: metrics.psnr, in: {a: s, b: m}}\n"
        "outputs: {smooth: s, psnr: q}\n"
    )
    result = gv.run(graph, registry, executor=executor, workers=2)
    reference = gv.run(graph, registry, executor="sync")
    np.testing.assert_array_equal(result.outputs["smooth"], reference.outputs["smooth"])
    assert result.outputs["psnr"] == reference.outputs["psnr"]
    assert result.record.executor == executor


def test_process_executor_runs_local_plugin_nodes(registry):
    result = gv.run(chain(registry), registry, executor="processes", workers=2)
    assert result.outputs == {"b": 5.0, "c": 12.0}


class Recorder(gv.RunHooks):
    def __init__(self):
        self.events = []

    def run_started(self, *, pipeline, steps):
        self.events.append(("start", pipeline, tuple(steps)))

    def node_finished(self, *, name, op, status, seconds):
        self.events.append(("node", name, status))

    def run_finished(self, *, record, failed):
        self.events.append(("end", failed))


def test_hooks_see_the_run_and_the_finish_even_on_failure(registry):
    hooks = Recorder()
    gv.run(chain(registry), registry, hooks=[hooks], executor="sync")
    assert hooks.events[0] == ("start", "chain", ("a", "b", "c"))
    assert hooks.events[-1] == ("end", False)
    failing = Recorder()
    with pytest.raises(gv.RunError):
        gv.run(failing_graph(), registry, hooks=[failing], executor="sync")
    assert ("node", "bad", "failed") in failing.events
    assert failing.events[-1] == ("end", True)


def test_overrides_apply_to_a_compiled_graph_too(registry):
    compiled = gv.compile_graph(chain(registry), registry)
    result = gv.run(compiled, registry, overrides={"b.offset": 2.0})
    assert result.outputs == {"b": 6.0, "c": 12.0}


def test_hooks_hear_of_cache_hits(registry, cache):
    heard: list[tuple[str, str]] = []

    class Listen(gv.RunHooks):
        def node_finished(self, *, name, op, status, seconds):
            heard.append((name, status))

    gv.run(chain(registry), registry, cache=cache)
    gv.run(chain(registry), registry, cache=cache, overrides={"c.offset": 3.0}, hooks=[Listen()])
    assert sorted(heard) == [("b", "cached"), ("c", "computed")]


def test_only_nodes_downstream_of_a_failure_are_called_skipped(registry):
    graph = gv.Graph("fails")
    x = graph.input("x", "Float", default=1.0)
    bad = graph.add("bad", "toy.fail", x=x)
    graph.output("after", graph.add("after", "toy.add", a=bad, b=bad))
    graph.output("other", graph.add("other", "toy.add", a=x, b=x))
    with pytest.raises(gv.RunError) as caught:
        gv.run(graph, registry, keep_going=True, executor="sync")
    assert statuses(caught.value.record) == {
        "bad": "failed",
        "after": "skipped",
        "other": "computed",
    }


def test_a_fully_cached_run_does_not_load_a_sample_input(tmp_path):
    """sample:NAME is keyed by its name and scikit-image's version: a warm run never loads it."""
    import subprocess
    import sys

    script = (
        "import sys, graphvision as gv\n"
        f"cache = gv.Cache(None, gv.DiskStore({str(tmp_path)!r}))\n"
        "g = gv.Graph('s')\n"
        "image = g.input('image', 'Image', default='sample:camera')\n"
        "g.output('gray', g.add('gray', 'colour.to_gray', image=image))\n"
        "result = gv.run(g, cache=cache)\n"
        "print(result.record.count('cached'), 'skimage.data' in sys.modules)\n"
    )
    first = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True)
    second = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True)
    assert first.stdout.split() == ["0", "True"], first.stderr
    assert second.stdout.split() == ["1", "False"], second.stderr


LAZY_PACKAGE = '''
from graphvision import Float, node


@node("lazy.uses_kernel")
def uses_kernel(x: Float) -> Float:
    """Imports its kernel on first use, as the compiled kernels of the built-in families do.

    Parameters
    ----------
    x : the value
    """
    from ._kernel import scaled

    return scaled(x)


@node("lazy.plain")
def plain(x: Float) -> Float:
    """Imports nothing.

    Parameters
    ----------
    x : the value
    """
    return x + 1.0
'''


def test_editing_a_module_imported_inside_a_node_invalidates_that_node_only(tmp_path):
    """A kernel module imported in the node's body (not at the top) is part of its code."""
    import sys

    from graphvision.nodes.fingerprint import _MEMO, code_fingerprint

    package = tmp_path / "lazy"
    package.mkdir()
    (package / "__init__.py").write_text(LAZY_PACKAGE)
    (package / "_kernel.py").write_text("def scaled(x):\n    return 2.0 * x\n")
    before = gv.discover([package], entry_points=False)
    uses = before.node("lazy.uses_kernel")
    kernel_module = uses.func.__module__ + "._kernel"
    assert kernel_module not in sys.modules  # not imported yet: fingerprinted from its file
    first = code_fingerprint(uses.func)
    uses.func(1.0)  # now it is imported
    assert kernel_module in sys.modules
    _MEMO.pop(uses.func, None)
    assert code_fingerprint(uses.func) == first  # the same whether imported or not
    (package / "_kernel.py").write_text("def scaled(x):\n    return 3.0 * x\n")
    after = gv.discover([package], entry_points=False)
    assert after.node("lazy.uses_kernel").source_hash != uses.source_hash
    assert after.node("lazy.plain").source_hash == before.node("lazy.plain").source_hash
    graph = gv.Graph("lazy")
    graph.output("o", graph.add("o", "lazy.uses_kernel", x=graph.input("x", "Float", default=1.0)))
    assert gv.run(graph, after, cache=None).outputs["o"] == 3.0


def test_editing_a_module_that_the_kernel_module_imports_invalidates_the_node(tmp_path):
    """The files the kernel module imports from the project are its code too, followed to
    the end: a kernel calling a kernel of another file (a tryer's case: an edit of RANSAC's
    sampling in fitting/_kernels.py kept the homography node's key, and its stale value)."""
    package = tmp_path / "lazy"
    package.mkdir()
    (package / "__init__.py").write_text(LAZY_PACKAGE)
    (package / "_kernel.py").write_text(
        "from ._middle import factor\n\n\ndef scaled(x):\n    return factor() * x\n"
    )
    (package / "_middle.py").write_text(
        "def factor():\n    from ._leaf import LEAF\n\n    return LEAF\n"
    )
    (package / "_leaf.py").write_text("LEAF = 2.0\n")
    before = gv.discover([package], entry_points=False)
    hashes = {op: before.node(op).source_hash for op in ("lazy.uses_kernel", "lazy.plain")}
    (package / "_leaf.py").write_text("LEAF = 5.0\n")  # two files away from the node's body
    after = gv.discover([package], entry_points=False)
    assert after.node("lazy.uses_kernel").source_hash != hashes["lazy.uses_kernel"]
    assert after.node("lazy.plain").source_hash == hashes["lazy.plain"]
    again = gv.discover([package], entry_points=False)  # nothing edited: the same key
    assert again.node("lazy.uses_kernel").source_hash == after.node("lazy.uses_kernel").source_hash


THREAD_PLUGIN = '''
import threading
from graphvision import Float, node

BARRIER = threading.Barrier(2, timeout=10)
THREADS = []


@node("threads.meet")
def meet(x: Float) -> Float:
    """Waits until a second node waits too (so only nodes running at once finish).

    Parameters
    ----------
    x : the value
    """
    BARRIER.wait()
    return x


@node("threads.where")
def where(x: Float) -> Float:
    """Notes the thread it runs in.

    Parameters
    ----------
    x : the value
    """
    THREADS.append(threading.current_thread())
    return x
'''


def _thread_nodes(tmp_path):
    plugin = tmp_path / "threads_plugin.py"
    plugin.write_text(THREAD_PLUGIN)
    return gv.discover([plugin])


def test_slow_nodes_run_at_once_on_threads(tmp_path):
    registry = _thread_nodes(tmp_path)
    graph = gv.Graph("meet")
    x = graph.input("x", "Float", default=1.0)
    for name in ("a", "b"):
        graph.output(name, graph.add(name, "threads.meet", x=x))
    result = gv.run(graph, registry, executor="threads", workers=2)
    assert result.outputs == {"a": 1.0, "b": 1.0}  # each waited for the other


def test_quick_nodes_run_in_the_calling_thread(tmp_path):
    """A hand-off to a thread costs more than a trivial node: after the first ones show
    they are quick, the rest run in the scheduler's own thread."""
    import sys
    import threading

    registry = _thread_nodes(tmp_path)
    graph = gv.Graph("where")
    x = graph.input("x", "Float", default=1.0)
    for k in range(200):
        graph.output(f"o{k}", graph.add(f"n{k}", "threads.where", x=x))
    gv.run(graph, registry, executor="threads", workers=2)
    threads = sys.modules[registry.nodes["threads.where"].ref.module].THREADS
    here = sum(thread is threading.current_thread() for thread in threads)
    assert len(threads) == 200 and here >= 150


def test_a_value_an_earlier_run_wrote_as_npz_is_an_input_of_its_type(tmp_path):
    """Keypoints (an .npz and its .json header) written by one run are read back by the next."""
    keypoints = gv.KeypointSet(
        xy=np.array([[3.0, 4.0], [10.5, 2.25]]),
        scale=np.array([1.6, 3.2]),
        orientation=np.array([0.0, 1.0]),
        response=np.array([0.5, 0.25]),
    )
    files = gv.KeypointsPort.write(keypoints, tmp_path / "keypoints")
    assert {f.suffix for f in files} >= {".npz"}
    graph = gv.Graph("again")
    graph.output("same", graph.input("kp", "Keypoints"))
    archive = next(f for f in files if f.suffix == ".npz")
    result = gv.run(graph, inputs={"kp": str(archive)})
    np.testing.assert_array_equal(result.outputs["same"].xy, keypoints.xy)
    np.testing.assert_array_equal(result.outputs["same"].scale, keypoints.scale)


def test_an_npz_that_is_not_of_the_inputs_type_is_named(tmp_path):
    np.savez(tmp_path / "other.npz", something=np.zeros(3))
    graph = gv.Graph("again")
    graph.output("same", graph.input("kp", "Keypoints"))
    with pytest.raises(gv.InputError, match=r"input 'kp': .*other\.npz is not a Keypoints"):
        gv.run(graph, inputs={"kp": str(tmp_path / "other.npz")})


SIZED_PLUGIN = '''
import threading
import time
from graphvision import Float, node

MAIN = []


@node("sized.work")
def work(x: Float, then: Float) -> Float:
    """At once for a small x, 0.3 s for a large one; notes whether it ran in the main thread.

    Parameters
    ----------
    x : the size
    then : read only to run after the node that gives it
    """
    if x > 10:
        MAIN.append(threading.current_thread() is threading.main_thread())
        time.sleep(0.3)
    return x
'''


def test_an_op_quick_on_small_inputs_does_not_run_its_slow_calls_one_after_another(tmp_path):
    """One slow call in the loop's thread shows the op is not quick; the others go to threads."""
    import sys

    plugin = tmp_path / "sized_plugin.py"
    plugin.write_text(SIZED_PLUGIN)
    registry = gv.discover([plugin])
    graph = gv.Graph("sized")
    s = graph.input("s", "Float", default=1.0)
    small = graph.add("small", "sized.work", x=s, then=s)
    big = graph.input("b", "Float", default=100.0)
    graph.output("small", small)
    for k in range(4):  # ready together once the small one has shown the op quick
        graph.output(f"big{k}", graph.add(f"big{k}", "sized.work", x=big, then=small))
    gv.run(graph, registry, executor="threads", workers=2)
    ran_here = sys.modules[registry.nodes["sized.work"].ref.module].MAIN
    assert len(ran_here) == 4 and sum(ran_here) <= 1


EXITING_PLUGIN = '''
from graphvision import Float, node


@node("exiting.quit")
def quit_(x: Float) -> Float:
    """Calls sys.exit, as a careless script might.

    Parameters
    ----------
    x : the value
    """
    raise SystemExit(3)
'''


@pytest.mark.parametrize("executor", ["sync", "threads"])
def test_a_node_that_exits_fails_alone_naming_itself(tmp_path, executor):
    plugin = tmp_path / "exiting.py"
    plugin.write_text(EXITING_PLUGIN)
    graph = gv.Graph("exits")
    x = graph.input("x", "Float", default=1.0)
    graph.output("bad", graph.add("bad", "exiting.quit", x=x))
    graph.output("same", x)
    with pytest.raises(gv.RunError) as caught:
        gv.run(graph, gv.discover([plugin]), executor=executor, keep_going=True)
    assert list(caught.value.failures) == ["bad"] and "SystemExit" in str(caught.value)
    assert caught.value.result.outputs == {"same": 1.0}


def test_an_input_whose_port_check_breaks_on_hostile_data_is_named(tmp_path):
    class Fragile(gv.PortType):
        @classmethod
        def validate(cls, value):
            return value.missing_attribute

    registry = gv.discover()
    registry.port_types["Fragile"] = Fragile
    graph = gv.Graph("fragile")
    graph.output("same", graph.input("x", "Fragile"))
    with pytest.raises(gv.InputError, match=r"input 'x': not a valid Fragile \(AttributeError"):
        gv.run(graph, registry, inputs={"x": 1.0})


def test_a_compiled_graph_run_again_keys_each_run_by_its_own_inputs(registry, tmp_path):
    """The keys of a compiled graph's last run are reused only for inputs of the same keys:
    a run on other inputs, or of fewer outputs, keys its values as a fresh graph would."""
    compiled = gv.compile_graph(chain(registry), registry)

    def keys(result):
        return {n.name: n.keys for n in result.record.nodes}

    fresh = {x: keys(gv.run(chain(registry), registry, inputs={"x": x})) for x in (1.0, 2.0)}
    assert fresh[1.0] != fresh[2.0]
    for x in (1.0, 2.0, 1.0):
        assert keys(gv.run(compiled, registry, inputs={"x": x})) == fresh[x]
    alone = keys(gv.run(compiled, registry, inputs={"x": 2.0}, outputs=["c"]))
    assert alone == {"c": fresh[2.0]["c"]}
    cache = gv.Cache.at(tmp_path / "cache")
    gv.run(compiled, registry, inputs={"x": 1.0}, cache=cache)
    warm = gv.run(compiled, registry, inputs={"x": 2.0}, cache=cache)
    assert statuses(warm.record) == {"a": "computed", "b": "computed", "c": "computed"}
    assert warm.outputs == {"b": 9.0, "c": 14.0}


@pytest.mark.parametrize("executor", ["sync", "threads"])
@pytest.mark.parametrize("keep", [False, True])
def test_an_output_array_nothing_else_holds_is_frozen_without_a_copy(registry, executor, keep):
    """An aligned array a node returns and keeps no reference to becomes the value itself
    (0.8 ms of copies per run of coins.yaml were saved); one it keeps is copied. Either way
    the value, and every base numpy gives it, cannot be made writable by flags."""
    from graphvision.values.ports import is_frozen

    graph = gv.Graph("own")
    made = graph.add("a", "toy.own_address", x=graph.input("x", "Float", default=1.0),
                     params={"keep": keep})  # fmt: skip
    graph.output("a", made)
    value = gv.run(graph, registry, executor=executor).outputs["a"]
    address = value.__array_interface__["data"][0]
    assert (value[0, 0] == address) is not keep  # the node's own memory unless it kept it
    assert np.all(value == value[0, 0]) and is_frozen(value)
    target = value
    while isinstance(target, np.ndarray):
        with pytest.raises(ValueError, match="WRITEABLE"):
            target.flags.writeable = True
        target = target.base
    root = target.obj if isinstance(target, memoryview) else target  # no array down there
    assert root is None if not keep else isinstance(root, bytes)
