"""Graph inputs as values: literals, paths, ``sample:NAME`` and the files an earlier run
wrote, validated by their port type and frozen."""

from __future__ import annotations

import difflib
from pathlib import Path
from typing import Any

import yaml

from graphvision.errors import (
    InputError,
    PortValueError,
    Problem,
    did_you_mean,
)
from graphvision.graph.model import Graph
from graphvision.nodes.registry import Registry
from graphvision.values.ports import PortType, freeze_all
from graphvision.values.scalars import TextPort, _ScalarPort

__all__ = ["default_problems", "freeze_value", "resolve_input", "value_bytes"]


class _RefusedError(Exception):
    """Why a value is not a valid input (the message, without the input's name)."""


def resolve_input(
    name: str,
    port_type: type[PortType],
    value: Any,
    registry: Registry,
    *,
    graph: Graph | None = None,
) -> Any:
    """Turn a given value into a validated port value.

    A string for a non-``Text`` port is a reference: ``scheme:rest`` goes to the
    plugin source of that scheme (e.g. ``sample:camera``), a scalar port parses
    it as YAML (``--input sigma=2``), a ``.npz`` path is read by the port type
    as it writes its values (with the ``.json`` beside it, if any: a trained
    network, keypoints or boxes from an earlier run's output folder), anything
    else is a path for the ``file`` source. The loaded value, or an array the
    caller passed, then goes through the port's dtype policy
    (:meth:`PortType.coerce`), so a ``uint8`` array from OpenCV is the same
    image as the PNG it was read from.

    Parameters
    ----------
    graph : Graph, optional
        The pipeline whose default ``value`` is (None: a value the caller gave). An
        error then names the default's place: ``inputs.image.default at p.yaml:4``,
        or the Python line that declared the input.

    Raises
    ------
    InputError
        Naming the input, the value and what is wrong.
    """
    try:
        return _resolved(port_type, value, registry)
    except _RefusedError as refused:
        where = f"input '{name}'"
        if graph is not None:
            where = graph.problem(f"inputs.{name}.default", "").place
        raise InputError(f"{where}: {refused}") from refused.__cause__


def default_problems(
    graph: Graph,
    types: dict[str, type[PortType]],
    registry: Registry,
    given: dict[str, str] | None = None,
) -> list[Problem]:
    """A problem for each default of ``graph`` that does not load as its input's port type
    (``types``), placed at its line: what ``validate`` reports of a default a run would
    refuse (a sample's name mistyped, a missing file). A value ``given`` for an input
    (``validate -i NAME=VALUE``) is loaded in place of its default, and a problem of it
    or of a name ``graph`` does not declare is placed at ``--input NAME=VALUE``."""
    given = given or {}
    problems = [
        Problem(0, f"--input {name}={value}", f"unknown input{did_you_mean(name, types)}; "
                f"inputs: {', '.join(types) or 'none'}")
        for name, value in given.items() if name not in types
    ]  # fmt: skip
    for name, port_type in types.items():
        value = given.get(name, graph.inputs[name].default)
        if value is None:
            continue
        try:
            _resolved(port_type, value, registry)
        except _RefusedError as refused:
            place = f"inputs.{name}.default"
            problems.append(
                Problem(0, f"--input {name}={value}", str(refused))
                if name in given
                else graph.problem(place, str(refused))
            )
    return problems


def _resolved(port_type: type[PortType], value: Any, registry: Registry) -> Any:
    """:func:`resolve_input`, its errors (``_RefusedError``) saying what is wrong, not where."""
    origin = f"'{value}'" if isinstance(value, str) else f"the {type(value).__name__} given"
    empty = isinstance(value, str) and not value  # Path('') would be this folder
    if empty and not issubclass(port_type, (TextPort, _ScalarPort)):
        raise _RefusedError("is empty: give a file, or a source such as sample:NAME")
    if isinstance(value, str) and not issubclass(port_type, TextPort):
        scheme, sep, rest = value.partition(":")
        try:
            if sep and scheme in registry.sources:
                value = registry.sources[scheme].func(rest)
            elif issubclass(port_type, _ScalarPort):
                value = yaml.safe_load(value)
            elif value.lower().endswith(".npz"):
                value = _read_written(port_type, Path(value))
            else:
                value = registry.source("file").func(value)
        except Exception as error:
            told = str(error)
            told = told if str(value) in told else f"cannot load '{value}': {told}"
            if isinstance(error, FileNotFoundError):  # `samples:camera`: a scheme mistyped?
                told += scheme_hint(value, registry)
            raise _RefusedError(told) from error
    try:
        return freeze_value(port_type, port_type.admit(value, origin))
    except PortValueError as error:
        raise _RefusedError(str(error)) from None
    except (Exception, RecursionError) as error:  # a port type's check undone by hostile data
        raise _RefusedError(
            f"not a valid {port_type.type_name()} ({type(error).__name__}: {str(error)[:200]})"
        ) from None


def scheme_hint(value: str, registry: Registry) -> str:
    """`` (did you mean 'sample:camera'?)`` for a ``value`` such as ``samples:camera`` (or
    ``SAMPLE:camera``), found as no file, whose part before its colon is close to a
    source's scheme; or ''."""
    scheme, sep, rest = value.partition(":")
    if not sep or scheme in registry.sources:
        return ""
    lowered = {name.lower(): name for name in registry.sources}
    close = difflib.get_close_matches(scheme.lower(), list(lowered), n=1, cutoff=0.6)
    return f" (did you mean '{lowered[close[0]]}:{rest}'?)" if close else ""


def _read_written(port_type: type[PortType], archive: Path) -> Any:
    """The value in an ``.npz`` ``port_type`` wrote (with the ``.json`` of its header
    beside it, if any), or an error naming the file and what it lacks."""
    if not archive.is_file():
        raise FileNotFoundError(f"no such file: {archive}")
    header = archive.with_suffix(".json")
    try:
        return port_type.read([archive, header] if header.is_file() else [archive])
    except (KeyError, TypeError, ValueError, OSError) as error:
        raise ValueError(
            f"{archive} is not a {port_type.type_name()} as graphvision writes it "
            f"({type(error).__name__}: {error})"
        ) from None


def value_bytes(port_type: type[PortType], value: Any) -> int:
    """Bytes of a value's arrays (what a run record counts per node; a scalar has none)."""
    if issubclass(port_type, _ScalarPort):
        return 0
    return sum(a.nbytes for a in port_type.encode(value)[0].values())


def freeze_value(port_type: type[PortType], value: Any) -> Any:
    """The value over immutable copies of its arrays (see :func:`~graphvision.values.ports.freeze`).

    A node's inputs then cannot be changed by the node, whatever flags it
    sets: a mutating node fails, naming itself, and nothing else changes.
    The caller's own arrays (graph inputs given in Python) stay as they were.
    """
    if issubclass(port_type, _ScalarPort):
        return value
    arrays, meta = port_type.encode(value)
    return port_type.decode(freeze_all(arrays), meta)
