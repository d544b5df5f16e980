"""Which modules an entry-point plugin is made of, and whether this process holds them as
their files are now: what the plugin index may be recorded from.

An index is keyed by the digest of the plugins' files *now*, but it records the nodes of
the modules this process *imported*. The two differ when a module was imported before
its file was edited (a notebook or the studio open while the user edits a plugin, a
plugin package imported before the first discovery), and when a plugin's nodes live in
another top-level module of its distribution, which the key of its entry package alone
does not cover. This module finds both:

* :func:`loaded_as_now`: whether every file of a module last changed before the module
  could have been imported (before this process started, for a module imported before
  the discovery; before the discovery began, for one it imported). A file changed
  since may hold other bytes than those imported, and no index is written then;
* :func:`distribution_modules`: the top-level modules that importing an entry point
  brought in and that belong to its distribution (its ``RECORD`` and ``top_level.txt``)
  or, for a distribution without such a list or installed in place (editable), that
  lie beside its entry package: the index records their digests, and is not served
  when one changed (:func:`graphvision.nodes.plugin_index.read_index`). A module of the
  distribution imported before the discovery, by something else, is not among them.
"""

from __future__ import annotations

import os
import sys
import time
from collections.abc import Iterable
from functools import cache
from importlib.metadata import EntryPoint
from pathlib import Path

from graphvision.nodes.plugin_index import metadata_folder, package_files

__all__ = ["distribution_modules", "loaded_as_now", "process_start_ns"]

_COARSE_NS = 50_000_000
"""How far before the bound a file must have changed: file times come from a coarse clock
(a tick late), and a process's start from /proc is counted in ticks of 10 ms."""


@cache
def process_start_ns() -> int | None:
    """When this process started, on the clock that stamps files (ns); None where it is
    not known (no ``/proc``): a module imported before a discovery is then never trusted.

    ``/proc/self/stat``'s 22nd field is the start in clock ticks after boot; the time
    since then, taken from the boot clock, is subtracted from the wall clock now.
    """
    try:
        fields = Path("/proc/self/stat").read_text().rpartition(")")[2].split()
        since_boot = int(fields[19]) / os.sysconf("SC_CLK_TCK")  # (field 22; fields[0] is 3)
        running = time.clock_gettime(time.CLOCK_BOOTTIME) - since_boot
    except (OSError, ValueError, IndexError, AttributeError):
        return None
    return time.time_ns() - int(running * 1e9)


def loaded_as_now(module: str, imported_before: bool, began_ns: int) -> bool:
    """Whether every file of top-level ``module`` last changed before it could have been
    imported: before this process started when it was ``imported_before`` the discovery,
    else before the discovery began (``began_ns``)."""
    bound = process_start_ns() if imported_before else began_ns
    if bound is None:
        return False
    for file in package_files(module):
        try:
            status = os.stat(file)
        except OSError:
            return False
        if max(status.st_mtime_ns, status.st_ctime_ns) >= bound - _COARSE_NS:
            return False
    return True


def distribution_modules(entry: EntryPoint, loaded: Iterable[str]) -> set[str]:
    """The top-level modules among ``loaded`` (the modules importing ``entry`` brought in)
    that belong to its distribution, or that lie in the folder of its entry package when
    the distribution lists no files or is installed in place; its entry package not
    included."""
    top = entry.value.partition(":")[0].partition(".")[0]
    where = _folder(top)
    listed = _listed_modules(entry)
    beside = where is not None and (
        listed is None or str(where) != str(Path(metadata_folder(entry.dist) or "").parent)
    )
    found = set()
    for name in {name.partition(".")[0] for name in loaded} - {top, "graphvision"}:
        if (listed is not None and name in listed) or (beside and _folder(name) == where):
            found.add(name)
    return found


def _listed_modules(entry: EntryPoint) -> set[str] | None:
    """The top-level modules ``entry``'s distribution lists (``top_level.txt`` and its
    ``RECORD``'s files), or None when it lists no files."""
    dist = entry.dist
    files = dist.files if dist is not None else None
    if dist is None or files is None:
        return None
    names = set((dist.read_text("top_level.txt") or "").split())
    for file in files:
        first = file.parts[0] if file.parts else ""
        if first.endswith((".dist-info", ".egg-info", ".data", ".pth")) or first == "..":
            continue
        names.add(first.removesuffix(".py"))
    return names


def _folder(name: str) -> Path | None:
    """The folder that holds top-level module ``name`` as imported (None when it has no
    file: built in, a namespace package)."""
    module = sys.modules.get(name)
    spec = getattr(module, "__spec__", None)
    origin = getattr(spec, "origin", None)
    if not origin or not os.path.isabs(origin):
        return None
    path = Path(origin).parent  # the package's folder, or the module file's
    return path.parent if origin.endswith("__init__.py") else path
