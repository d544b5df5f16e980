"""Planning a run: the keys of its values, and which nodes are cached and which must
compute (pure functions of the graph, the keys and the cache)."""

from __future__ import annotations

import hashlib
import time
from collections.abc import Callable, Collection, Iterable, Mapping
from dataclasses import dataclass
from typing import Any

from graphvision.cache.keys import output_keys
from graphvision.compiler.compile import CompiledGraph
from graphvision.nodes.registry import Registry
from graphvision.values.ports import PortType
from graphvision.values.scalars import TextPort

__all__ = ["Plan", "chain_keys", "plan_steps", "referenced_inputs"]


@dataclass(frozen=True)
class Plan:
    """What a run must do: the outputs found in the cache (value and seconds to load),
    and the steps to compute, in topological order."""

    loaded: dict[tuple[str, str], tuple[Any, float]]
    compute: list[str]


def plan_steps(
    compiled: CompiledGraph,
    keys: Mapping[tuple[str, str], str],
    wanted: Iterable[tuple[str, str]],
    known: Collection[tuple[str, str]],
    deferred: Collection[str],
    lookup: Callable[[str, type[PortType]], tuple[bool, Any]] | None,
) -> Plan:
    """Decide, from the outputs backwards, what is loaded from the cache and what runs.

    A wanted value that is ``known`` (a graph input, or already produced) or a
    ``deferred`` input (loaded when read) needs nothing; a cached node's
    output found by ``lookup(key, port_type)`` is loaded and its producers are
    not visited, so a fully cached re-run reads only the requested outputs;
    any other step is computed, and so are the producers of its inputs. The
    function reads the cache and changes nothing else.
    """
    compute: set[str] = set()
    loaded: dict[tuple[str, str], tuple[Any, float]] = {}
    stack = list(wanted)
    steps = compiled.steps
    while stack:
        source = stack.pop()
        name, port = source
        if source in known or source in loaded or name in compute or name in deferred:
            continue
        step = steps[name]
        if step.spec.cache and lookup is not None:
            began = time.perf_counter()
            hit, value = lookup(keys[source], step.outputs[port])
            if hit:
                loaded[source] = (value, time.perf_counter() - began)
                continue
        compute.add(name)
        stack.extend(step.inputs.values())
    return Plan(loaded, [name for name in steps if name in compute])


def chain_keys(
    compiled: CompiledGraph, keys: Mapping[tuple[str, str], str], names: list[str]
) -> dict[tuple[str, str], str]:
    """The output keys of the steps ``names``, chained from the graph inputs' ``keys``.

    Keys are a function of these alone, so the last chain made for the same
    steps on inputs of the same keys is taken as it is (a graph run again on
    the same inputs keys 10,000 nodes in a dict copy, not 10,000 hashes).
    """
    given = tuple(sorted((name, key) for (name, port), key in keys.items() if not port))
    memo = compiled.last_keys
    found = memo.get(given)
    if found is not None and found[0] == names:
        return found[1]
    chained, steps = dict(keys), compiled.steps
    for name in names:
        step = steps[name]
        inputs = {port: chained[source] for port, source in step.inputs.items()}
        made = output_keys(step.fingerprint, inputs, step.outputs)
        for port, key in zip(step.outputs, made, strict=True):
            chained[(name, port)] = key
    chained = {source: key for source, key in chained.items() if source[0] in steps}
    memo.clear()  # the last chain only: a graph run on many inputs keeps one
    memo[given] = (list(names), chained)
    return chained


def referenced_inputs(
    compiled: CompiledGraph, given: dict[str, Any], registry: Registry
) -> dict[str, str]:
    """Input name -> key, for inputs given as a reference whose source keys it without loading.

    ``sample:astronaut`` is fixed by its name and scikit-image's version: the
    run keys it by that and loads it only if a node that reads it must run.
    """
    keys = {}
    for name, value in given.items():
        if not isinstance(value, str) or issubclass(compiled.input_types[name], TextPort):
            continue
        scheme, sep, rest = value.partition(":")
        spec = registry.sources.get(scheme) if sep else None
        if spec is None or spec.key is None:
            continue
        try:
            text = spec.key(rest)
        except Exception:  # loading reports the problem, with its message
            continue
        kind = compiled.input_types[name].type_name()
        digest = hashlib.blake2b(f"{kind}|{text}".encode(), digest_size=16).hexdigest()
        keys[name] = "r" + digest
    return keys
