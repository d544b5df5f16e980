"""Checking a graph against a registry, before anything runs.

:func:`compile_graph` resolves every op, port, type and parameter of a
:class:`~graphvision.Graph` and returns a :class:`CompiledGraph` ready to
schedule, or raises one :class:`~graphvision.PipelineError` listing every
problem, each with its YAML file and line:

* unknown op, port, node or output (with a "did you mean"),
* missing required input port, type mismatch naming both ends and both types,
* invalid parameter (type, range, unknown name), unknown ``${params.x}``,
* cycles, printed as ``a -> b -> a``,
* graph inputs that are unused, of unknown type, or missing a value,
* an unknown backend, a node pinned to a backend its op lacks or that is not installed
  (each node's implementation is chosen here: :mod:`.backends`).
"""

from __future__ import annotations

import difflib
from collections.abc import Sequence
from typing import Any

import pydantic

from graphvision.compiler.backends import BackendChooser
from graphvision.compiler.compiled import CompiledGraph, Schedule, Step
from graphvision.errors import PipelineError, Problem, UnknownNameError, did_you_mean
from graphvision.graph.collector import collector_paused
from graphvision.graph.model import NAME, PARAM_REFERENCE, Graph, Ref, output_name_problem
from graphvision.graph.order import CycleError, topological_order
from graphvision.nodes.registry import Registry
from graphvision.nodes.spec import NodeSpec
from graphvision.values.ports import PortType

__all__ = ["CompiledGraph", "Schedule", "Step", "compile_graph"]


class _Checker:
    def __init__(self, graph: Graph, registry: Registry, chooser: BackendChooser) -> None:
        self.graph, self.registry, self.chooser = graph, registry, chooser
        self.problems: list[Problem] = []
        self.resolved: dict[str, dict[str, type[PortType]]] = {}
        self.untyped: set[str] = set()  # generic nodes whose input's type is unknown
        self.unresolved: set[str] = set()  # parameters naming an unknown ${params.NAME}

    def report(self, where: str, message: str) -> None:
        self.problems.append(self.graph.problem(where, message))

    # -- parameters -------------------------------------------------------------

    def substitute(self, value: Any, where: str, used: set[str]) -> Any:
        if isinstance(value, str):
            names = PARAM_REFERENCE.findall(value)
            for name in names:
                used.add(name)
                if name not in self.graph.params:
                    self.report(
                        where,
                        f"unknown pipeline param '${{params.{name}}}'"
                        f"{did_you_mean(name, self.graph.params)}",
                    )
                    # one problem: not the value's type too, nor the param it misspells unused
                    self.unresolved.add(where)
                    used.update(difflib.get_close_matches(name, list(self.graph.params), n=1))
                    return value
            whole = PARAM_REFERENCE.fullmatch(value)
            if whole:
                return self.graph.params[whole.group(1)]
            return PARAM_REFERENCE.sub(lambda m: str(self.graph.params[m.group(1)]), value)
        if isinstance(value, list):
            return [self.substitute(v, f"{where}.{i}", used) for i, v in enumerate(value)]
        if isinstance(value, dict):
            return {k: self.substitute(v, f"{where}.{k}", used) for k, v in value.items()}
        return value

    def overrides_behind(self, name: str, param: str) -> list[str]:
        """The overrides (``--set``) that gave node ``name``'s parameter ``param`` its value:
        the parameter itself (``centre`` for a problem in ``centre.0``), or a pipeline param
        it uses (``params.seed`` behind ``${params.seed}``); every override of the node for
        a problem of its parameters together (``param`` empty)."""
        overrides = self.graph.overrides_applied
        if not param:
            return [key for key in overrides if key.startswith(f"{name}.")]
        top = param.split(".")[0]
        if f"{name}.{top}" in overrides:
            return [f"{name}.{top}"]
        raw = self.graph.nodes[name].params.get(top)
        used = PARAM_REFERENCE.findall(str(raw)) if isinstance(raw, (str, list, dict)) else []
        return [f"params.{p}" for p in used if f"params.{p}" in overrides]

    def check_params(self, name: str, spec: NodeSpec, params: dict[str, Any]) -> dict[str, Any]:
        try:
            return spec.validate_params(params)
        except pydantic.ValidationError as error:
            overrides = self.graph.overrides_applied
            for param, message in spec.param_problems(error):
                spot = f"nodes.{name}.params.{param.split('.')[0]}"
                typo = any(w == spot or w.startswith(f"{spot}.") for w in self.unresolved)
                if param and typo and not message.startswith("unknown parameter"):
                    continue  # its unknown ${params.NAME} is the problem, reported once
                keys = self.overrides_behind(name, param)
                if keys:  # the file is fine: the command line set these values
                    where = ", ".join(f"--set {key}={overrides[key]!r}" for key in keys)
                    self.problems.append(Problem(0, where, message))
                else:
                    self.report(
                        f"nodes.{name}.params.{param}" if param else f"nodes.{name}.params",
                        message,
                    )
            return {}

    # -- connections --------------------------------------------------------------

    def source_type(self, ref: Ref, where: str) -> tuple[tuple[str, str], type[PortType]] | None:
        graph = self.graph
        if ref.node in graph.inputs:
            if ref.port is not None:
                self.report(where, f"graph input '{ref.node}' has no port '{ref.port}'")
                return None
            try:
                return (ref.node, ""), self.registry.port_type(graph.inputs[ref.node].type)
            except UnknownNameError:
                return None  # reported once, on the input
        if ref.node not in graph.nodes:
            options = list(graph.nodes) + list(graph.inputs)
            self.report(
                where, f"unknown node or input '{ref.node}'{did_you_mean(ref.node, options)}"
            )
            return None
        op = graph.nodes[ref.node].op
        if op not in self.registry.nodes or ref.node in self.untyped:
            return None  # reported on that node, or upstream of it
        outputs = self.resolved.get(ref.node) or self.registry.nodes[op].outputs
        port = ref.port
        if port is None:
            if len(outputs) != 1:
                self.report(
                    where,
                    f"node '{ref.node}' ({op}) has outputs "
                    f"{', '.join(outputs)}; name one, e.g. '{ref.node}.{next(iter(outputs))}'",
                )
                return None
            port = next(iter(outputs))
        elif port not in outputs:
            self.report(
                where,
                f"node '{ref.node}' ({op}) has no output '{port}'"
                f"{did_you_mean(port, outputs)}; outputs: {', '.join(outputs)}",
            )
            return None
        return (ref.node, port), outputs[port]

    def check_inputs(self, name: str, spec: NodeSpec) -> dict[str, tuple[str, str]]:
        """Wire the node's inputs, check their types, bind its type variables."""
        decl = self.graph.nodes[name]
        wired: dict[str, tuple[str, str]] = {}
        bindings: dict[str, type[PortType]] = {}
        for port, ref in decl.inputs.items():
            where = f"nodes.{name}.in.{port}"
            if port not in spec.inputs:
                listing = ", ".join(spec.inputs) or "none"
                self.report(
                    where,
                    f"{spec.id} has no input port '{port}'"
                    f"{did_you_mean(port, spec.inputs)}; inputs: {listing}",
                )
                continue
            found = self.source_type(ref, where)
            if found is None:
                if spec.inputs[port].typevar:  # its outputs' types are unknown, not Array
                    self.untyped.add(name)
                continue
            wired[port], given = found
            declared = spec.inputs[port]
            if not declared.accepts(given):
                self.report(
                    where,
                    f"type mismatch: '{ref}' gives {given.type_name()} but "
                    f"'{name}.{port}' ({spec.id}) takes {declared.type_label()}",
                )
            elif declared.typevar:
                chosen = declared.bind(given)
                bound = bindings.get(declared.typevar, chosen)
                if chosen.is_a(bound):
                    chosen = bound
                elif not bound.is_a(chosen):
                    chosen = declared.type
                bindings[declared.typevar] = chosen
        for port, declared in spec.inputs.items():
            if port not in decl.inputs and not declared.optional:
                self.report(
                    f"nodes.{name}.in",
                    f"missing input port '{port}' of {spec.id} ({declared.type_label()})",
                )
        self.resolved[name] = {
            port: bindings.get(spec.output_vars.get(port, ""), kind)
            for port, kind in spec.outputs.items()
        }
        return wired

    # -- whole graph ----------------------------------------------------------------

    def check_cycles(self) -> list[str] | None:
        nodes = self.graph.nodes
        dependencies = {
            name: {r.node for r in decl.inputs.values() if r.node in nodes}
            for name, decl in nodes.items()
        }
        try:
            return topological_order(dependencies)
        except CycleError as error:
            for cycle in error.cycles:
                self.report(f"nodes.{cycle[0]}", f"cycle: {' -> '.join(cycle)}")
            return None

    def run(self, provided: set[str] | None) -> CompiledGraph:
        graph, registry = self.graph, self.registry
        input_types: dict[str, type[PortType]] = {}
        for name, input_decl in graph.inputs.items():
            try:
                input_types[name] = registry.port_type(input_decl.type)
            except UnknownNameError as error:
                self.report(f"inputs.{name}.type", str(error))
            if provided is not None and name not in provided and input_decl.default is None:
                self.report(
                    f"inputs.{name}",
                    f"missing input '{name}': no value given (--input {name}=PATH) and no default",
                )
        clashes = set(graph.inputs) & set(graph.nodes)
        for name in sorted(clashes):
            self.report(f"nodes.{name}", f"'{name}' is both a graph input and a node")

        order = self.check_cycles()
        used_params: set[str] = set()
        steps: dict[str, Step] = {}
        for name in order or list(graph.nodes):
            decl = graph.nodes[name]
            try:
                spec = registry.node(decl.op)
            except UnknownNameError as error:
                self.report(f"nodes.{name}.op", str(error))
                for port, ref in decl.inputs.items():  # still check the references
                    if ref.node not in graph.nodes and ref.node not in graph.inputs:
                        self.source_type(ref, f"nodes.{name}.in.{port}")
                # and the ${params.NAME} it uses (so they are not reported unused)
                self.substitute(decl.params, f"nodes.{name}.params", used_params)
                continue
            params = self.substitute(decl.params, f"nodes.{name}.params", used_params)
            checked = self.check_params(name, spec, params)
            wired = self.check_inputs(name, spec)
            spec, problem = self.chooser.choose(spec, decl.backend, checked)
            if problem:
                self.report(f"nodes.{name}.backend", problem)
            steps[name] = Step(name, spec, checked, wired, self.resolved[name])

        outputs: dict[str, tuple[str, str]] = {}
        if not graph.outputs:
            self.report("outputs", "a pipeline needs at least one output")
        for out_name, ref in graph.outputs.items():
            if not NAME.match(out_name):
                self.report(f"outputs.{out_name}", output_name_problem(out_name))
                continue
            found = self.source_type(ref, f"outputs.{out_name}")
            if found is not None:
                outputs[out_name] = found[0]

        self.check_unused(used_params)
        for where, message in graph.truth_problems():
            self.report(where, message)

        if self.problems:
            raise PipelineError(self.problems, graph.source)
        return CompiledGraph(graph, {n: steps[n] for n in order or []}, input_types, outputs)

    def check_unused(self, used_params: set[str]) -> None:
        """Inputs nothing reads and pipeline params no node refers to."""
        graph = self.graph
        referenced = {ref.node for d in graph.nodes.values() for ref in d.inputs.values()}
        referenced |= {ref.node for ref in graph.outputs.values()}
        for name in graph.inputs:
            if name not in referenced:
                self.report(f"inputs.{name}", f"unused input '{name}': no node or output reads it")
        for name in graph.params:
            if name not in used_params and name not in graph.overridden_params:
                self.report(
                    f"params.{name}",
                    f"unused pipeline param '{name}': no node refers to ${{params." + name + "}",
                )


def compile_graph(
    graph: Graph,
    registry: Registry,
    *,
    provided: set[str] | None = None,
    backends: Sequence[str] | None = None,
) -> CompiledGraph:
    """Validate ``graph`` against ``registry`` and resolve it for running.

    Parameters
    ----------
    graph : Graph
        The pipeline, from YAML or the Python builder.
    registry : Registry
        Where ops and port types are looked up.
    provided : set of str, optional
        Names of graph inputs given values for a run; inputs neither provided
        nor defaulted are then reported. None skips that check (``validate``).
    backends : sequence of str, optional
        The backend lookup order (``["opencv", "numpy"]``); None takes the graph's
        ``backends:``, and the reference ``numpy`` ends every order (:mod:`.backends`).

    Raises
    ------
    PipelineError
        Listing every problem found, sorted by line.
    """
    chooser = BackendChooser(registry, graph.backends if backends is None else backends)
    with collector_paused():
        checker = _Checker(graph, registry, chooser)
        for problem in chooser.order_problems():  # the file's line, or the command line's
            checker.report("backends" if backends is None else "--backend", problem)
        return checker.run(provided)
