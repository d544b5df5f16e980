"""What is wrong with the command line's overrides (``-s NODE.PARAM=V``,
``--grid NODE.PARAM=V1,V2``): a node, parameter or pipeline param that does not exist, and a
value its parameter refuses, every one of them found at once."""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from typing import TYPE_CHECKING, Any

from graphvision.errors import did_you_mean

if TYPE_CHECKING:
    from graphvision.graph.model import Graph
    from graphvision.nodes.registry import Registry

__all__ = ["refused_overrides"]


def refused_overrides(
    graph: Graph,
    registry: Registry,
    overrides: dict[str, Any],
    flag: str,
    swept: bool = False,
    malformed: Sequence[str] = (),
    also_overridden: Iterable[str] = (),
) -> tuple[list[str], int, int]:
    """Every override of a node or parameter that does not exist and every value its
    parameter refuses, one line each after the ``malformed`` ones (values that could not be
    read), naming the command line; with how many overrides they concern, and how many of
    those name nothing. ``swept``: each override holds a list of values (``--grid``).
    ``also_overridden``: the node parameters the command line's other flag sets (a sweep's
    ``-s`` and ``--grid``), which a pipeline param's value no longer reaches."""
    problems, refused, unknown = list(malformed), len(malformed), 0
    overridden = {*overrides, *also_overridden}
    for key, value in overrides.items():
        if problem := _unknown_target(graph, registry, key):
            problems.append(f"{flag} {key}={value!r}: {problem}")
            refused, unknown = refused + 1, unknown + 1
            continue
        found = [
            f"{flag} {key}={each!r}: {said}"
            for each in (value if swept else [value])
            for said in _refused(graph, registry, key, each, overridden)
        ]
        problems += found
        refused += bool(found)
    return problems, refused, unknown


def _refused(
    graph: Graph, registry: Registry, key: str, value: Any, overridden: Iterable[str] = ()
) -> list[str]:
    """Why the parameter ``key`` (NODE.PARAM or params.NAME, which exists) refuses ``value``
    on its own; for a pipeline param, why each node parameter that is that param whole
    (``"${params.NAME}"``) and is not ``overridden`` itself refuses it (one inside a longer
    text is checked when compiled)."""
    import pydantic

    target, _, param = key.partition(".")
    if target == "params":
        reference = f"${{params.{param}}}"
        uses = [
            f"{node}.{name}"
            for node, decl in graph.nodes.items()
            for name, given in decl.params.items()
            if isinstance(given, str)
            and given.strip() == reference
            and f"{node}.{name}" not in overridden
        ]
        uses_refusing: dict[str, list[str]] = {}  # the same words from nodes of one op: one line
        for use in uses:
            for said in _refused(graph, registry, use, value):
                uses_refusing.setdefault(said, []).append(use)
        return [f"{said} (as {', '.join(names)})" for said, names in uses_refusing.items()]
    spec = registry.nodes.get(graph.nodes[target].op) if target in graph.nodes else None
    if spec is None:
        return []
    try:
        spec.validate_params({param: value})
    except pydantic.ValidationError as error:
        found = spec.param_problems(error)
        return [said for name, said in found if name == param or name.startswith(f"{param}.")]
    return []


def _unknown_target(graph: Graph, registry: Registry, key: str) -> str:
    """What is wrong with the override ``key`` (NODE.PARAM or params.NAME), or ''."""
    target, _, param = key.partition(".")
    if not param:
        return "expected NODE.PARAM or params.NAME"
    if target == "params":
        if param not in graph.params:
            return f"the pipeline has no param '{param}'{did_you_mean(param, graph.params)}"
        return ""
    if target not in graph.nodes:
        return f"the pipeline has no node '{target}'{did_you_mean(target, graph.nodes)}"
    spec = registry.nodes.get(graph.nodes[target].op)
    if spec is not None and param not in spec.param_fields:
        names = list(spec.param_fields)
        hint, listing = did_you_mean(param, names), ", ".join(names) or "none"
        return f"{spec.id} has no parameter '{param}'{hint}; parameters: {listing}"
    return ""
