"""Backends (kernel packages): one op, several implementations.

An op is declared once, by its ``@node`` function: id, ports, parameters,
documentation. That function is the op's **reference** implementation, of the
backend ``numpy``. Any plugin may add an implementation of an op for another
backend (``opencv``, or its own), with :func:`implements`::

    @implements("filters.gaussian", backend="opencv", requires=("cv2",), extra="opencv")
    def gaussian(image, *, sigma=1.0, truncate=4.0, mode="reflect", cval=0.0):
        ...

The implementation takes the op's inputs (positional, same names) and every
parameter of the op (keyword-only, same names); the engine validates values and
parameters with the op's port types and parameter model, so an implementation
never sees a value the reference would refuse. It returns what the op returns.

``requires`` names the modules the implementation imports when it runs; an
implementation whose modules are not installed is listed but not chosen, and
pinning it is a validation error naming ``extra`` (``pip install
'graphvision[opencv]'``). Those modules are found with ``importlib.util.find_spec``
(not imported) until a run uses the implementation, so listing the ops of a
backend does not import its library. ``requires`` may also hold

* releases: ``"opencv-python-headless<5"`` (a distribution, ``<`` or ``>=`` and a
  release), met when that distribution is not installed or its installed release is
  in range. They are read from the distributions' metadata (``importlib.metadata``,
  nothing imported), so ``graphvision nodes`` and ``describe`` (and the plugin index
  they print from) show an implementation the installed release cannot run as
  unavailable, and the install hint asks for the release (``pip install
  'graphvision[opencv]' 'opencv-python-headless<5'``);
* checks: functions returning why the installed library cannot run the
  implementation ('' when it can), such as a class a build of the library lacks;
  they run (and may import) only when a run considers the implementation, and a pin
  it fails is a validation error giving their reason.

``exclusive`` names parameter values only this implementation handles (OpenCV's
``method: magsac``): a node given one of them that runs another backend, the
reference included, is a validation error naming the backend that has it.

Each implementation has its own ``version``, and its code fingerprint covers its
own source and helpers, and the version of the libraries in ``requires``: the cache
key of a node names the backend that ran it (see :meth:`NodeSpec.key_id`), so the
results of two backends never stand in for each other.
"""

from __future__ import annotations

import dataclasses
import inspect
import re
import sys
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from functools import cache
from importlib.metadata import PackageNotFoundError
from importlib.metadata import version as release_of
from importlib.util import find_spec
from typing import Any

from graphvision.errors import RegistrationError
from graphvision.nodes.marks import unchecked
from graphvision.nodes.spec import FunctionRef, NodeSpec

__all__ = [
    "REFERENCE",
    "Check",
    "Implementation",
    "ImplementationMark",
    "exclusive_entries",
    "exclusive_problem",
    "implementation_problem",
    "implementation_spec",
    "implements",
    "installed",
    "listed_problem",
    "unavailable",
]

REFERENCE = "numpy"
"""The backend of every op's declaring function: always installed, the default."""


Check = Callable[[], str]
"""A requirement beyond a module: why the installed library cannot run it ('' if it can)."""


@dataclass(frozen=True)
class ImplementationMark:
    op: str
    backend: str
    version: int
    requires: tuple[str | Check, ...]
    extra: str
    exclusive: tuple[tuple[str, tuple[object, ...]], ...] = ()

    @property
    def modules(self) -> tuple[str, ...]:
        """The modules of ``requires`` (its releases and checks left out)."""
        return tuple(r for r in self.requires if isinstance(r, str) and not _RELEASE.match(r))

    @property
    def releases(self) -> tuple[str, ...]:
        """The releases of ``requires`` (``"opencv-python-headless<5"``)."""
        return tuple(r for r in self.requires if isinstance(r, str) and _RELEASE.match(r))


@dataclass(frozen=True)
class Implementation:
    """An implementation as registered: which op, which backend, the function, its plugin."""

    mark: ImplementationMark
    func: Callable
    ref: FunctionRef
    plugin: str

    @property
    def op(self) -> str:
        return self.mark.op

    @property
    def backend(self) -> str:
        return self.mark.backend

    @property
    def install_hint(self) -> str:
        """``pip install 'graphvision[EXTRA]'``, with the release it needs when it names
        one (the one the installed distribution is out of, else the first)."""
        extra, releases = self.mark.extra, self.mark.releases
        wrong = [r for r in releases if release_problem(r)]
        pinned = f" '{(wrong or releases)[0]}'" if releases else ""
        if extra:
            return f"pip install 'graphvision[{extra}]'{pinned}"
        if pinned:
            return f"pip install{pinned}"
        return f"install {', '.join(self.mark.modules)}"


def implements(
    op: str,
    *,
    backend: str,
    version: int = 1,
    requires: tuple[str | Check, ...] = (),
    extra: str = "",
    exclusive: Mapping[str, Sequence[object]] | None = None,
) -> Callable[[Callable], Callable]:
    """Mark a function as the ``backend`` implementation of the op ``op``.

    Parameters
    ----------
    op : str
        The id of the op (declared by some plugin's ``@node`` function).
    backend : str
        The backend's name (lower snake case; ``numpy`` is the reference's).
    version : int
        Bump it when the implementation's results change for reasons its source
        does not show; it is part of the cache key of every result it computes.
    requires : tuple of str or callable
        Modules the implementation imports when it runs (``("cv2",)``), and checks:
        functions returning why the installed library cannot run it ('' when it
        can), run only when a run considers the implementation.
    extra : str
        The ``graphvision`` extra that installs them, named by errors.
    exclusive : mapping of str to values, optional
        Parameter values this implementation alone handles (``{"method":
        ["magsac"]}``): any other backend given one is a validation error.
    """
    only = tuple((name, tuple(values)) for name, values in (exclusive or {}).items())

    def mark(func: Callable) -> Callable:
        func.__graphvision_implementation__ = ImplementationMark(  # type: ignore[attr-defined]
            op, backend, version, tuple(requires), extra, only
        )
        return func

    return mark


def implementation_of(func: Callable, plugin: str) -> Implementation:
    """The registered form of a marked function, or a RegistrationError naming it."""
    mark: ImplementationMark = func.__graphvision_implementation__  # type: ignore[attr-defined]
    where = f"plugin '{plugin}', function {func.__qualname__}"
    if mark.backend == REFERENCE or not mark.backend.isidentifier() or not mark.backend.islower():
        raise RegistrationError(
            f"{where}: backend must be a lower-case name other than '{REFERENCE}' "
            f"(the op's own function is its {REFERENCE} implementation), got {mark.backend!r}"
        )
    if not isinstance(mark.version, int) or isinstance(mark.version, bool) or mark.version < 1:
        raise RegistrationError(f"{where}: version must be a positive integer")
    odd = [r for r in mark.requires if isinstance(r, str) and not _requirement(r)]
    if odd:
        raise RegistrationError(
            f"{where}: requires holds modules ('cv2'), releases ('opencv-python-headless<5', "
            f"'numpy>=2') and checks; not {', '.join(map(repr, odd))}"
        )
    func = unchecked(func)
    module = sys.modules.get(func.__module__)
    path = getattr(module, "__graphvision_path__", "") if module else ""
    return Implementation(mark, func, FunctionRef(func.__module__, func.__qualname__, path), plugin)


def implementation_problem(spec: NodeSpec, impl: Implementation) -> str:
    """Why ``impl`` cannot implement ``spec`` ('' when it can): its inputs must be the op's
    inputs in order, and its keyword-only parameters the op's parameters."""
    parameters = inspect.signature(impl.func).parameters.values()
    inputs = [p.name for p in parameters if p.kind in (p.POSITIONAL_ONLY, p.POSITIONAL_OR_KEYWORD)]
    params = {p.name for p in parameters if p.kind == p.KEYWORD_ONLY}
    where = f"plugin '{impl.plugin}', function {impl.func.__qualname__}"
    if inputs != list(spec.inputs):
        return (
            f"{where}: the {impl.backend} implementation of {spec.id} takes inputs "
            f"({', '.join(inputs)}) but the op's are ({', '.join(spec.inputs)})"
        )
    strange = sorted(name for name, _ in impl.mark.exclusive if name not in spec.param_fields)
    if strange:
        return f"{where}: exclusive names no parameter of {spec.id}: {', '.join(strange)}"
    if params != set(spec.param_fields):
        missing = sorted(set(spec.param_fields) - params)
        extra = sorted(params - set(spec.param_fields))
        return (
            f"{where}: the {impl.backend} implementation of {spec.id} must take the op's "
            f"parameters; missing: {', '.join(missing) or 'none'}; "
            f"not the op's: {', '.join(extra) or 'none'}"
        )
    return ""


def installed(impl: Implementation) -> bool:
    """True when every module ``impl`` requires can be imported and every release it
    requires is met (found and read from metadata, nothing imported; its checks are
    not run: see :func:`unavailable`)."""
    return not listed_problem(impl)


def listed_problem(impl: Implementation) -> str:
    """Why ``impl`` cannot run here, as far as is known without importing anything
    ('' when nothing is): its modules not found, or an installed release out of range."""
    missing = [module for module in impl.mark.modules if not _found(module)]
    if missing:
        return f"{', '.join(missing)} not found"
    for release in impl.mark.releases:
        reason = release_problem(release)
        if reason:
            return reason
    return ""


def unavailable(impl: Implementation) -> str:
    """Why ``impl`` cannot run here ('' when it can): its modules not found, the reason
    a check of ``requires`` gives (the checks may import the library: they say what the
    library lacks), or an installed release out of range."""
    missing = [module for module in impl.mark.modules if not _found(module)]
    if missing:
        return f"{', '.join(missing)} not found"
    for check in impl.mark.requires:
        if not isinstance(check, str):
            reason = check()
            if reason:
                return reason
    return listed_problem(impl)


_RELEASE = re.compile(r"^([A-Za-z0-9][A-Za-z0-9._-]*)\s*(<|>=)\s*(\d+(?:\.\d+)*)$")
_MODULE = re.compile(r"^[A-Za-z_]\w*(\.[A-Za-z_]\w*)*$")


def _requirement(text: str) -> bool:
    return bool(_MODULE.match(text) or _RELEASE.match(text))


@cache
def release_problem(requirement: str) -> str:
    """Why the installed distribution is out of ``requirement`` (``"name<5"``,
    ``"name>=4.8"``), read from its metadata; '' when it is in range or not installed."""
    match = _RELEASE.match(requirement)
    if match is None:  # pragma: no cover - registration refuses other forms
        return ""
    name, operator, bound = match.groups()
    try:
        installed_release = release_of(name)
    except PackageNotFoundError:
        return ""
    leading = re.match(r"\d+(?:\.\d+)*", installed_release)  # 5.0.0rc1: 5.0.0
    numbers = tuple(int(n) for n in leading.group().split(".")) if leading else ()
    limit = tuple(int(n) for n in bound.split("."))
    if (numbers < limit) == (operator == "<"):
        return ""
    return f"{name} {installed_release} is installed; needs {name}{operator}{bound}"


Exclusive = tuple[tuple[str, tuple[object, ...]], ...]


def exclusive_entries(plugins: dict[str, dict[str, Any]]) -> dict[str, tuple[Exclusive, str]]:
    """``op@backend`` -> (its ``exclusive`` values, its install hint), for every
    implementation of the index's ``plugins`` that declares some: a pipeline is refused
    a value only a backend it did not load handles without importing that backend."""
    found: dict[str, tuple[Exclusive, str]] = {}
    for entry in plugins.values():
        recorded = entry.get("exclusive")
        for name, item in (recorded if isinstance(recorded, dict) else {}).items():
            values = item.get("values") if isinstance(item, dict) else None
            if isinstance(values, dict) and isinstance(item.get("hint"), str):
                pairs = tuple((p, tuple(v)) for p, v in values.items() if isinstance(v, list))
                found[name] = (pairs, item["hint"])
    return found


def exclusive_problem(
    op: str,
    backend: str,
    others: Mapping[str, tuple[Exclusive, str]],
    params: Mapping[str, object],
) -> str:
    """Why ``backend`` cannot run ``op`` with ``params`` ('' when it can): a value
    another backend's implementation declares ``exclusive`` (it alone handles it).
    ``others``: backend -> (its ``exclusive`` values, its install hint), as
    :meth:`~graphvision.nodes.registry.Registry.exclusive_of` gives them."""
    for other, (exclusive, hint) in sorted(others.items()):
        if other == backend:
            continue
        for name, values in exclusive:
            value = params.get(name)
            if any(value == v and type(value) is type(v) for v in values):
                return (
                    f"{name}: {value!r} of {op} is implemented by the '{other}' backend "
                    f"alone, not by '{backend}': choose it (--backend {other}, "
                    f"backends: [{other}] or backend: {other} on the node; {hint})"
                )
    return ""


@cache
def _found(module: str) -> bool:
    try:
        return find_spec(module) is not None
    except (ImportError, ValueError):
        return False


def implementation_spec(spec: NodeSpec, impl: Implementation) -> NodeSpec:
    """The op's spec running ``impl``: same ports, parameters and documentation; the
    implementation's function, version, plugin and backend."""
    return dataclasses.replace(
        spec,
        version=impl.mark.version,
        func=impl.func,
        ref=impl.ref,
        plugin=impl.plugin,
        backend=impl.backend,
        requires=impl.mark.modules,
    )
