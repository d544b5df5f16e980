"""The local plugins of a graph (``graph.plugins``), each path where Python finds it.

A pipeline read from a file names its plugins relative to that file: the paths
in its ``plugins:`` and the paths added later in Python (``graph.plugins.append
("my_nodes.py")`` on a loaded pipeline) are both read from the file's folder, so
a script that loads ``try/denoise.yaml`` finds ``try/my_nodes.py`` wherever it
runs. A graph built in Python has no such folder: its plugins are read from the
working folder, as ``open`` reads a path.

The list holds each path as the process can open it: relative to the working
folder (``try/my_nodes.py``) or absolute, so every consumer (discovery, a
worker process, the messages) reads it as it is.
"""

from __future__ import annotations

from collections.abc import Iterable
from pathlib import Path
from typing import Any, SupportsIndex

__all__ = ["PluginPaths"]


class PluginPaths(list[str]):
    """The plugin paths of a graph read from a file in ``folder`` ("" for none).

    Parameters
    ----------
    paths : iterable of str
        Paths already placed (relative to the working folder, or absolute).
    folder : str
        The pipeline file's folder, as given when it was read; a relative path added
        later is joined to it. Empty: paths are taken as given.

    Examples
    --------
    >>> plugins = PluginPaths(["try/a.py"], folder="try")
    >>> plugins.append("b.py"); plugins += ["/abs/c.py"]
    >>> plugins
    ['try/a.py', 'try/b.py', '/abs/c.py']
    """

    def __init__(self, paths: Iterable[str] = (), folder: str = "") -> None:
        super().__init__(paths)
        self.folder = folder

    def __reduce__(self) -> tuple[Any, ...]:  # a copy or a pickle is not placed again
        return (PluginPaths, (list(self), self.folder))

    def placed(self, path: str | Path) -> str:
        """``path`` as the process opens it: a relative path joined to the file's folder
        (an empty one kept as it is, for the discovery to refuse it by name)."""
        text = str(path)
        if not self.folder or not text.strip() or Path(text).is_absolute():
            return text
        return str(Path(self.folder) / text)

    def append(self, path: str) -> None:
        super().append(self.placed(path))

    def insert(self, index: SupportsIndex, path: str) -> None:
        super().insert(index, self.placed(path))

    def extend(self, paths: Iterable[str]) -> None:
        super().extend(self.placed(path) for path in paths)

    def __iadd__(self, paths: Iterable[str]) -> PluginPaths:  # type: ignore[override,misc]
        self.extend(paths)
        return self

    def __setitem__(self, index: Any, value: Any) -> None:
        if isinstance(index, slice):
            super().__setitem__(index, [self.placed(path) for path in value])
        else:
            super().__setitem__(index, self.placed(value))
