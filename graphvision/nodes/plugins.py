"""Plugin discovery: the ``graphvision.plugins`` entry-point group and local paths.

Built-in plugins are found exactly as third-party ones are: each entry point
names a module, which is imported and registered. A user may also name a
local plugin file or folder (``--plugins PATH`` on the CLI, ``plugins:`` in a
pipeline file). A plugin that fails to import or register is recorded with
its error and the others keep working.

Plugins import only light modules at the top (numpy); heavy ones (scipy,
scikit-image) are imported inside the node functions, so listing nodes stays
fast. When the plugin index (:mod:`._plugin_index`) matches the installed
plugins, their nodes' parameter models are built on first use.
"""

from __future__ import annotations

import sys
import time
import traceback
import types
import warnings
from collections.abc import Iterable
from dataclasses import dataclass
from importlib.metadata import EntryPoint
from pathlib import Path

from graphvision.errors import GraphvisionError, PluginLoadError
from graphvision.graph.model import Graph
from graphvision.nodes.fingerprint import note_distribution
from graphvision.nodes.loading import exit_noted, import_file
from graphvision.nodes.node import script_nodes
from graphvision.nodes.plugin_index import (
    ENTRY_POINT_GROUP,
    environment_key,
    has_index,
    installed_entry_points,
    metadata_folder,
    package_digest,
    read_providers,
    write_index,
)
from graphvision.nodes.plugin_modules import distribution_modules, loaded_as_now
from graphvision.nodes.registry import Registry

__all__ = [
    "ENTRY_POINT_GROUP",
    "Needs",
    "discover",
    "discover_for",
    "load_entry_points",
    "load_path",
    "plugin_files",
    "warn_of_failed_plugins",
]

_ENGINE = Path(__file__).resolve().parent.parent  # graphvision's own files


def _summarise(error: BaseException, plugin: Path | None = None) -> str:
    """``error`` in one line, with the file and line it came from: a syntax error's own
    place, else the innermost frame of the traceback in the local ``plugin`` (a file, or a
    folder's files) when there is one, else its innermost frame in a file (not importlib's)."""
    if isinstance(error, GraphvisionError):
        return str(error)
    if isinstance(error, SyntaxError) and error.filename:
        return f"{type(error).__name__}: {error.msg} ({error.filename}:{error.lineno})"
    stack = traceback.extract_tb(error.__traceback__)
    frames = [frame for frame in stack if not frame.filename.startswith("<")]
    if plugin is not None:  # its own line, else one outside graphvision's loading code
        mine = [f for f in frames if Path(f.filename).resolve().is_relative_to(plugin.resolve())]
        outside = [f for f in frames if not Path(f.filename).resolve().is_relative_to(_ENGINE)]
        frames = mine or outside
    where = f" ({frames[-1].filename}:{frames[-1].lineno})" if frames else ""
    if isinstance(error, SystemExit):
        return f"it called sys.exit({error.code!r}) while being imported{where}"
    return f"{type(error).__name__}: {error}{where}"


def load_entry_points(registry: Registry, needs: Needs | None = None) -> None:
    """Register the plugins of the ``graphvision.plugins`` entry-point group.

    With a plugin index for the same files, the nodes' parameter models are
    left to be built on first use, and given ``needs`` (what a pipeline uses)
    only the plugins that provide it are imported, with every plugin that
    loads input values (``sample:``, files); without an index, every plugin is
    imported and checked, and the index is written for the next discovery.
    """
    fresh = not registry.plugins  # only a registry of these plugins alone is recorded
    entries = installed_entry_points()
    key = environment_key(entries)
    providers = read_providers(key) if has_index(key) else None  # a damaged one is removed
    indexed = providers is not None
    registry.indexed = providers or registry.indexed  # what the plugins not imported provide
    if providers is not None and needs is not None:
        wanted = _providers(providers, needs, set(registry.port_types))
        if wanted is not None:
            entries = [entry for entry in entries if entry.name in wanted]
            fresh = False  # a part of the plugins: never recorded as the whole
    tops = {entry.value.partition(":")[0].partition(".")[0] for entry in entries}
    imported_before, began = {top for top in tops if top in sys.modules}, time.time_ns()
    for entry in entries:
        if entry.name not in registry.plugins:
            count = len(sys.modules)
            _load_entry_point(registry, entry, indexed)
            if len(sys.modules) > count:  # (modules are added at the end: a dict keeps order)
                brought = distribution_modules(entry, list(sys.modules)[count:])
                _BROUGHT.setdefault(entry.value, set()).update(brought)
    others = {name for entry in entries for name in _BROUGHT.get(entry.value, ())}
    for top in (tops | others) - _LOADED_AS.keys():  # (once per module and process)
        trusted = loaded_as_now(top, top in imported_before, began)
        _LOADED_AS[top] = package_digest(top) if trusted else None
    recordable = fresh and not indexed and not registry.failed_plugins()
    if recordable and environment_key(entries) == key and _unchanged_since_loaded(tops | others):
        recorded = {name: _LOADED_AS[name] or b"" for name in others}
        write_index(key, registry, recorded)  # (no file changed while, or since, they loaded)


def _load_entry_point(registry: Registry, entry: EntryPoint, indexed: bool) -> None:
    """Import ``entry``'s module and register it, or record why it failed."""
    try:
        with exit_noted(f"plugin '{entry.name}' ({entry.value})"):
            module = entry.load()
        if not isinstance(module, types.ModuleType):
            raise PluginLoadError(f"entry point must name a module, got {module!r}")
        registry.add_plugin(module, entry.name, entry.value, params_checked=indexed)
        if entry.dist is not None:
            note_distribution(module.__name__.partition(".")[0], _distribution_name(entry))
    except KeyboardInterrupt:  # (Ctrl-C: the user's stop)
        raise
    except BaseException as error:  # sys.exit(), a BaseException of its own: the command ended
        registry.record_failure(entry.name, entry.value, _summarise(error))


_LOADED_AS: dict[str, bytes | None] = {}
"""A plugin's top-level module -> its files' digest when first loaded, None when they may
have changed since it was imported (:func:`~.plugin_modules.loaded_as_now`)."""

_BROUGHT: dict[str, set[str]] = {}
"""An entry point's target -> the other top-level modules of its distribution its import
brought in (:func:`~.plugin_modules.distribution_modules`), kept for the discoveries after
the first, whose import of it imports nothing."""


def _unchanged_since_loaded(modules: set[str]) -> bool:
    """Whether every module's files are those this process loaded (see :data:`_LOADED_AS`).

    A module imported before its files were edited keeps the old code: a registry of it,
    recorded under the new key, would be an index served stale to every later command (a
    notebook or the studio open while the user edits a plugin, a plugin package imported
    before the first discovery).
    """
    return all(
        _LOADED_AS[name] is not None and _LOADED_AS[name] == package_digest(name)
        for name in modules
    )


_DISTRIBUTION_NAMES: dict[object, str] = {}  # by metadata folder (its name holds the name)


def _distribution_name(entry: EntryPoint) -> str:
    """The name of ``entry``'s distribution, its metadata parsed once per process (11 ms)."""
    dist = entry.dist
    assert dist is not None
    where = metadata_folder(dist)
    if where is None:
        return str(dist.name)
    if where not in _DISTRIBUTION_NAMES:
        _DISTRIBUTION_NAMES[where] = dist.name
    return _DISTRIBUTION_NAMES[where]


@dataclass(frozen=True)
class Needs:
    """What a pipeline asks of the installed plugins: its ops and its inputs' port types.

    >>> graph = Graph("g"); image = graph.input("image", "Image")
    >>> graph.output("smooth", graph.add("smooth", "filters.gaussian", image=image))
    >>> needs = Needs.of(graph)
    >>> needs.ops, needs.port_types, needs.backends
    (frozenset({'filters.gaussian'}), frozenset({'Image'}), frozenset())

    ``backends`` are those its lookup order and its nodes' pins name: the plugins adding
    implementations of its ops for those backends are imported too.
    """

    ops: frozenset[str]
    port_types: frozenset[str] = frozenset()
    backends: frozenset[str] = frozenset()

    @classmethod
    def of(cls, graph: Graph) -> Needs:
        return cls(
            frozenset(decl.op for decl in graph.nodes.values()),
            frozenset(decl.type for decl in graph.inputs.values()),
            frozenset(graph.backends) | {d.backend for d in graph.nodes.values() if d.backend},
        )


def _providers(
    plugins: dict[str, dict[str, list[str]]], needs: Needs, builtin: set[str]
) -> set[str] | None:
    """The entry points to import for ``needs``: those registering a needed op or a
    needed port type that is not built in, and every one that loads input values.

    None (import all) when a need is provided by no plugin: the error then lists
    every plugin's names for a "did you mean".
    """
    wanted = {name for name, entry in plugins.items() if entry["sources"]}
    for kinds, needed in (("nodes", needs.ops), ("port_types", needs.port_types - builtin)):
        for name in needed:
            providers = {plugin for plugin, entry in plugins.items() if name in entry[kinds]}
            if not providers:
                return None
            wanted |= providers
    for plugin, entry in plugins.items():  # the chosen backends' implementations of the ops
        provided = [i.partition("@") for i in entry.get("implementations", [])]
        if any(op in needs.ops and backend in needs.backends for op, _, backend in provided):
            wanted.add(plugin)
    return wanted


def load_path(registry: Registry, path: str | Path) -> None:
    """Register a local plugin: a ``.py`` file, a package folder, or a folder of ``.py`` files."""
    if not str(path).strip():  # (Path("") is the current folder: every file in it would run)
        registry.record_failure("''", "''", "the plugin path is empty: name a file or folder")
        return
    path = Path(path)
    if not path.exists():
        registry.record_failure(str(path), str(path), f"plugin path {path} does not exist")
        return
    for target in plugin_files(path):
        name = str(target)
        try:
            registry.add_plugin(import_file(target), name, name)
        except KeyboardInterrupt:  # (Ctrl-C: the user's stop)
            raise
        except BaseException as error:  # sys.exit(), a BaseException of its own: it ended
            registry.record_failure(name, name, _summarise(error, path))  # the command


def plugin_files(path: Path) -> list[Path]:
    """What a local plugin path imports: a folder of ``.py`` files, each of them (not those
    named ``_*``); a file or a package folder, itself."""
    if path.is_dir() and not (path / "__init__.py").exists():
        return sorted(p for p in path.glob("*.py") if not p.name.startswith("_"))
    return [path]


def discover(
    paths: Iterable[str | Path] = (), *, entry_points: bool = True, needs: Needs | None = None
) -> Registry:
    """A registry with the entry-point plugins and the local plugins at ``paths``.

    ``needs`` (a pipeline's ops and input types) lets a discovery with a plugin
    index import only the plugins that provide them; the registry then holds
    those alone (the command line runs a pipeline this way).
    """
    registry = Registry()
    if entry_points:
        load_entry_points(registry, needs)
    for path in paths:
        load_path(registry, path)
    return registry


def discover_for(graph: Graph, paths: Iterable[str | Path] = ()) -> Registry:
    """The registry a run of ``graph`` needs: the local plugins at ``paths`` and of its
    ``plugins:``, the installed families of its ops and input types, and the nodes it
    uses that were defined in ``__main__`` (a script or a notebook) and no plugin has."""
    needs = Needs.of(graph)
    registry = discover([*paths, *graph.plugins], needs=needs)
    known = {spec.id for specs in registry.families().values() for spec in specs}
    mine = [f for op, f in script_nodes().items() if op in needs.ops and op not in known]
    if mine:
        module = types.ModuleType("__main__")
        module.__all__ = [f"node_{i}" for i in range(len(mine))]  # type: ignore[attr-defined]
        for index, func in enumerate(mine):
            setattr(module, f"node_{index}", func)
        registry.add_plugin(module, "__main__", "defined in __main__ (a script or a notebook)")
    return registry


def warn_of_failed_plugins(registry: Registry) -> None:
    """A warning, at the user's call, for each plugin of ``registry`` that failed to load
    (as the command line prints one): a run from Python whose ops were all found went on
    without a word, where a file of ``graph.plugins`` was missing or raised."""
    level, frame = 1, sys._getframe(0)
    while frame.f_back is not None and str(_ENGINE) in frame.f_code.co_filename:
        level, frame = level + 1, frame.f_back
    for plugin in registry.failed_plugins():
        warnings.warn(f"plugin '{plugin.name}' failed to load: {plugin.error}", stacklevel=level)
