"""A sweep's grid checked before anything runs: its shape, every value, the combinations'
pipelines (:func:`graphvision.execution.sweep.sweep` runs them)."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

from graphvision.compiler.compile import CompiledGraph, compile_graph
from graphvision.errors import PipelineError, Problem, did_you_mean
from graphvision.graph.model import Graph
from graphvision.nodes.registry import Registry

__all__ = ["MAX_COMBINATIONS", "checked_combinations", "compile_combination", "grid_values"]

MAX_COMBINATIONS = 10_000
"""A larger grid is refused before anything runs (each combination is a whole run)."""


def grid_values(
    graph: Graph, grid: Mapping[str, Sequence[Any]], keys: list[str]
) -> list[list[Any]]:
    """Each key's values, or every problem of the grid's shape at once (PipelineError)."""
    for key in keys:
        if isinstance(grid[key], (str, bytes)) or not isinstance(grid[key], Sequence):
            raise PipelineError(
                [Problem(0, f"grid {key}", f"needs a list of values, got {grid[key]!r}")],
                graph.source,
            )
    values = [list(grid[key]) for key in keys]
    problems = [
        Problem(0, f"grid {key}", "has no values")
        for key, options in zip(keys, values, strict=True)
        if not options
    ]
    for key in keys:
        target, _, param = key.partition(".")
        if not param:
            problems.append(Problem(0, f"grid {key}", "must be node.param or params.name"))
        elif target != "params" and target not in graph.nodes:
            hint = did_you_mean(target, graph.nodes)
            problems.append(Problem(0, f"grid {key}", f"no node '{target}'{hint}"))
    if not keys:
        problems.append(Problem(0, "grid", "the grid is empty: give at least one node.param"))
    problems += _shadowed(graph, keys)
    total = math.prod(len(options) for options in values)
    if total > MAX_COMBINATIONS:
        sizes = " × ".join(str(len(options)) for options in values)
        problems.append(
            Problem(
                0,
                "grid",
                f"{total:,} combinations ({sizes}); at most {MAX_COMBINATIONS:,}: "
                "sweep fewer values, or one parameter after another",
            )
        )
    if problems:  # (values given twice are named with the values' own problems, later)
        raise PipelineError([*repeated_values(keys, values), *problems], graph.source)
    return values


def repeated_values(keys: list[str], values: list[list[Any]]) -> list[Problem]:
    """A problem for each value a key gives twice."""
    return [
        Problem(0, f"grid {key}", f"gives {twice}: its combinations would run twice")
        for key, options in zip(keys, values, strict=True)
        for twice in _repeated(options)
    ]


def checked_combinations(
    graph: Graph,
    registry: Registry,
    keys: list[str],
    values: list[list[Any]],
    inputs: dict[str, Any] | None,
    outputs: Sequence[str] | None,
) -> tuple[CompiledGraph, list[str]]:
    """The first combination compiled, each other value checked once, and the outputs
    to produce; PipelineError naming every value given twice or refused, unknown output
    and input."""
    first = {key: options[0] for key, options in zip(keys, values, strict=True)}
    refused: dict[tuple[str, str], Problem] = {}  # a bad first value fails every check

    def compiled(combo: dict[str, Any]) -> CompiledGraph | None:
        try:
            return compile_graph(graph.with_overrides(combo), registry, provided=set(inputs or {}))
        except PipelineError as error:
            for p in error.problems:  # (named once, with the first combination that shows it)
                refused.setdefault((_grid_named(p.where, combo), p.message), _in(combo, p))
            return None

    base = compiled(first)
    for key, options in zip(keys, values, strict=True):  # each value checked once
        for value in options[1:]:
            compiled({**first, key: value})
    twice = repeated_values(keys, values)
    if base is None or refused or twice:
        raise PipelineError([*twice, *refused.values()], graph.source)
    wanted = list(outputs) if outputs is not None else list(base.outputs)
    listing, names = ", ".join(base.outputs), ", ".join(base.input_types) or "none"
    unknown = [
        *(Problem(0, "outputs", f"no output '{name}'; outputs: {listing}") for name in wanted
          if name not in base.outputs),
        *(Problem(0, "inputs", f"no input '{name}'; inputs: {names}") for name in inputs or {}
          if name not in base.input_types),
    ]  # fmt: skip
    if unknown:
        raise PipelineError(unknown, graph.source)
    return base, wanted


def _shadowed(graph: Graph, keys: list[str]) -> list[Problem]:
    """A swept ``params.name`` whose every use is itself swept would change nothing."""
    problems = []
    for key in keys:
        target, _, name = key.partition(".")
        if target != "params":
            continue
        reference = f"${{params.{name}}}"
        uses = [
            f"{node}.{param}"
            for node, decl in graph.nodes.items()
            for param, value in decl.params.items()
            if isinstance(value, str) and reference in value
        ]
        if uses and all(use in keys for use in uses):
            problems.append(
                Problem(
                    0,
                    f"grid {key}",
                    f"has no effect: every parameter that uses it ({', '.join(uses)}) is "
                    "swept itself",
                )
            )
    return problems


def _grid_named(where: str, combo: dict[str, Any]) -> str:
    """A problem's place as the user gave it: ``--grid key=value`` for a swept value."""
    for key, value in combo.items():
        where = where.replace(f"--set {key}={value!r}", f"--grid {key}={value!r}")
    return where


def compile_combination(
    graph: Graph, registry: Registry, combo: dict[str, Any], inputs: dict[str, Any] | None
) -> CompiledGraph:
    """The graph with ``combo`` applied, validated; errors name the combination."""
    try:
        overridden = graph.with_overrides(combo)
        return compile_graph(overridden, registry, provided=set(inputs or {}))
    except PipelineError as error:
        raise PipelineError([_in(combo, p) for p in error.problems], error.source) from None


def _in(combo: dict[str, Any], problem: Problem) -> Problem:
    """``problem`` of the graph with ``combo`` applied, named as the user gave the values."""
    shown = ", ".join(f"{k}={v!r}" for k, v in combo.items())
    where = _grid_named(problem.where, combo)
    return Problem(
        problem.line, where, f"{problem.message} (grid combination {shown})", problem.file
    )


def _repeated(options: list[Any]) -> list[str]:
    """Each value given again, in words, once: equal values are one (3 and 3.0, 1 and
    true: a parameter reads them alike)."""
    firsts: list[Any] = []
    said: list[str] = []
    for value in options:
        earlier = [first for first in firsts if first == value]
        if not earlier:
            firsts.append(value)
            continue
        twice = f"{value!r} twice" if repr(value) == repr(earlier[0]) else (
            f"{earlier[0]!r} and {value!r}, one value")  # fmt: skip
        if twice not in said:
            said.append(twice)
    return said
