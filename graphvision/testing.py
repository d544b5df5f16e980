"""Checks for plugin authors: the same ones the built-in plugins pass.

In a plugin's test suite::

    from graphvision.testing import check_plugin

    def test_my_plugin_conforms():
        check_plugin("my_package.nodes")

:func:`check_plugin` imports the module, registers it in a fresh registry
(so every signature is checked), and checks each node: its description is
JSON, its documentation has a summary line, its default parameters are
valid, its docstring's NumPy-style ``Parameters`` section names every input
port and parameter, its annotations are the type-checkable aliases of
:mod:`graphvision.types` (not bare port classes), and no two of its port
types share a name. It raises one :class:`PluginCheckError` listing every
problem.
"""

from __future__ import annotations

import importlib
import inspect
import json
import re
import textwrap
import types
import typing
from typing import Any

from graphvision.errors import GraphvisionError
from graphvision.nodes.registry import Registry
from graphvision.values.ports import PortType

__all__ = ["PluginCheckError", "check_conformance", "check_plugin", "documented_parameters"]


class PluginCheckError(GraphvisionError):
    """A plugin does not meet the conventions; ``problems`` lists them all."""

    def __init__(self, plugin: str, problems: list[str]) -> None:
        self.problems = problems
        super().__init__(f"plugin '{plugin}':\n" + "\n".join(f"  - {p}" for p in problems))


def check_conformance(
    op: str,
    backend: str,
    inputs: dict[str, Any],
    params: dict[str, Any] | None = None,
    *,
    registry: Registry | None = None,
) -> None:
    """Run ``op``'s reference and its ``backend`` implementation on ``inputs`` (by port
    name) and ``params``, and compare them by the tolerance the op declares.

    ``registry`` defaults to the installed plugins. A backend implementation comes with
    a test of this kind on inputs that exercise it (every parameter value it treats
    differently), the same inputs for both implementations.

    Raises
    ------
    PluginCheckError
        Listing every output that differs beyond the op's tolerance.
    """
    from graphvision.nodes.conformance import conformance_problems
    from graphvision.nodes.plugins import discover

    registry = registry or discover()
    problems = conformance_problems(registry, op, backend, inputs, dict(params or {}))
    if problems:
        raise PluginCheckError(f"{op}@{backend}", problems)


def check_plugin(module: str | types.ModuleType) -> Registry:
    """Register ``module`` and check every node it defines; return the registry.

    Raises
    ------
    RegistrationError
        For a node whose signature is not a node's.
    PluginCheckError
        Listing every convention a node breaks.
    """
    if isinstance(module, str):
        module = importlib.import_module(module)
    registry = Registry()
    status = registry.add_plugin(module, module.__name__)
    problems = []
    if not status.nodes and not status.implementations:
        problems.append("defines no node and no implementation of another plugin's op")
    for op in status.nodes:
        spec = registry.nodes[op]
        try:
            json.dumps(spec.describe())
        except (TypeError, ValueError) as error:
            problems.append(f"{op}: description is not JSON ({error})")
        if not spec.summary:
            problems.append(f"{op}: the docstring needs a summary line")
        try:
            spec.validate_params({})
        except Exception as error:
            problems.append(f"{op}: default parameters are invalid ({error})")
        for port, kind in [*((p, i.type) for p, i in spec.inputs.items()), *spec.outputs.items()]:
            if registry.port_types.get(kind.type_name()) is not kind:
                problems.append(
                    f"{op}: port '{port}' has type {kind.type_name()}, but another port "
                    "type of that name is registered (give the class another name)"
                )
        undocumented = [
            name
            for name in (*spec.inputs, *spec.params_model.model_fields)
            if name not in documented_parameters(spec.doc)
        ]
        if undocumented:
            problems.append(
                f"{op}: the docstring's Parameters section does not describe "
                + ", ".join(f"'{name}'" for name in undocumented)
            )
        problems += [f"{op}: {problem}" for problem in _bare_port_classes(spec.func)]
    if problems:
        raise PluginCheckError(module.__name__, problems)
    return registry


_SECTION = re.compile(r"^(\w[\w ]*)\n-{3,}\s*$", re.MULTILINE)


def documented_parameters(doc: str) -> set[str]:
    """Names listed in a NumPy-style docstring's ``Parameters`` section.

    An entry is a line at the section's indentation, ``name : description``,
    ``name`` alone, or ``a, b : description`` for several names.
    """
    text = textwrap.dedent("\n".join(doc.splitlines()[1:]))  # the summary is not indented
    headers = list(_SECTION.finditer(text))
    for header, following in zip(headers, [*headers[1:], None], strict=False):
        if header.group(1).strip() != "Parameters":
            continue
        body = text[header.end() : following.start() if following else len(text)]
        names: set[str] = set()
        for line in body.splitlines():
            if line[:1].isspace() or not line.strip():
                continue
            head = line.split(":", 1)[0]
            names.update(name.strip().lstrip("*") for name in head.split(","))
        return names
    return set()


def _bare_port_classes(func: typing.Callable[..., object]) -> list[str]:
    """Annotations that name a port class instead of its type-checkable alias."""
    hints = typing.get_type_hints(func)  # without extras: an alias shows its value type
    found = []
    for name, hint in hints.items():
        for item in (hint, *typing.get_args(hint)):
            if inspect.isclass(item) and issubclass(item, PortType):
                where = "the return value" if name == "return" else f"'{name}'"
                found.append(
                    f"{where} is annotated with the port class {item.__name__}; use an "
                    f"Annotated alias (see graphvision.types) so type checkers see the value type"
                )
    return found
