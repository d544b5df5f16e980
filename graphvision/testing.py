"""Checks for plugin authors: the same ones the built-in plugins pass.

In a plugin's test suite::

    from graphvision.testing import check_plugin

    def test_my_plugin_conforms():
        check_plugin("my_package.nodes")

:func:`check_plugin` imports the module, registers it in a fresh registry
(so every signature is checked), and checks each node: its description is
JSON, its documentation has a summary line, its default parameters are
valid, and its port types are registered. It raises one
:class:`PluginCheckError` listing every problem.
"""

from __future__ import annotations

import importlib
import json
import types

from ._errors import GraphvisionError
from ._registry import Registry

__all__ = ["PluginCheckError", "check_plugin"]


class PluginCheckError(GraphvisionError):
    """A plugin does not meet the conventions; ``problems`` lists them all."""

    def __init__(self, plugin: str, problems: list[str]) -> None:
        self.problems = problems
        super().__init__(f"plugin '{plugin}':\n" + "\n".join(f"  - {p}" for p in problems))


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
    if not status.nodes:
        problems.append("defines no node")
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
                    f"{op}: port '{port}' has type {kind.type_name()}, which no "
                    "plugin registers (export the PortType from the plugin module)"
                )
    if problems:
        raise PluginCheckError(module.__name__, problems)
    return registry
