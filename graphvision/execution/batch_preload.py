"""What a batch's workers will import on their first file, found before it runs: the
modules its node functions (and the report pages) import inside their bodies.

Plugins import heavy libraries (scipy's ``ndimage``, imageio's plugins) and
their numba kernel modules inside the node functions, so that listing nodes
stays fast. A worker forked from the fork server
(:mod:`graphvision.execution.worker_start`) that has not imported them does it
on its first file: seconds on a loaded machine, paid by every worker (on two
loaded cores, over 2 s of a worker's first coins file was scipy's import and
numba's cache loads). Found here from the functions' bytecode, they are
imported once by the server, and every worker forked from it has them (and
the kernels' compiled code, loaded from numba's cache:
:mod:`graphvision.execution._preload`).

The search follows, from each function, the functions of the same top-level
package it names (a helper such as ``_extreme`` calling ``scipy.ndimage``), as
the code fingerprint does; a name in an ``import`` that may be a module
(``from scipy import ndimage``) is listed as ``scipy.ndimage``: what is not a
module is skipped where it is imported.
"""

from __future__ import annotations

import contextlib
import dis
import functools
import importlib
import inspect
import sys
import threading
import types
from collections.abc import Callable, Iterable
from importlib.util import resolve_name
from typing import Any

from graphvision.execution.batch_signals import signals_deferred

__all__ = ["import_modules", "lazy_imports", "load_kernels"]

_MOST_FUNCTIONS = 500  # a bound on the walk, whatever the plugins' code
_IMPORTING = threading.RLock()  # two threads importing one package at once can fail


def lazy_imports(functions: Iterable[Callable[..., Any]]) -> list[str]:
    """The modules ``functions`` import inside their bodies, and those the functions of the
    same top-level package they name import, in the order found."""
    found: dict[str, None] = {}
    seen: set[types.CodeType] = set()
    todo = [inspect.unwrap(f) for f in functions]
    while todo and len(seen) < _MOST_FUNCTIONS:
        func = todo.pop()
        code = getattr(func, "__code__", None)
        if not isinstance(code, types.CodeType) or code in seen:
            continue
        seen.add(code)
        scope: dict[str, Any] = getattr(func, "__globals__", {})
        package = scope.get("__package__") or ""
        project = (getattr(func, "__module__", "") or "").partition(".")[0]
        for inner in _codes(code):
            for name in _imports(inner, package):
                found.setdefault(name)
            for name in inner.co_names:
                helper = inspect.unwrap(scope[name]) if name in scope else None
                if _is_function_of(helper, project):
                    todo.append(helper)
    return list(found)


def _codes(code: types.CodeType) -> Iterable[types.CodeType]:
    """``code`` and the code nested in it (comprehensions, inner functions)."""
    yield code
    for const in code.co_consts:
        if isinstance(const, types.CodeType):
            yield from _codes(const)


@functools.lru_cache(maxsize=4096)
def _imports(code: types.CodeType, package: str) -> tuple[str, ...]:
    """The modules an ``import`` in ``code`` may name, made absolute; kept per code object
    (its bytecode read again took 19 ms of a batch's client each batch: on Dask, while the
    client runs the batch's first file, before the workers are warmed)."""
    names: list[str] = []
    consts: list[Any] = []
    for instruction in dis.get_instructions(code):
        if instruction.opname == "LOAD_CONST":
            consts = [*consts[-1:], instruction.argval]
            continue
        if instruction.opname == "IMPORT_NAME" and len(consts) == 2:
            level, fromlist = consts
            try:
                module = resolve_name("." * int(level or 0) + instruction.argval, package)
            except (ImportError, ValueError, TypeError):
                module = ""
            if module:
                names.append(module)
                names += [f"{module}.{item}" for item in fromlist or () if item != "*"]
        consts = []
    return tuple(names)


def _is_function_of(obj: Any, project: str) -> bool:
    module = getattr(obj, "__module__", None) or ""
    return isinstance(obj, types.FunctionType) and bool(project) and module.startswith(project)


def import_modules(names: list[str]) -> list[Any]:
    """The modules of ``names`` that import (each on its own; whatever it raises), imported by
    one thread at a time in the process (:mod:`graphvision.execution.node_imports`)."""
    found = []
    with _IMPORTING:
        for name in names:
            try:
                found.append(importlib.import_module(name))
            except (Exception, SystemExit):  # it fails its nodes where they run, as anyway
                continue
    return found


def load_kernels(modules: list[Any]) -> None:
    """The numba kernels of ``modules`` take the compiled code numba's cache holds for them."""
    if "numba" not in sys.modules:
        return
    from numba.core.dispatcher import Dispatcher

    for module in modules:
        for kernel in list(vars(module).values()):
            if isinstance(kernel, Dispatcher) and getattr(kernel, "__module__", None) == (
                module.__name__
            ):
                with contextlib.suppress(Exception):
                    _load_cached(kernel)


def _load_cached(kernel: Any) -> None:
    """Every signature numba's cache holds for ``kernel``'s code on this machine, loaded (a
    signature whose entry is missing or stale is left to the kernel's first call). A Ctrl-C
    meanwhile is raised after each signature's code: raised inside llvmlite's object cache,
    which LLVM calls back, it was dropped there and LLVM read a missing buffer (the
    client crashed, SIGSEGV; :mod:`graphvision.execution.batch_signals`)."""
    cache = kernel._cache
    codegen = kernel.targetctx.codegen()
    for key in list(cache._cache_file._load_index()):
        signature = key[0]
        if cache._index_key(signature, codegen) == key:  # this machine's, for this code
            with signals_deferred():
                kernel.compile(signature)
