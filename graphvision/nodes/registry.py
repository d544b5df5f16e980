"""The registry: nodes, port types and input sources, by name.

A plugin is a Python module (or package) whose namespace holds functions
marked with :func:`~graphvision.node` or :func:`~graphvision.source` and,
optionally, new :class:`~graphvision.PortType` subclasses. Registering a
plugin is all or nothing: every node is checked first, then all are added.

Two plugins that define the same node id are an error naming both, unless one
of the nodes declares ``overrides=True``; the overriding node then wins
whatever the loading order.
"""

from __future__ import annotations

import inspect
import types
from dataclasses import dataclass, field
from typing import Any

from graphvision.errors import DuplicateNodeError, RegistrationError, UnknownNameError, did_you_mean
from graphvision.nodes.backends import (
    REFERENCE,
    Exclusive,
    Implementation,
    exclusive_entries,
    implementation_of,
    implementation_problem,
    implementation_spec,
    installed,
    listed_problem,
)
from graphvision.nodes.signature import build_spec
from graphvision.nodes.spec import NodeSpec, SourceSpec
from graphvision.values.builtin import builtin_port_types
from graphvision.values.ports import PortType

__all__ = ["PluginStatus", "Registry", "did_you_mean"]


@dataclass
class PluginStatus:
    """What loading one plugin gave: its nodes, or the error that stopped it."""

    name: str
    origin: str
    nodes: list[str] = field(default_factory=list)
    error: str = ""
    port_types: list[str] = field(default_factory=list)
    sources: list[str] = field(default_factory=list)
    implementations: list[str] = field(default_factory=list)
    """``op@backend`` of each implementation the plugin adds to an op."""


class Registry:
    """Nodes by id, port types by name, input sources by scheme, and plugin statuses."""

    def __init__(self) -> None:
        self.nodes: dict[str, NodeSpec] = {}
        self.port_types: dict[str, type[PortType]] = {
            t.type_name(): t for t in builtin_port_types()
        }
        self.sources: dict[str, SourceSpec] = {}
        self.plugins: dict[str, PluginStatus] = {}
        self._implementation_specs: dict[tuple[str, str], NodeSpec] = {}
        self.implementations: dict[str, dict[str, Implementation]] = {}
        """Op id -> backend -> implementation (the reference, ``numpy``, is the op's node)."""
        self.indexed: dict[str, dict[str, Any]] = {}
        """The plugin index's entries of the installed plugins when discovery read one
        (it may import only some of them): what the others provide, known unimported."""
        self.renamed: dict[str, str] = {}
        """Old op id -> new one, from the plugins' ``RENAMED_OPS`` (a pipeline using an old
        id is told the new one)."""
        self.unread_plugins: list[str] = []
        """A pipeline's own ``plugins:`` that were not imported (it was only checked or
        drawn): an op of a family no loaded plugin provides may be theirs."""

    # -- registration -------------------------------------------------------------

    def add_plugin(
        self,
        module: types.ModuleType,
        name: str,
        origin: str = "",
        *,
        params_checked: bool = False,
    ) -> PluginStatus:
        """Register every node, source and port type that ``module`` exposes.

        ``params_checked`` (the plugin index knows these files registered
        before) leaves each node's parameter model to be built on first use.

        Raises
        ------
        RegistrationError
            If any node is malformed or clashes with a registered one; then
            nothing of the plugin is registered.
        """
        members = [getattr(module, n) for n in getattr(module, "__all__", dir(module))]
        specs, rejected = [], []
        for member in members:
            if hasattr(member, "__graphvision_node__"):
                try:
                    specs.append(build_spec(member, name, params_checked=params_checked))
                except RegistrationError as error:
                    rejected.append(str(error))
        if len(rejected) == 1:
            raise RegistrationError(rejected[0])
        if rejected:  # every bad node at once, not one per attempt
            listing = "\n".join(f"  - {reason}" for reason in rejected)
            raise RegistrationError(
                f"{len(rejected)} nodes of plugin '{name}' are rejected:\n{listing}"
            )
        sources = [
            SourceSpec(m.__graphvision_source__.scheme, m, name, m.__graphvision_source__.key)
            for m in members
            if hasattr(m, "__graphvision_source__")
        ]
        port_types = [
            m
            for m in members
            if inspect.isclass(m)
            and issubclass(m, PortType)
            and not m.__module__.startswith("graphvision.")  # the engine's own are built in
            and not m.__name__.startswith("_")
        ]
        for spec in specs:  # a type its nodes use is registered even if only its alias is exported
            port_types += [port.type for port in spec.inputs.values()]
            port_types += [c for port in spec.inputs.values() for c in port.choices]
            port_types += list(spec.outputs.values())
        kept = self._check_new_nodes(specs)
        impls = self._check_implementations(members, name, kept)
        for spec in kept:
            self.nodes[spec.id] = spec
        self._add_implementations(impls)
        self.renamed.update(getattr(module, "RENAMED_OPS", {}))
        for source_spec in sources:
            self.sources[source_spec.scheme] = source_spec
        for port_type in port_types:
            self.port_types.setdefault(port_type.type_name(), port_type)
        status = PluginStatus(
            name,
            origin or module.__name__,
            [s.id for s in kept],
            port_types=sorted({t.type_name() for t in port_types}),
            sources=[s.scheme for s in sources],
            implementations=[f"{i.op}@{i.backend}" for i in impls],
        )
        self.plugins[name] = status
        return status

    def _check_new_nodes(self, specs: list[NodeSpec]) -> list[NodeSpec]:
        kept: list[NodeSpec] = []
        seen: dict[str, NodeSpec] = {}
        for spec in specs:
            if spec.id in seen:
                raise DuplicateNodeError(
                    f"node id '{spec.id}' is defined twice in plugin '{spec.plugin}': "
                    f"{seen[spec.id].ref.qualname} and {spec.ref.qualname}"
                )
            seen[spec.id] = spec
            old = self.nodes.get(spec.id)
            if old is None or (spec.overrides and not old.overrides):
                kept.append(spec)
            elif old.overrides and not spec.overrides:
                continue  # the overriding node loaded first and stays
            else:
                raise DuplicateNodeError(
                    f"node id '{spec.id}' is defined by plugin '{old.plugin}' "
                    f"({old.ref.module}.{old.ref.qualname}) and by plugin '{spec.plugin}' "
                    f"({spec.ref.module}.{spec.ref.qualname}); rename one, or mark the "
                    "replacement with @node(..., overrides=True)"
                )
        return kept

    def _check_implementations(
        self, members: list, plugin: str, kept: list[NodeSpec]
    ) -> list[Implementation]:
        """The plugin's implementations, each checked against its op when the op is known
        (here or registered before); one of an op registered later is checked on use."""
        impls = [
            implementation_of(m, plugin)
            for m in members
            if hasattr(m, "__graphvision_implementation__")
        ]
        ops = {**self.nodes, **{spec.id: spec for spec in kept}}
        problems = [implementation_problem(ops[i.op], i) for i in impls if i.op in ops]
        problems = [p for p in problems if p]
        if problems:
            raise RegistrationError("\n".join(problems))
        return impls

    def _add_implementations(self, impls: list[Implementation]) -> None:
        for impl in impls:
            self.implementations.setdefault(impl.op, {})[impl.backend] = impl
            self._implementation_specs.pop((impl.op, impl.backend), None)

    def backends_of(self, op: str) -> dict[str, bool]:
        """The backends implementing ``op`` (the reference first), each with whether the
        modules it requires are installed and the releases it requires met."""
        found = {REFERENCE: True}
        for backend, impl in sorted(self.implementations.get(op, {}).items()):
            found[backend] = installed(impl)
        return found

    def exclusive_of(self, op: str) -> dict[str, tuple[Exclusive, str]]:
        """Backend -> (the ``exclusive`` values of its implementation of ``op``, its install
        hint): the loaded implementations', and those the plugin index records for plugins
        this registry did not import (a run imports only the backends it names)."""
        found = {
            backend: (impl.mark.exclusive, impl.install_hint)
            for backend, impl in self.implementations.get(op, {}).items()
            if impl.mark.exclusive
        }
        for name, entry in exclusive_entries(self.indexed).items():
            indexed_op, _, backend = name.partition("@")
            if indexed_op == op:
                found.setdefault(backend, entry)
        return found

    def describe(self, op: str) -> dict:
        """The op's description (:meth:`NodeSpec.describe`) with its ``backends``
        (name -> installed), as ``graphvision describe`` and ``nodes --json`` show it, and
        when some cannot run here, ``unavailable`` (name -> why: a module not found, an
        installed release out of range; read without importing anything)."""
        described = {**self.node(op).describe(), "backends": self.backends_of(op)}
        why = {
            backend: listed_problem(impl)
            for backend, impl in sorted(self.implementations.get(op, {}).items())
            if listed_problem(impl)
        }
        return {**described, "unavailable": why} if why else described

    def backends(self) -> set[str]:
        """Every backend some op has an implementation of (the reference included)."""
        return {REFERENCE} | {b for impls in self.implementations.values() for b in impls}

    def implementation(self, op: str, backend: str) -> NodeSpec | None:
        """The spec of ``op`` run by ``backend`` (None when it has none or the op is
        unknown); a RegistrationError when the implementation does not fit the op."""
        spec = self.nodes.get(op)
        if spec is None or backend == REFERENCE:
            return spec
        impl = self.implementations.get(op, {}).get(backend)
        if impl is None:
            return None
        key = (op, backend)
        if key not in self._implementation_specs:
            problem = implementation_problem(spec, impl)
            if problem:
                raise RegistrationError(problem)
            self._implementation_specs[key] = implementation_spec(spec, impl)
        return self._implementation_specs[key]

    def record_failure(self, name: str, origin: str, error: str) -> None:
        self.plugins[name] = PluginStatus(name, origin, error=error)

    # -- look-up ------------------------------------------------------------------

    def node(self, op: str) -> NodeSpec:
        try:
            return self.nodes[op]
        except KeyError:
            raise UnknownNameError(self.unknown_op(op)) from None

    def unknown_op(self, op: str) -> str:
        """Why ``op`` is not here: renamed (naming the new id), a family no loaded plugin
        provides (naming the plugins that failed to load, else saying how to load one), or
        a misspelling (with the closest op)."""
        if op in self.renamed:
            return f"op '{op}' was renamed '{self.renamed[op]}': use the new name"
        family = op.split(".", 1)[0]
        families = {name.split(".", 1)[0] for name in self.nodes}
        failed = [f"{plugin.name} ({plugin.error})" for plugin in self.failed_plugins()]
        if "." in op and family not in families and failed:  # why, as Python prints no warning
            return (
                f"unknown op '{op}': no loaded plugin provides the family '{family}', and "
                f"plugin {'; '.join(failed)} failed to load"
            )
        if "." in op and family not in families and self.unread_plugins:
            return (
                f"unknown op '{op}': no loaded plugin provides the family '{family}'; the "
                f"pipeline's plugins ({', '.join(self.unread_plugins)}) are not imported to "
                "check it: pass --plugins PATH to load them and check their ops"
            )
        if "." in op and family not in families:
            return (
                f"unknown op '{op}': no loaded plugin provides the family '{family}'"
                f"{did_you_mean(family, families)}; a plugin of your own is loaded with "
                "--plugins PATH on the command line, `plugins: [PATH]` in the pipeline file, "
                "or gv.discover([PATH]) in Python"
            )
        return f"unknown op '{op}'{did_you_mean(op, self.nodes)}"

    def port_type(self, name: str) -> type[PortType]:
        try:
            return self.port_types[name]
        except KeyError:
            raise UnknownNameError(
                f"unknown port type '{name}'{did_you_mean(name, self.port_types)}"
            ) from None

    def source(self, scheme: str) -> SourceSpec:
        try:
            return self.sources[scheme]
        except KeyError:
            known = ", ".join(sorted(self.sources)) or "none"
            raise UnknownNameError(
                f"no plugin loads '{scheme}:' values (known: {known})"
                f"{did_you_mean(scheme, self.sources)}"
            ) from None

    def failed_plugins(self) -> list[PluginStatus]:
        return [p for p in self.plugins.values() if p.error]

    def families(self) -> dict[str, list[NodeSpec]]:
        grouped: dict[str, list[NodeSpec]] = {}
        for op in sorted(self.nodes):
            grouped.setdefault(self.nodes[op].family, []).append(self.nodes[op])
        return grouped
