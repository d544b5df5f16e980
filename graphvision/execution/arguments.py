"""Arguments of the Python API checked at the door: :func:`~graphvision.run`,
:func:`~graphvision.run_batch` and :func:`~graphvision.sweep` take what people
pass (a pipeline file's path, one output name, ``pathlib`` paths) and refuse
the rest with a ``TypeError`` naming the argument, instead of an
``AttributeError`` from deep inside the engine.
"""

from __future__ import annotations

import os
from collections.abc import Iterable, Mapping, Sequence
from functools import partial
from itertools import repeat
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from graphvision.cache.store import Cache
from graphvision.compiler.compile import CompiledGraph
from graphvision.errors import UnknownNameError, did_you_mean
from graphvision.execution.executors import EXECUTORS
from graphvision.execution.inputs import resolve_input
from graphvision.execution.limits import NodeLimits, current_limits
from graphvision.execution.peak_memory import environment_memory
from graphvision.graph.model import Graph
from graphvision.values.budget import max_pixels as budget_in_force
from graphvision.values.known import note, recall

if TYPE_CHECKING:
    from graphvision.compiler.compile import Schedule
    from graphvision.nodes.registry import Registry
    from graphvision.values.ports import PortType

__all__ = [
    "admitted",
    "checked_run_arguments",
    "environment_limits",
    "given_inputs",
    "graph_argument",
    "input_values",
    "mapping_argument",
    "names_argument",
    "refuse_unknown_inputs",
    "run_arguments",
    "wanted_outputs",
]


def graph_argument(graph: Any, backends: Any = None) -> Graph | CompiledGraph:
    """A ``Graph`` or ``CompiledGraph`` as given, or the pipeline file a path names; with
    ``backends`` (a lookup order), the graph with that order, to be compiled with it."""
    if backends is not None:
        given = graph_argument(graph)
        plain = given.graph if isinstance(given, CompiledGraph) else given
        return plain.with_backends(backends)
    if isinstance(graph, (Graph, CompiledGraph)):
        return graph
    if isinstance(graph, (str, os.PathLike)):
        from graphvision.graph.pipeline_file import load_pipeline

        return load_pipeline(Path(graph))
    raise TypeError(
        f"graph must be a gv.Graph, a compiled graph or a pipeline file's path, "
        f"got {type(graph).__name__}"
    )


def names_argument(names: Any, what: str) -> list[str] | None:
    """``None``, one name, or an iterable of names, as a list (``outputs="count"`` is one)."""
    if names is None:
        return None
    if isinstance(names, str):
        return [names]
    if isinstance(names, Iterable) and not isinstance(names, Mapping):
        listed = list(names)
        if all(isinstance(name, str) for name in listed):
            return listed
    raise TypeError(f"{what} must be a name or a list of names, got {names!r}")


def mapping_argument(value: Any, what: str) -> dict[str, Any]:
    """``None`` or a mapping from names, as a dict; ``pathlib`` paths among the values as
    strings (a path given as ``Path`` reads like the same path given as ``str``)."""
    if value is None:
        return {}
    if type(value) is not dict and not isinstance(value, Mapping):  # (a dict: no ABC check)
        raise TypeError(f"{what} must be a dict from names to values, got {value!r}")
    if not all(map(isinstance, value, repeat(str))):  # (in C: no Python step per name)
        raise TypeError(f"{what} must be a dict from names to values, got {value!r}")
    if all(map(_NO_PATHS.__contains__, map(type, value.values()))):  # (none is a path)
        return dict(value)
    return {key: _text_if_path(v) for key, v in value.items()}


_NO_PATHS = frozenset({str, int, float, bool, type(None), np.ndarray})
"""Types whose values are no ``os.PathLike`` (decided without the ABC's check: an array
given as an input is the common case)."""


def _text_if_path(value: Any) -> Any:
    if type(value) in _NO_PATHS or not isinstance(value, os.PathLike):
        return value
    return os.fspath(value)


def environment_limits(
    *, max_pixels: int | None = None, max_memory: int | None = None
) -> NodeLimits:
    """Refuse a limit the environment sets that is malformed (``GRAPHVISION_MAX_PIXELS``,
    ``GRAPHVISION_NODE_TIMEOUT``, ``GRAPHVISION_NODE_MEMORY``, ``GRAPHVISION_MAX_MEMORY``),
    naming the variable and its value, before any work: each was read only where it is
    used (the pixel budget when a file is read, deep in a run or per file of a batch). A
    limit given as an argument (``max_pixels``, ``max_memory``) supersedes its variable.

    Raises
    ------
    InputError
        Naming the variable, its value and what it takes.

    Returns
    -------
    NodeLimits
        The node limits in force (:func:`~graphvision.execution.limits.current_limits`), as
        read here: a run takes them instead of reading the environment again.
    """
    if max_pixels is None:
        budget_in_force()
    limits = current_limits()
    if max_memory is None:
        environment_memory()
    return limits


def run_arguments(cache: Any, executor: Any, workers: Any, **limits: int | None) -> NodeLimits:
    """Refuse a cache, executor or worker count of the wrong kind, saying what is taken, and
    a malformed limit in the environment (:func:`environment_limits`, given ``limits``);
    the node limits in force."""
    if cache is not None and not isinstance(cache, Cache):
        hint = " (for a folder: gv.Cache.at(path))" if isinstance(cache, (str, os.PathLike)) else ""
        raise TypeError(f"cache must be a gv.Cache or None, got {cache!r}{hint}")
    if isinstance(executor, str):
        if executor not in EXECUTORS:
            raise ValueError(f"executor must be one of {', '.join(EXECUTORS)}, got {executor!r}")
    elif not callable(getattr(executor, "submit", None)):
        raise TypeError(
            f"executor must be one of {', '.join(EXECUTORS)} or an executor with submit(), "
            f"got {executor!r}"
        )
    if workers is not None and (isinstance(workers, bool) or not isinstance(workers, int)):
        raise TypeError(f"workers must be a whole number, got {workers!r}")
    if isinstance(workers, int) and workers < 1:
        raise ValueError(f"workers must be at least 1, got {workers}")
    return environment_limits(**limits)


def wanted_outputs(
    compiled: CompiledGraph, outputs: Sequence[str] | None, inputs: dict[str, Any]
) -> list[str]:
    """The outputs asked for, after checking every output and input name given."""
    wanted = list(outputs) if outputs is not None else list(compiled.outputs)
    for name in wanted:
        if name not in compiled.outputs:
            raise UnknownNameError(
                f"unknown output '{name}'{did_you_mean(name, compiled.outputs)}"
                f"; outputs: {', '.join(compiled.outputs)}"
            )
    refuse_unknown_inputs(inputs, compiled.input_types)
    return wanted


def refuse_unknown_inputs(given: Iterable[str], declared: Iterable[str]) -> None:
    """UnknownNameError for the first of ``given`` that the pipeline does not declare."""
    names = list(declared)
    for name in given:
        if name not in names:
            raise UnknownNameError(
                f"unknown input '{name}'{did_you_mean(name, names)}; "
                f"inputs: {', '.join(names) or 'none'}"
            )


def given_inputs(
    compiled: CompiledGraph, schedule: Schedule, inputs: dict[str, Any]
) -> dict[str, Any]:
    """What is given for each graph input the wanted outputs read (step 2): value or default."""
    return {
        name: inputs.get(name, compiled.graph.inputs[name].default)
        for name in compiled.input_types
        if name in schedule.inputs
    }


def admitted(
    name: str, kind: type[PortType], value: Any, registry: Registry, graph: Graph | None = None
) -> Any:
    """:func:`~graphvision.execution.inputs.resolve_input` (``graph``: the pipeline whose
    default ``value`` is, if it is one); a frozen array given again, that it returned as it
    was the last time, as it is (:mod:`graphvision.values.known`: no pass over its data)."""
    if recall(value, (resolve_input, kind)):
        return value
    resolved = resolve_input(name, kind, value, registry, graph=graph)
    if resolved is value:
        note(value, (resolve_input, kind), True)
    return resolved


def input_values(
    compiled: CompiledGraph,
    given: dict[str, Any],
    inputs: dict[str, Any],
    reference_keys: Any,
    registry: Registry,
) -> dict[str, Any]:
    """Each input's value as the run takes it: :func:`admitted`, or, for an input named
    by a reference (``reference_keys``: resolved only if a node needs it), a call that
    resolves it; a default is resolved with its pipeline (its errors at its line)."""
    values: dict[str, Any] = {}
    for name, value in given.items():
        kind, graph = compiled.input_types[name], None if name in inputs else compiled.graph
        if name in reference_keys:
            values[name] = partial(resolve_input, name, kind, value, registry, graph=graph)
        else:
            values[name] = admitted(name, kind, value, registry, graph)
    return values


def checked_run_arguments(
    graph: Any,
    inputs: Any,
    outputs: Any,
    overrides: Any,
    running: tuple[Any, Any, Any],
    max_pixels: Any,
    max_memory: Any,
) -> tuple[Graph | CompiledGraph, dict[str, Any], list[str] | None, dict[str, Any], NodeLimits]:
    """The arguments of :func:`~graphvision.execution.run.run` as it uses them, or a
    TypeError naming the wrong one; ``running``: its cache, executor and workers. A
    malformed limit in the environment is refused (an InputError) unless the argument of
    that limit supersedes it. Last, the node limits in force, as read for that check."""
    limits = run_arguments(*running, max_pixels=max_pixels, max_memory=max_memory)
    return (
        graph_argument(graph),
        mapping_argument(inputs, "inputs"),
        names_argument(outputs, "outputs"),
        mapping_argument(overrides, "overrides"),
        limits,
    )
