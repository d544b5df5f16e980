"""Importing a local plugin file or package folder under a stable module name, so that a
worker process importing the same file gets the same module (and the same node ids); and
the line of a local plugin where one of its nodes failed.

A plugin that calls ``os._exit`` while it is imported ends the process at once: no
exception, no ``atexit``, nothing a caller can catch. While a plugin is imported
(:func:`exit_noted`), ``os._exit`` first writes one line naming it (``graphvision:
os._exit(3) while importing plugin /me/my_nodes.py``); nothing is written otherwise, so a
command that loads plugins says nothing more than it did.
"""

from __future__ import annotations

import contextlib
import hashlib
import importlib.util
import os
import sys
import threading
import traceback
import types
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any, NoReturn

from graphvision.errors import PluginLoadError
from graphvision.locations import not_utf8

__all__ = ["exit_noted", "import_file", "note_plugin_line", "plugin_line"]


def import_file(path: str | Path, module_name: str = "") -> types.ModuleType:
    """Import a plugin file (or a package folder) under a stable module name.

    The name is derived from the resolved path, so that a worker process
    importing the same file gets the same module name. A file imported before
    is imported again when its content has changed since (so ``discover()``
    after an edit runs, and fingerprints, the edited code).
    """
    path = Path(path).resolve()
    shown = not_utf8(path)  # (its module name, its record and the messages name it in UTF-8)
    if shown is not None:
        raise PluginLoadError(f"plugin {shown}: its path is not UTF-8: rename it")
    target = path / "__init__.py" if path.is_dir() else path
    digest = hashlib.blake2b(str(path).encode(), digest_size=4).hexdigest()
    name = module_name or f"graphvision_local_{path.stem}_{digest}"
    content = _content_digest(path)
    loaded = sys.modules.get(name)
    if loaded is not None:
        if getattr(loaded, "__graphvision_digest__", content) == content:
            return loaded
        for stale in [n for n in sys.modules if n == name or n.startswith(name + ".")]:
            del sys.modules[stale]
    spec = importlib.util.spec_from_file_location(
        name, target, submodule_search_locations=[str(path)] if path.is_dir() else None
    )
    if spec is None or spec.loader is None:
        raise PluginLoadError(f"cannot import plugin file {path}")
    module = importlib.util.module_from_spec(spec)
    module.__graphvision_path__ = str(path)  # type: ignore[attr-defined]
    module.__graphvision_digest__ = content  # type: ignore[attr-defined]
    sys.modules[name] = module
    try:
        with exit_noted(f"plugin {path}"):
            spec.loader.exec_module(module)
    except BaseException:
        del sys.modules[name]
        raise
    return module


@contextlib.contextmanager
def exit_noted(label: str) -> Iterator[None]:
    """While the block runs, ``os._exit`` called by its thread first writes
    ``graphvision: os._exit(STATUS) while importing LABEL`` to stderr."""
    previous, ident, active = os._exit, threading.get_ident(), [True]

    def noting(status: int) -> NoReturn:
        if active and threading.get_ident() == ident:
            os.write(2, f"graphvision: os._exit({status}) while importing {label}\n".encode())
        previous(status)

    os._exit = noting
    try:
        yield
    finally:
        active.clear()  # (kept by whoever took it meanwhile: it says nothing now)
        if os._exit is noting:
            os._exit = previous


def _content_digest(path: Path) -> str:
    """Digest of a plugin file, or of every ``.py`` file of a package folder."""
    files = sorted(path.rglob("*.py")) if path.is_dir() else [path]
    hasher = hashlib.blake2b(digest_size=16)
    for file in files:
        with contextlib.suppress(OSError):
            hasher.update(os.fsencode(file.relative_to(path.parent)))
            hasher.update(file.read_bytes())
    return hasher.hexdigest()


def note_plugin_line(error: BaseException, func: Callable[..., Any]) -> None:
    """Note on ``error``, raised by the node function ``func`` of a local plugin, the
    innermost line of its traceback in that plugin (``/home/me/my_nodes.py:17``), where the
    traceback is still there: the note crosses to the client with the error (a worker
    process sends the error without its traceback). Nothing for an installed plugin."""
    module = sys.modules.get(getattr(func, "__module__", "") or "")
    plugin = getattr(module, "__graphvision_path__", None)
    if plugin is None or hasattr(error, "__graphvision_line__"):
        return
    root = Path(plugin)
    for frame in reversed(traceback.extract_tb(error.__traceback__)):
        file = Path(frame.filename)
        if file == root or (root.is_dir() and file.is_relative_to(root)):
            error.__graphvision_line__ = f"{frame.filename}:{frame.lineno}"  # type: ignore[attr-defined]
            return


def plugin_line(error: BaseException) -> str:
    """`` (FILE:LINE)`` of the local plugin line that raised ``error``
    (:func:`note_plugin_line`), or ''."""
    line = getattr(error, "__graphvision_line__", "")
    return f" ({line})" if line else ""
