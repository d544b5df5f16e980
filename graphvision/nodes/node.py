"""Nodes: a typed Python function plus a decorator.

::

    @node("filters.gaussian", version=1)
    def gaussian(image: ImageT, *, sigma: Annotated[float, Field(gt=0)] = 1.0) -> ImageT:
        '''NumPy-style docstring: the node's documentation.'''

* positional parameters are **input ports**, annotated with an alias of
  :mod:`graphvision.types` (``Annotated[value type, port type]``; a bare port
  class is still read) and ``Optional[T] = None`` makes the port optional;
* keyword-only parameters are **parameters**, with defaults, validated by a
  pydantic model built from their annotations (``Annotated[..., Field(...)]``
  for constraints, ``Literal[...]`` for choices);
* the return annotation is the **output**: one port type (port ``out``) or a
  ``NamedTuple`` whose fields are port types (one port per field);
* a ``TypeVar`` makes a node generic: ``def gaussian(image: ImageT) -> ImageT``
  with ``ImageT = TypeVar("ImageT", GrayImage, ColorImage, Image)`` gives a
  ``GrayImage`` out for a ``GrayImage`` in. The checker binds the variable to
  the first constraint the connected type is a subtype of (a bound works
  too, binding to the connected type itself).

Signatures are checked when a plugin registers (:func:`build_spec`), not when
the node first runs. The decorator returns the function wrapped so that a
direct call (``gaussian(image, sigma=2)`` in a script or a test) takes its
inputs through the same dtype policy as a run's graph inputs (a ``uint8``
photo is the image its PNG gives), validates them with the same port types
and its parameters with the same pydantic model as a run does, and fails
with a :class:`~graphvision.PortValueError` or
:class:`~graphvision.ParameterError` naming the node and the port or
parameter. The engine validates values itself and calls the unchecked
function (``NodeSpec.func``, also ``checked.__wrapped__``), so nothing is
checked twice on a run's hot path.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from typing import Any

from graphvision.nodes.marks import Conformance, NodeMark, SourceMark
from graphvision.nodes.signature import build_spec
from graphvision.nodes.spec import NodeSpec

__all__ = [
    "node",
    "script_nodes",
    "source",
]

_SCRIPT_NODES: dict[str, Callable] = {}
"""Nodes defined in ``__main__`` (a script, a notebook), by id: the last definition wins,
as when a notebook cell is run again."""


def script_nodes() -> dict[str, Callable]:
    """The nodes defined so far in ``__main__`` (a script or a notebook), by id.

    ``gv.run(graph)`` without a registry adds those the graph uses to the registry it
    discovers, so a node written in a notebook runs without a registry call.
    """
    return dict(_SCRIPT_NODES)


def node(
    id: str,
    *,
    version: int = 1,
    cache: bool = True,
    overrides: bool = False,
    check: Callable[..., None] | None = None,
    conformance: Conformance | None = None,
) -> Callable[[Callable], Callable]:
    """Mark a function as the graphvision node ``id`` (``family.name``).

    Parameters
    ----------
    id : str
        Stable node id, ``family.name`` in lower snake case.
    version : int
        Bump it when the node's results change for reasons its own source does
        not show (a helper it calls changed); it is part of every cache key.
    cache : bool
        False opts the node out of caching (it is recomputed on every run).
    overrides : bool
        True lets this node replace another plugin's node of the same id.
    check : callable, optional
        ``check(**params)`` raises ``ValueError`` for parameter values that are
        each valid but not together (``p2 < p1``, an even window): it runs with
        the parameter model, so a pipeline is refused before anything runs and a
        direct call before the body, naming the node.
    conformance : Conformance, optional
        How far another backend's implementation may differ from this one (the
        reference) on the conformance suite's inputs (see :mod:`.backends`).
    """

    def mark(func: Callable) -> Callable:
        func.__graphvision_node__ = NodeMark(id, version, cache, overrides, check, conformance)  # type: ignore[attr-defined]
        checked = _checked_call(func)
        if func.__module__ == "__main__":
            _SCRIPT_NODES[id] = checked
        return checked

    return mark


def _checked_call(func: Callable) -> Callable:
    """``func`` behind the checks a run makes: inputs by port type, parameters by model."""
    specs: list[NodeSpec] = []  # built on the first call: registration stays the checker

    @functools.wraps(func)
    def checked(*args: Any, **kwargs: Any) -> Any:
        if not specs:
            specs.append(build_spec(func, plugin=func.__module__))
        inputs, params = specs[0].check_call(args, kwargs)
        return func(*inputs, **params)

    return checked


def source(
    scheme: str, *, key: Callable[[str], str] | None = None
) -> Callable[[Callable], Callable]:
    """Mark ``func(reference: str)`` as the loader of graph-input values ``scheme:reference``.

    The scheme ``file`` is used for values without a scheme (paths). ``key``,
    for a source whose values are fixed by the reference (data shipped with a
    library), gives the text that identifies the value without loading it
    (e.g. name and library version): the cache keys the input by that text,
    and a fully cached run never loads the value.
    """

    def mark(func: Callable) -> Callable:
        func.__graphvision_source__ = SourceMark(scheme, key)  # type: ignore[attr-defined]
        return func

    return mark
