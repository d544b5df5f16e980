"""The fingerprint of the code a node runs, taken from the loaded code.

A node's cache key must change whenever the code that computes it changes,
and only then. The fingerprint therefore covers, from the code objects in
memory (never the file on disk, which may be newer than what was imported):

* the node function's bytecode, names and constants (docstrings, line
  numbers and file names left out, so editing documentation or comments,
  or moving a function in its file, keeps the cache);
* every function, class method and constant of the same project that it
  reaches through its global names, attribute chains and closures,
  recursively (a helper in another module of the package, a numba kernel's
  Python function, a lookup table);
* the source files of this project's modules that such a function imports
  inside its body (``from ._kernels import kernel``: a numba kernel module
  imported on first use, so that start-up stays fast), and the files of the
  project's modules those files import, followed to the end (a kernel
  calling a kernel of another file). Their code may not be loaded yet, so
  the file's bytes are what identifies it, the same whether or not the
  module has been imported (a module edited on disk after it was imported in
  a long-running process is the one case this misreads);
* the version of the installed distribution that provides the node, so that
  an upgrade of a plugin invalidates its results even where the code that
  changed is out of reach (compiled extensions).

"Same project" is the top-level package of the node's module (for an
installed plugin) or the module itself (a local plugin file). Calls into
other libraries (numpy, scipy) are covered by nothing here: upgrading them
keeps the cache, as it keeps the results of nearly every function.

Fingerprints are memoised per function object: a reloaded module gives new
function objects and so new fingerprints.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import types
import weakref
from collections.abc import Callable
from functools import cache
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from importlib.machinery import ModuleSpec

__all__ = [
    "code_fingerprint",
    "distributions_of",
    "library_version",
    "node_fingerprint",
    "note_distribution",
    "top_level_distributions",
]

_MEMO: weakref.WeakKeyDictionary[Callable[..., Any], str] = weakref.WeakKeyDictionary()
_SCALARS = (int, float, complex, str, bytes, bool, type(None))
_NESTED = object()  # code nested in a function (a comprehension, a lambda): no docstring slot


def code_fingerprint(func: Callable[..., Any]) -> str:
    """A 32-hex-digit digest of the code ``func`` runs (see the module docstring)."""
    try:
        return _MEMO[func]
    except (KeyError, TypeError):
        pass
    project = _project_of(getattr(func, "__module__", "") or "")
    hasher = hashlib.blake2b(digest_size=16)
    hasher.update(_distribution_version(project).encode())
    _Walker(hasher, project).function(func)
    digest = hasher.hexdigest()
    with contextlib.suppress(TypeError):  # not weak-referenceable: recomputed each time
        _MEMO[func] = digest
    return digest


def _project_of(module: str) -> str:
    return module.split(".", 1)[0]


def _in_project(obj: Any, project: str) -> bool:
    module = getattr(obj, "__module__", None)
    return isinstance(module, str) and _project_of(module) == project


@cache
def top_level_distributions() -> dict[str, list[str]]:
    """Top-level package -> distributions providing it, read once per process (it is slow)."""
    from importlib.metadata import packages_distributions

    return dict(packages_distributions())


_NOTED: dict[str, list[str]] = {}


def note_distribution(top_level: str, distribution: str) -> None:
    """Remember that ``distribution`` provides package ``top_level`` (plugin discovery knows
    it from the entry point), so :func:`distributions_of` need not scan every installed
    distribution's metadata (0.1 s or more)."""
    names = _NOTED.setdefault(top_level, [])
    if distribution not in names:
        names.append(distribution)


def distributions_of(top_level: str) -> list[str]:
    """The distributions providing top-level package ``top_level``: those noted by plugin
    discovery, none for a local plugin file, else from the installed metadata."""
    if top_level in _NOTED:
        return _NOTED[top_level]
    if top_level.startswith("graphvision_local_"):  # a plugin file: no distribution
        return []
    return top_level_distributions().get(top_level, [])


@cache
def _distribution_version(project: str) -> str:
    """``name==version`` of the installed distribution providing ``project``, or ''."""
    from importlib.metadata import version

    names = distributions_of(project)
    return ";".join(f"{name}=={version(name)}" for name in sorted(set(names)))


def library_version(module: str) -> str:
    """``name==version`` of the distributions providing top-level module ``module``
    (``cv2`` -> ``opencv-python-headless==4.10.0.84``), or ``module==?`` when none is
    found; read from the installed metadata, without importing the module."""
    return _distribution_version(module) or f"{module}==?"


class _Walker:
    """Feeds a hash with everything of one project that a function reaches."""

    def __init__(self, hasher: Any, project: str) -> None:
        self.hasher = hasher
        self.project = project
        self.seen: set[int] = set()
        self.seen_modules: set[tuple[str, str]] = set()

    def feed(self, *parts: object) -> None:
        for part in parts:
            self.hasher.update(repr(part).encode())
            self.hasher.update(b"\0")

    def function(self, func: Any) -> None:
        func = getattr(func, "py_func", func)  # a numba dispatcher: its Python function
        while hasattr(func, "__wrapped__"):  # a node's checked wrapper, functools.wraps
            func = func.__wrapped__
        code = getattr(func, "__code__", None)
        if code is None or id(func) in self.seen:
            return
        self.seen.add(id(func))
        self.feed("function")
        doc = getattr(func, "__doc__", None)
        self.code(code, doc)
        namespace = getattr(func, "__globals__", {})
        package = namespace.get("__package__") or ""
        imported = _imported_modules(code, package)
        # a submodule imported in the body appears in its package's namespace once imported:
        # it is covered by its file below, the same before and after the import
        skipped = {module.rpartition(".")[2] for module in imported}
        for name in _global_names(code):
            if name in namespace and name not in skipped:
                self.reference(name, namespace[name], _attribute_names(code))
        for module in imported:
            if _project_of(module) == self.project:
                self.source_file(module)
        for cell in getattr(func, "__closure__", None) or ():
            try:
                self.value("closure", cell.cell_contents)
            except ValueError:  # an empty cell
                continue

    def source_file(self, module: str) -> None:
        """The bytes of ``module``'s source file (a module imported inside a function)."""
        if ("module", module) in self.seen_modules:
            return
        self.seen_modules.add(("module", module))
        origin = _module_file(module)
        self.feed("imported module", module)
        if not origin:
            return
        try:
            with open(origin, "rb") as handle:
                source = handle.read()
        except OSError:
            return
        self.hasher.update(hashlib.blake2b(source, digest_size=16).digest())
        # and the project's modules that file imports (a kernel calling a kernel of another
        # file: ``from ..fitting._kernels import draw_sample``), followed to the end
        package = module if origin.endswith("__init__.py") else module.rpartition(".")[0]
        for imported in _file_imports(origin, source, package):
            if _project_of(imported) == self.project:
                self.source_file(imported)

    def code(self, code: types.CodeType, doc: object) -> None:
        constants = list(code.co_consts)
        if doc is not _NESTED and constants and constants[0] in (doc, None):
            constants = constants[1:]  # a function's docstring slot (None when it has none)
        self.feed(code.co_code, code.co_names, code.co_varnames, code.co_freevars, code.co_argcount)
        for constant in constants:
            if isinstance(constant, types.CodeType):
                self.code(constant, _NESTED)
            else:
                self.feed(constant)

    def reference(self, name: str, obj: Any, attributes: set[str]) -> None:
        """A global the code names: follow it when it is this project's."""
        if isinstance(obj, types.ModuleType):
            if _project_of(obj.__name__) != self.project:
                self.feed("module", name, obj.__name__)
                return
            for attribute in sorted(attributes):  # `_kernels.descriptor(...)`
                if hasattr(obj, attribute):
                    self.reference(f"{name}.{attribute}", getattr(obj, attribute), set())
            return
        self.value(name, obj)

    def value(self, name: str, obj: Any) -> None:
        if isinstance(obj, _SCALARS) or (
            isinstance(obj, tuple | frozenset) and all(isinstance(o, _SCALARS) for o in obj)
        ):
            self.feed("constant", name, obj)
        elif isinstance(obj, np.ndarray) and obj.dtype != object:
            self.feed("array", name, obj.dtype.str, obj.shape)
            self.hasher.update(np.ascontiguousarray(obj).tobytes())
        elif isinstance(obj, type) and _in_project(obj, self.project):
            if id(obj) in self.seen:
                return
            self.seen.add(id(obj))
            self.feed("class", obj.__qualname__)
            for attribute, member in sorted(vars(obj).items()):
                if not attribute.startswith("__"):
                    self.value(f"{name}.{attribute}", member)
        elif isinstance(obj, staticmethod | classmethod):
            self.value(name, obj.__func__)
        elif callable(obj) and _in_project(obj, self.project):
            self.function(obj)
        elif isinstance(obj, dict) and len(obj) < 1000:
            for key in sorted(obj, key=repr):
                if isinstance(key, _SCALARS):
                    self.value(f"{name}[{key!r}]", obj[key])


def _global_names(code: types.CodeType) -> list[str]:
    """The global and attribute names of ``code`` and of the code nested in it."""
    names = list(code.co_names)
    for constant in code.co_consts:
        if isinstance(constant, types.CodeType):
            names += _global_names(constant)
    return sorted(set(names))


def _imported_modules(code: types.CodeType, package: str) -> list[str]:
    """Absolute names of the modules ``code`` (and code nested in it) imports in its body,
    with the submodules a ``from package import name`` may mean."""
    import dis
    from importlib.util import resolve_name

    found: list[str] = []
    constants: list[object] = []
    for instruction in dis.get_instructions(code):
        if instruction.opname == "LOAD_CONST":
            constants = [*constants[-1:], instruction.argval]
        elif instruction.opname == "IMPORT_NAME" and len(constants) == 2:
            level, names = constants
            relative = "." * level if isinstance(level, int) else ""
            try:
                module = (
                    resolve_name(relative + instruction.argval, package)
                    if relative
                    else (instruction.argval)
                )
            except (ImportError, ValueError):
                continue
            found.append(module)
            if isinstance(names, tuple):
                found += [f"{module}.{name}" if module else name for name in names]
    for constant in code.co_consts:
        if isinstance(constant, types.CodeType):
            found += _imported_modules(constant, package)
    return found


@cache
def _file_imports(origin: str, source: bytes, package: str) -> tuple[str, ...]:
    """The modules a source file imports anywhere in it (:func:`_imported_modules` of its
    compiled code; nothing when it does not compile)."""
    try:
        code = compile(source, origin, "exec", dont_inherit=True)
    except (SyntaxError, ValueError):
        return ()
    return tuple(_imported_modules(code, package))


def _module_file(module: str) -> str:
    """The source file of ``module`` without importing it ('' when it is not a module)."""
    import sys

    loaded = sys.modules.get(module)
    if loaded is not None:
        return str(getattr(loaded, "__file__", "") or "")
    spec = _module_spec(module)
    origin = spec.origin if spec is not None else None
    return origin if origin and origin.endswith(".py") else ""


def _module_spec(module: str) -> ModuleSpec | None:
    """The spec of ``module``, found without importing it nor its packages (None: no module).

    ``importlib.util.find_spec("pkg.mod.name")`` imports ``pkg.mod`` to look
    for ``name`` in it, and ``from pkg.mod import name`` in a node's body gives
    such a name: fingerprinting a node that imports a numba kernel lazily then
    imported numba (0.13 s) on runs that never call the node.
    """
    import sys
    from importlib.machinery import PathFinder
    from importlib.util import find_spec

    loaded = sys.modules.get(module)
    if loaded is not None:
        return getattr(loaded, "__spec__", None)
    parent, _, _ = module.rpartition(".")
    try:
        if not parent:
            return find_spec(module)  # a top-level name: nothing to import first
        package = _module_spec(parent)
        if package is None or package.submodule_search_locations is None:
            return None  # the parent is a module (or none): the name is an attribute
        return PathFinder.find_spec(module, list(package.submodule_search_locations))
    except (ImportError, ValueError, AttributeError):
        return None


def _attribute_names(code: types.CodeType) -> set[str]:
    return set(_global_names(code))


def node_fingerprint(op: str, version: int, source_hash: str, params: dict[str, Any]) -> str:
    """Canonical text of what a node is: id, version, code fingerprint, parameters."""
    return json.dumps([op, version, source_hash, params], sort_keys=True, separators=(",", ":"))
