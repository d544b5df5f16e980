"""The local plugins of a graph (``graph.plugins``), each path where Python finds it.

A pipeline read from a file names its plugins relative to that file: the paths
in its ``plugins:`` and the paths added later in Python (``graph.plugins.append
("my_nodes.py")`` on a loaded pipeline) are both read from the file's folder, so
a script that loads ``try/denoise.yaml`` finds ``try/my_nodes.py`` wherever it
runs. The folder is made absolute when the file is read, so a script that changes
its working folder afterwards (``os.chdir``) still finds them; a list given in its
place (``graph.plugins = ["my_nodes.py"]``) is read from there too. A graph built in
Python has no such folder: its plugins are read from the working folder, as
``open`` reads a path.

The list holds each path as the process opens it (absolute, for a pipeline read from
a file), so every consumer (discovery, a worker process, the messages) reads it as it
is. It compares equal to the paths its file names (``["my_nodes.py"]``) as well, and a
pipeline's text writes them so (:func:`written_plugins`): ``parse_pipeline(
dump_pipeline(graph)) == graph``, and the text written beside the pipeline loads them.
"""

from __future__ import annotations

import os
from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import Any, SupportsIndex

__all__ = ["PluginPaths", "written_plugins"]


class PluginPaths(list[str]):
    """The plugin paths of a graph read from a file in ``folder`` ("" for none).

    Parameters
    ----------
    paths : iterable of str
        Paths already placed (absolute, or relative to the working folder).
    folder : str
        The pipeline file's folder (made absolute); a relative path added later is
        joined to it. Empty: paths are taken as given.

    Examples
    --------
    >>> plugins = PluginPaths(["/try/a.py"], folder="/try")
    >>> plugins.append("b.py"); plugins += ["/abs/c.py"]
    >>> plugins
    ['/try/a.py', '/try/b.py', '/abs/c.py']
    >>> plugins == ["a.py", "b.py", "/abs/c.py"]  # as its file names them
    True
    """

    def __init__(self, paths: Iterable[str] = (), folder: str = "") -> None:
        super().__init__(_path_texts(paths))
        self.folder = os.path.abspath(folder) if folder else ""

    def __reduce__(self) -> tuple[Any, ...]:  # a copy or a pickle is not placed again
        return (PluginPaths, (list(self), self.folder))

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, list):
            return NotImplemented
        if isinstance(other, PluginPaths) and other.folder and not self.folder:
            return other == list(self)  # (a file's paths placed from its folder)
        return list(self) == [self.placed(path) for path in other]

    def __ne__(self, other: object) -> bool:
        equal = self.__eq__(other)
        return equal if equal is NotImplemented else not equal

    __hash__ = None  # (a list: mutable)

    def placed(self, path: str | os.PathLike[str]) -> str:
        """``path`` as the process opens it: a relative path joined to the file's folder
        (an empty one kept as it is, for the discovery to refuse it by name).

        Raises
        ------
        TypeError
            ``path`` is not a ``str`` or a ``pathlib.Path`` (bytes, a number, a list).
        """
        text = _path_text(path)
        if not self.folder or not text.strip() or Path(text).is_absolute():
            return text
        return os.path.normpath(os.path.join(self.folder, text))

    def append(self, path: str) -> None:
        super().append(self.placed(path))

    def insert(self, index: SupportsIndex, path: str) -> None:
        super().insert(index, self.placed(path))

    def extend(self, paths: Iterable[str]) -> None:
        super().extend(self.placed(path) for path in _path_texts(paths))

    def __iadd__(self, paths: Iterable[str]) -> PluginPaths:  # type: ignore[override,misc]
        self.extend(paths)
        return self

    def __setitem__(self, index: Any, value: Any) -> None:
        if isinstance(index, slice):
            super().__setitem__(index, [self.placed(path) for path in _path_texts(value)])
        else:
            super().__setitem__(index, self.placed(value))

    # A path as its file names it is found as the list holds it (placed).
    def __contains__(self, path: object) -> bool:
        return super().__contains__(self._found(path))

    def count(self, path: Any) -> int:
        return super().count(self._found(path))

    def index(self, path: Any, *bounds: SupportsIndex) -> int:
        return super().index(self._found(path), *bounds)

    def remove(self, path: Any) -> None:
        super().remove(self._found(path))

    def _found(self, path: Any) -> Any:
        return self.placed(path) if isinstance(path, str | os.PathLike) else path


def _path_texts(paths: Iterable[str]) -> list[str]:
    """The paths of a list given for ``graph.plugins``, each checked (:func:`_path_text`);
    one path in place of the list is refused (it would be taken letter by letter: ``.``
    the pipeline's folder, ``/`` the root, each a plugin path)."""
    if isinstance(paths, str | bytes | os.PathLike):
        raise TypeError(f"graph.plugins takes a list of paths ([{str(paths)!r}]), not {paths!r}")
    if not isinstance(paths, Iterable):
        raise TypeError(f"graph.plugins takes a list of paths, not {paths!r}")
    return [_path_text(path) for path in paths]


def _path_text(path: object) -> str:
    """One plugin path as text: a ``str`` or an ``os.PathLike`` naming one."""
    text = os.fspath(path) if isinstance(path, os.PathLike) else path
    if not isinstance(text, str):
        raise TypeError(
            f"graph.plugins holds paths (str or pathlib.Path), not {type(path).__name__} {path!r}"
        )
    return text


def written_plugins(plugins: Sequence[str], file: str | Path | None = None) -> list[str]:
    """``plugins`` as a pipeline file in ``file``'s folder names them: each path inside
    that folder relative to it, any other absolute. Without ``file``: a loaded pipeline's
    as its own file names them (relative to its folder), a built graph's as given.

    Examples
    --------
    >>> written_plugins(PluginPaths(["/try/a.py", "/lib/b.py"], folder="/try"))
    ['a.py', '/lib/b.py']
    >>> written_plugins(["/try/a.py"], "/try/sub/p.yaml")
    ['/try/a.py']
    """
    if file is not None:
        folder = os.path.dirname(os.path.abspath(file))
    elif isinstance(plugins, PluginPaths) and plugins.folder:
        folder = plugins.folder
    else:
        return list(plugins)
    written = []
    for path in plugins:
        absolute = os.path.abspath(path) if path.strip() else path
        inside = path.strip() and Path(absolute).is_relative_to(folder)
        written.append(os.path.relpath(absolute, folder) if inside else absolute)
    return written
