"""What a node raises reaches the run's message whole on every executor: an exception that
does not pickle (a lock among its attributes) or does not unpickle (an ``__init__`` taking
other arguments than it gives its base) travels back from a worker as its copy, and one whose
``__str__`` raises says so. A tryer saw, on processes, ``TypeError: cannot pickle
'_thread.lock' object`` in place of the node's error, and for the second that the worker had
died (the node ran twice); and an internal error for the third, on every executor."""

from __future__ import annotations

import pickle

import pytest

import graphvision as gv
from graphvision.errors import CopiedError, error_text
from graphvision.execution.sendable import arrived, sendable

PLUGIN = '''import threading

from graphvision import Float, node


class Unpicklable(Exception):
    def __init__(self, message):
        super().__init__(message)
        self.lock = threading.Lock()


class NeedsArgs(Exception):
    def __init__(self, a, b):
        super().__init__(f"{a}/{b}")


class BadStr(Exception):
    def __str__(self):
        raise RuntimeError("str broken")


@node("own.unpicklable")
def unpicklable() -> Float:
    """Raises an exception holding a lock."""
    raise Unpicklable("cannot pickle me")


@node("own.needs_args")
def needs_args() -> Float:
    """Raises an exception that pickles and does not unpickle."""
    raise NeedsArgs(1, 2)


@node("own.bad_str")
def bad_str() -> Float:
    """Raises an exception whose message cannot be made."""
    raise BadStr()
'''

SAID = {
    "unpicklable": ("Unpicklable: cannot pickle me", 25),
    "needs_args": ("NeedsArgs: 1/2", 31),
    "bad_str": ("BadStr: (its message could not be made: RuntimeError)", 37),
}


@pytest.fixture(scope="module")
def plugin(tmp_path_factory):
    path = tmp_path_factory.mktemp("own") / "my_nodes.py"
    path.write_text(PLUGIN)
    return gv.discover([path]), path.resolve()


@pytest.mark.parametrize("executor", ["sync", "threads", "processes"])
@pytest.mark.parametrize("op", sorted(SAID))
def test_a_node_error_reaches_the_run_whole(plugin, executor, op):
    registry, path = plugin
    graph = gv.Graph("own")
    graph.output("out", graph.add("x", f"own.{op}"))
    with pytest.raises(gv.RunError) as caught:
        gv.run(graph, registry, executor=executor, cache=None)
    said, line = SAID[op]
    assert str(caught.value.failures["x"]).splitlines()[0] == (
        f"node 'x' (op own.{op}) failed: {said} ({path}:{line})"
    )
    (node,) = (n for n in caught.value.record.nodes if n.name == "x")
    assert node.error == f"{said} ({path}:{line})"


def test_a_copy_pickles_with_its_type_name_message_and_line():
    class LocalError(Exception):  # a class of a function's: pickle cannot name it
        pass

    error = LocalError("bad")
    error.__graphvision_line__ = "/me/my_nodes.py:3"  # type: ignore[attr-defined]
    copy = pickle.loads(pickle.dumps(sendable(error)))
    assert isinstance(copy, CopiedError) and error_text(copy) == "LocalError: bad"
    assert copy.__graphvision_line__ == "/me/my_nodes.py:3"
    plain = ValueError("fine")
    plain.__graphvision_line__ = "/me/my_nodes.py:4"  # type: ignore[attr-defined]
    back = pickle.loads(pickle.dumps(sendable(plain)))  # itself where it unpickles
    assert type(back) is ValueError and back.args == ("fine",)
    assert back.__graphvision_line__ == "/me/my_nodes.py:4"
    assert error_text(sendable(plain)) == "ValueError: fine"  # the copy, where not pickled


class FrozenError(Exception):
    """An exception that unpickles, and raises when asked for its plugin line. (Only for
    that: tblib, which Dask installs for every exception in the process, asks for
    ``__notes__`` when pickling one.)"""

    def __reduce__(self):
        return (FrozenError, self.args)

    def __getattr__(self, name):
        if name == "__graphvision_line__":
            raise RuntimeError(f"no {name} here")
        raise AttributeError(name)


def test_an_exception_that_fails_at_its_plugin_line_arrives_as_its_copy():
    got = arrived(pickle.dumps(FrozenError("cold")), "FrozenError", "cold", "/me/my_nodes.py:8")
    assert isinstance(got, CopiedError) and error_text(got) == "FrozenError: cold"
    assert got.__graphvision_line__ == "/me/my_nodes.py:8"
