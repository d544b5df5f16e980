"""``njit``: numba's, with an on-disk cache that also knows the kernels a kernel calls.

numba keys a cached kernel on the bytes of the file that defines it (and the
kernel's own bytecode), not on the kernels it calls: when only a callee in
another file changes (``fitting._kernels.draw_sample`` under
``geometry._kernels.ransac_homography``), the caller keeps loading its old
machine code, with the old callee compiled in. A checkout updated by ``git
pull``, or a kernel edited by hand, then runs code that is no longer in the
sources, and graphvision's cache (whose keys do cover the callee) would keep
its wrong values under the new key.

Every kernel here is compiled with :func:`njit`, which is ``numba.njit`` whose
cache adds to each entry's key a digest of the files of every kernel reachable
from it (its globals, and the attributes it reads of a module it holds,
followed to the end) and of the project's modules those kernels' files import
(a constant read from another file is compiled in too): a changed callee or
constant is a cache miss, compiled anew.
"""

from __future__ import annotations

import ast
import functools
import hashlib
import importlib.util
import inspect
import sys
import types
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import numba
from numba.core.caching import FunctionCache
from numba.core.dispatcher import Dispatcher

__all__ = ["njit"]


def njit(**options: Any) -> Callable[[Callable[..., Any]], Any]:
    """``numba.njit(**options)``; with ``cache=True`` the cache also covers the callees."""

    def compile_later(func: Callable[..., Any]) -> Any:
        kernel = numba.njit(**options)(func)
        if options.get("cache"):
            kernel._cache = _CalleeAwareCache(kernel.py_func)
        return kernel

    return compile_later


class _CalleeAwareCache(FunctionCache):
    """numba's function cache, its index key extended by :func:`callees_digest`."""

    def _index_key(self, sig: Any, codegen: Any) -> tuple[Any, ...]:
        return (*super()._index_key(sig, codegen), callees_digest(self._py_func))


def callees_digest(func: Callable[..., Any]) -> str:
    """sha256 over the source files of every kernel ``func`` reaches and of the project's
    modules those kernels' modules import, to the end (a constant read from another file
    is compiled in too), itself excluded (numba's own stamp covers its file): each file's
    path and bytes, in path order."""
    modules = {func.__module__, *(kernel.py_func.__module__ for kernel in _reachable(func))}
    files = _imported_files(modules)
    files.pop(Path(inspect.getfile(func)), None)
    digest = hashlib.sha256()
    for path in sorted(files):
        digest.update(files[path])
    return digest.hexdigest()


def _imported_files(modules: set[str]) -> dict[Path, bytes]:
    """The files of ``modules`` and of the modules of their project that they import (at
    the top of their file: what is loaded when a kernel is compiled), followed to the end;
    each with the digest of its name and bytes."""
    files: dict[Path, bytes] = {}
    waiting, seen = list(modules), set(modules)
    while waiting:
        module = sys.modules.get(waiting.pop())
        path = getattr(module, "__file__", None)
        if module is None or not path or not path.endswith(".py"):
            continue
        state, package = Path(path).stat(), module.__package__ or ""
        files[Path(path)], imports = _read(path, state.st_mtime_ns, state.st_size, package)
        project = module.__name__.partition(".")[0]
        for name in imports:
            if name.partition(".")[0] == project and name not in seen:
                seen.add(name)
                waiting.append(name)
    return files


@functools.cache
def _read(path: str, mtime_ns: int, size: int, package: str) -> tuple[bytes, tuple[str, ...]]:
    """sha256 of ``path``'s name and bytes, and the absolute names its top-level imports
    may mean (``from .a import b``: ``a`` and ``a.b``, which may be a module); the file is
    read once, and again only when its time or size changes."""
    source = Path(path).read_bytes()
    found: list[str] = []
    for statement in ast.parse(source).body:
        if isinstance(statement, ast.Import):
            found += [alias.name for alias in statement.names]
        elif isinstance(statement, ast.ImportFrom):
            relative = "." * statement.level + (statement.module or "")
            try:
                base = (
                    importlib.util.resolve_name(relative, package) if statement.level else relative
                )
            except (ImportError, ValueError):
                continue
            found += [base, *(f"{base}.{alias.name}" for alias in statement.names)]
    return hashlib.sha256(path.encode() + b"\0" + source).digest(), tuple(found)


def _reachable(func: Callable[..., Any]) -> Iterator[Dispatcher]:
    """The compiled kernels ``func`` calls, and those they call, each once."""
    seen: set[int] = set()
    waiting = [func]
    while waiting:
        for kernel in _called(waiting.pop()):
            if id(kernel) not in seen:
                seen.add(id(kernel))
                waiting.append(kernel.py_func)
                yield kernel


def _called(func: Callable[..., Any]) -> Iterator[Dispatcher]:
    """The kernels among ``func``'s globals that its code names, directly or as an
    attribute of a module it names."""
    names = _names(func.__code__)
    for name in names:
        found = func.__globals__.get(name)
        if isinstance(found, Dispatcher):
            yield found
        elif isinstance(found, types.ModuleType):
            for attribute in names:
                held = getattr(found, attribute, None)
                if isinstance(held, Dispatcher):
                    yield held


def _names(code: types.CodeType) -> set[str]:
    """The global and attribute names ``code`` and the code nested in it use."""
    names = set(code.co_names)
    for constant in code.co_consts:
        if isinstance(constant, types.CodeType):
            names |= _names(constant)
    return names
