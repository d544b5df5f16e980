"""Exceptions raised by graphvision.

Every error a user can cause derives from :class:`GraphvisionError`; the CLI
prints those without a traceback (exit 2 for a bad pipeline or usage, 1 for a
failed run). Anything else is a bug and keeps its traceback.

::

    GraphvisionError
    ├── RegistrationError        a node, port type or source rejected at registration
    │   └── DuplicateNodeError   two plugins define one node id
    ├── PluginLoadError          a plugin failed to import (the others keep working)
    ├── UnknownNameError         an op, port type or source that is not registered
    ├── PortValueError           a value does not satisfy its port type
    ├── PipelineError            a pipeline is invalid; carries every Problem at once
    ├── InputError               a graph input cannot be resolved (file missing, ...)
    ├── OutputFolderError        an output folder holds files graphvision did not write
    ├── NodeExecutionError       a node raised; names node, op, params and inputs
    └── RunError                 a run finished with failed nodes
"""

from __future__ import annotations

import difflib
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from typing import TypeVar

__all__ = [
    "CopiedError",
    "DuplicateNodeError",
    "FileWriteError",
    "GraphvisionError",
    "InputError",
    "NodeExecutionError",
    "OutputFolderError",
    "ParameterError",
    "PipelineError",
    "PluginLoadError",
    "PortValueError",
    "Problem",
    "RegistrationError",
    "RunError",
    "UnknownNameError",
    "chained",
    "did_you_mean",
    "error_text",
]


class GraphvisionError(Exception):
    """Base class of every error a user of graphvision can cause."""


class RegistrationError(GraphvisionError):
    """A node, port type or input source was rejected when it registered."""


class DuplicateNodeError(RegistrationError):
    """Two plugins define the same node id and neither declares an override."""


class PluginLoadError(GraphvisionError):
    """A plugin could not be imported."""


class UnknownNameError(GraphvisionError, KeyError):
    """A name (op, port type, source scheme) that is not registered."""

    def __str__(self) -> str:  # KeyError would quote the message
        return str(self.args[0]) if self.args else ""


class PortValueError(GraphvisionError, ValueError):
    """A value does not satisfy the port type it is given to."""


class ParameterError(GraphvisionError, ValueError):
    """A node parameter is unknown or fails its constraint."""


class InputError(GraphvisionError):
    """A graph input could not be resolved to a value."""


class OutputFolderError(GraphvisionError):
    """An output folder cannot take a run's files without losing files graphvision did not write."""


class FileWriteError(OSError):
    """A file could not be written (a full disk, a size limit, a folder in its place): a
    failure of the environment, not of the pipeline (exit 1), named by the file meant, not
    the temporary one beside it. An ``OSError``: ``errno``, ``strerror`` and ``filename``
    are set."""

    def __str__(self) -> str:
        return f"cannot write {self.filename}: {self.strerror}"


class CopiedError(Exception):
    """What a node raised, as its type's name and its message, as the run reports them
    (:func:`error_text`): an exception raised in a worker process that could not travel
    back as itself (it does not pickle, or does not unpickle in the client: a lock or a
    lambda in its arguments, an ``__init__`` that takes other arguments than it gives its
    base, a class only the workers import), or one that is not an ``Exception``
    (``SystemExit``, a ``BaseException`` of the node's own), the node's failure all the
    same (:mod:`graphvision.execution.node_raised`)."""

    def __init__(self, type_name: str, message: str) -> None:
        super().__init__(type_name, message)
        self.type_name, self.message = type_name, message

    def __str__(self) -> str:
        return self.message


def error_text(error: BaseException) -> str:
    """``Type: message`` of an exception as a run reports it (``Type`` alone for an empty
    message): a copy by its original's type (:class:`CopiedError`); one whose message cannot
    be made (its ``__str__`` raised) says so, where the run ended with an internal error."""
    name = error.type_name if isinstance(error, CopiedError) else type(error).__name__
    try:
        message = str(error)
    except Exception as broken:  # (a user's exception class: anything can happen)
        message = f"(its message could not be made: {type(broken).__name__})"
    return f"{name}: {message}" if message else name  # (as Python's traceback: no colon)


_Found = TypeVar("_Found", bound=BaseException)


def chained(
    error: BaseException, kind: type[_Found], test: Callable[[_Found], bool] = bool
) -> _Found | None:
    """The first exception of ``kind`` that passes ``test`` among ``error`` and the chain of
    exceptions it came from (each one's ``__cause__``, else its ``__context__``), or None:
    a Ctrl-C that code it interrupted wrapped in an error of its own."""
    seen: set[int] = set()
    found: BaseException | None = error
    while found is not None and id(found) not in seen:
        if isinstance(found, kind) and test(found):
            return found
        seen.add(id(found))
        found = found.__cause__ or found.__context__
    return None


@dataclass(frozen=True, order=True)
class Problem:
    """One problem found in a pipeline, located in its file when known.

    Attributes
    ----------
    line : int
        1-based line in ``file`` (0 when unknown).
    where : str
        Dotted location in the pipeline, e.g. ``nodes.blur.params.sigma``.
    message : str
        What is wrong, in words a user can act on.
    file : str
        The pipeline file ('' for graphs built in Python), or the Python file that
        added the part at fault (``graph.add``) when ``added`` says so.
    added : str
        How the part at fault came into the graph when not from ``file``'s YAML
        (``"added in Python"``), else ''.
    """

    line: int
    where: str
    message: str
    file: str = ""
    added: str = ""

    @property
    def place(self) -> str:
        """Where the problem is: ``nodes.blur.params.sigma at p.yaml:14``."""
        place = self.where
        if self.file:
            place += f" at {self.file}:{self.line}" if self.line else f" in {self.file}"
        if self.added:
            place += f" ({self.added})"
        return place

    def __str__(self) -> str:
        return f"{self.place}: {self.message}"


class PipelineError(GraphvisionError):
    """A pipeline is invalid. ``problems`` lists every problem, sorted by line."""

    def __init__(self, problems: list[Problem], source: str = "", message: str = "") -> None:
        self.problems = sorted(problems)
        self.source = source
        if not message:  # the headline, then one line per problem
            head = f"invalid pipeline {source}" if source else "invalid pipeline"
            count = len(self.problems)
            lines = [f"{head}: {count} problem{'s' if count != 1 else ''}"]
            message = "\n".join(lines + [f"  - {p}" for p in self.problems])
        super().__init__(message)


class NodeExecutionError(GraphvisionError):
    """A node raised. The original exception is chained as ``__cause__``."""

    def __init__(self, node: str, op: str, params: dict, inputs: dict[str, str], error: str):
        self.node, self.op, self.params, self.inputs = node, op, params, inputs
        summary = ", ".join(f"{k}={v}" for k, v in inputs.items()) or "none"
        super().__init__(
            f"node '{node}' (op {op}) failed: {error}\n    params: {params}\n    inputs: {summary}"
        )


class RunError(GraphvisionError):
    """A run ended with failed nodes; ``failures`` maps node name to its error."""

    def __init__(self, failures: dict[str, GraphvisionError], record: object = None) -> None:
        self.failures = failures
        self.record = record
        super().__init__("\n".join(str(e) for e in failures.values()))


def did_you_mean(name: str, options: Iterable[str]) -> str:
    """`` (did you mean 'x'?)`` for the closest option, or ''."""
    close = difflib.get_close_matches(name, list(options), n=1, cutoff=0.6)
    return f" (did you mean '{close[0]}'?)" if close else ""
