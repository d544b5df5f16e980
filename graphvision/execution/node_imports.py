"""What the nodes of a run import inside their bodies, imported before they run, one thread at
a time.

Plugins import heavy libraries and their numba kernel modules inside the node
functions, so that listing nodes stays fast; a node then imports them on its
first call. Two nodes doing that at once, on two threads, can fail. Python
locks each module while it imports it, but puts a package in ``sys.modules``
before running its ``__init__``; another thread that imports one of its
submodules sees the parent there, takes only the submodule's lock and goes
on with the parent half made. When the parent's import then fails, the
parent leaves ``sys.modules`` (only the failing modules do), and the other
thread fails with ``KeyError`` naming the parent. The case met: a kernel
module imports numba, numba imports scipy inside ``try ... except
ImportError``; scipy's ``__init__`` finds ``scipy._lib._testutils`` half made
by a second thread importing ``scipy.ndimage`` ("cannot import name
'PytestTester' from partially initialized module"), fails, and numba goes on
without it; the second thread's node fails with ``KeyError: 'scipy'``.

:func:`import_ahead` imports, in the calling thread and before any node of
the run starts, the modules the nodes that will compute import inside their
bodies (found from their bytecode: :func:`~graphvision.execution.batch_preload.
lazy_imports`, which follows the helpers of the node's own top-level package)
and the libraries an implementation declares it requires. Importing a module
imports what it imports at its top, so a kernel module brings numba, and
numba scipy, here. Runs started from several threads at once (a batch's file
threads, a Dask worker's threads) import one after the other (a process-wide
lock in :func:`~graphvision.execution.batch_preload.import_modules`, which a
batch's warm-up of its workers takes too). Cached nodes import nothing (a
warm run imports nothing it did not before); what each function imports is
found once per process.

Not covered, because no code names it before it runs: a module named by a
string at run time (``importlib.import_module(name)``), a submodule reached as
an attribute (``scipy.ndimage`` after ``import scipy``, a lazy-loader
package's attributes), and what a library imports inside its own functions
(numba's compiler, on a kernel's first compile or cache load, imports its
implementations and ``scipy.linalg.cython_blas``; two threads made to meet
there, one setting numba's compiler up while the other imported scipy.optimize,
scipy.spatial or skimage.transform, did not fail in 20 tries).

References
----------
The Python Language Reference, section 5.4.1, "Loading": the module is in
``sys.modules`` before its code runs; if loading fails, the failing module, and
only it, is removed from ``sys.modules``.
"""

from __future__ import annotations

import sys
import weakref
from collections.abc import Callable, Iterable, Mapping
from operator import attrgetter
from typing import Any

from graphvision.compiler.compiled import Step
from graphvision.execution.batch_preload import import_modules, lazy_imports

__all__ = ["import_ahead", "import_ahead_of"]

# What each node function imports in its body (weak: a registry loaded again is not kept)
_FOUND: weakref.WeakKeyDictionary[Callable[..., Any], tuple[str, ...]] = weakref.WeakKeyDictionary()
_SPEC = attrgetter("spec")
_NOT_MODULES: set[str] = set()  # names that did not import (``from m import f``'s ``m.f``)


def import_ahead(functions: Iterable[Callable[..., Any]], libraries: Iterable[str] = ()) -> None:
    """Import the modules node ``functions`` import in their bodies, and ``libraries``, here.

    Parameters
    ----------
    functions : iterable of callables
        The functions of the nodes that will compute (not those found in the cache).
    libraries : iterable of str
        Modules their implementations declare they import when they run
        (``NodeSpec.requires``).

    Each module is imported on its own; one that fails is left to fail its
    nodes where they run, as it would anyway.
    """
    _import_missing(_modules_of(functions, libraries))


def _modules_of(functions: Iterable[Callable[..., Any]], libraries: Iterable[str]) -> list[str]:
    wanted = dict.fromkeys(libraries)
    for func in functions:
        wanted.update(dict.fromkeys(_imports_of(func)))
    return list(wanted)


def _import_missing(wanted: list[str]) -> None:
    modules, skipped = sys.modules, _NOT_MODULES
    missing = [name for name in wanted if name not in modules and name not in skipped]
    if not missing:
        return
    import_modules(missing)  # (one thread at a time in the process)
    skipped.update(name for name in missing if name not in modules)


def import_ahead_of(steps: Mapping[str, Step], names: Iterable[str]) -> None:
    """:func:`import_ahead` for the steps ``names`` of a compiled graph (each op once); the
    modules of the same steps of the same graph are listed once (a graph run again with
    nothing cached asks for the same steps each time)."""
    listed = list(names)
    known = _LISTED.get(id(steps))
    if known is not None and known[0] is steps and known[1] == listed:
        _import_missing(known[2])
        return
    specs = set(map(_SPEC, map(steps.__getitem__, listed)))  # (in C: a run of many nodes)
    wanted = _modules_of([s.func for s in specs], [m for s in specs for m in s.requires])
    if len(_LISTED) > 8:
        _LISTED.clear()
    _LISTED[id(steps)] = (steps, listed, wanted)
    _import_missing(wanted)


_LISTED: dict[int, tuple[Mapping[str, Step], list[str], list[str]]] = {}
"""The modules :func:`import_ahead_of` listed for the last graphs' steps (held: an ``id``
is not reused while its steps are), with the step names they were listed for. What a node
function imports never changes (:func:`_imports_of`), nor do a compiled graph's steps."""


def _imports_of(func: Callable[..., Any]) -> tuple[str, ...]:
    """The modules ``func`` (and its helpers) import in their bodies, found once."""
    try:
        return _FOUND[func]
    except KeyError:
        pass
    except TypeError:  # not weakly referable (a callable object): found each time
        return tuple(lazy_imports([func]))
    found = _FOUND[func] = tuple(lazy_imports([func]))
    return found
