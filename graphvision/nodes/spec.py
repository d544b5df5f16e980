"""What the registry knows of a node without running it: its ports, parameters, code
and documentation (``NodeSpec``), and where its function lives (``FunctionRef``)."""

from __future__ import annotations

import copy
import importlib
import inspect
import sys
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any

import pydantic

from graphvision.errors import ParameterError, PortValueError, did_you_mean
from graphvision.nodes.doc_text import doc_summary, math_text, plain_text
from graphvision.nodes.fingerprint import code_fingerprint, library_version
from graphvision.nodes.marks import SINGLE_OUTPUT, Conformance, unchecked
from graphvision.values.ports import PortType

__all__ = [
    "FunctionRef",
    "InputPort",
    "NodeSpec",
    "SourceSpec",
    "doc_summary",
    "math_text",
    "params_model",
    "plain_text",
]


@dataclass(frozen=True)
class FunctionRef:
    """Where a function lives, so another process can import it by name."""

    module: str
    qualname: str
    path: str = ""  # file of a local plugin that is not importable by module name

    def resolve(self) -> Callable:
        module = sys.modules.get(self.module)
        if module is None:
            if self.path:
                from graphvision.nodes.loading import import_file

                module = import_file(self.path, self.module)
            else:
                module = importlib.import_module(self.module)
        obj: Any = module
        for part in self.qualname.split("."):
            obj = getattr(obj, part)
        return unchecked(obj)  # the engine validates values itself


PortClass = type[PortType]
"""A port-type class (named so that a field called ``type`` cannot shadow it)."""


@dataclass(frozen=True)
class InputPort:
    """An input port: its type (a TypeVar's bound), optional or not, its TypeVar name."""

    type: PortClass
    optional: bool = False
    typevar: str = ""
    choices: tuple[PortClass, ...] = ()

    def accepts(self, given: PortClass) -> bool:
        """True when a value of type ``given`` may be connected to this port."""
        if self.choices:
            return any(given.is_a(choice) for choice in self.choices)
        return given.is_a(self.type)

    def bind(self, given: PortClass) -> PortClass:
        """The type this port's TypeVar takes for a connected ``given`` type."""
        for choice in self.choices:
            if given.is_a(choice):
                return choice
        return given

    def check(self, value: Any, where: str) -> tuple[Any, PortClass]:
        """(validated value, the port type it satisfies), or a PortValueError naming ``where``.

        The value goes through the port type's dtype policy first (:meth:`PortType.coerce`),
        as a graph input of ``gv.run`` does: a ``uint8`` photo is the image a PNG gives.
        """
        failures: dict[PortClass, str] = {}
        for choice in self.choices or (self.type,):
            try:
                return choice.admit(value, where), choice
            except PortValueError as error:  # the policy's messages start with ``where``
                failures[choice] = str(error).removeprefix(where).lstrip()
        # The common type's message covers the choices when it is one of them.
        message = failures.get(self.type) or " or ".join(failures.values())
        raise PortValueError(f"{where} {message}")

    def type_label(self) -> str:
        """The accepted type: the common one when a choice covers the others, else each."""
        if not self.choices or self.type in self.choices:
            return self.type.type_name()
        return " or ".join(c.type_name() for c in self.choices)


@dataclass(frozen=True)
class SourceSpec:
    scheme: str
    func: Callable[[str], Any]
    plugin: str
    key: Callable[[str], str] | None = None


@dataclass(frozen=True, eq=False)
class NodeSpec:
    """Everything the engine knows about a registered node."""

    id: str
    version: int
    func: Callable
    ref: FunctionRef
    inputs: dict[str, InputPort]
    outputs: dict[str, type[PortType]]
    param_fields: dict[str, tuple[Any, Any]]
    doc: str
    plugin: str
    cache: bool = True
    overrides: bool = False
    output_tuple: type | None = field(default=None, repr=False)
    output_vars: dict[str, str] = field(default_factory=dict)
    check: Callable[..., None] | None = field(default=None, repr=False)
    conformance: Conformance | None = field(default=None, repr=False)
    backend: str = "numpy"
    """The backend of this implementation (``numpy``: the op's own function, the reference)."""
    requires: tuple[str, ...] = ()
    """Modules the implementation imports when it runs (their versions are in its key)."""

    @property
    def key_id(self) -> str:
        """The op id as cache keys know it: ``op`` for the reference, ``op@backend`` else."""
        return self.id if self.backend == "numpy" else f"{self.id}@{self.backend}"

    @property
    def family(self) -> str:
        return self.id.split(".", 1)[0]

    @property
    def summary(self) -> str:
        """The docstring's first sentence as plain text (:func:`doc_summary`)."""
        return doc_summary(self.doc)

    @cached_property
    def source_hash(self) -> str:
        """Digest of the code the node runs, from the loaded code (see ``_fingerprint``),
        and of the versions of the libraries an implementation requires."""
        digest = code_fingerprint(self.func)
        if self.requires:
            digest += "+" + ",".join(library_version(m) for m in self.requires)
        return digest

    @cached_property
    def params_model(self) -> type[pydantic.BaseModel]:
        """The pydantic model of the parameters, built on first use.

        Building the models of every node is most of what registering the
        built-in plugins costs, and a command or a run uses few of them.
        Registration has checked that the model builds (or the plugin index
        recorded that it did for the same files: :mod:`._plugin_index`).
        """
        return params_model(self.id, self.param_fields, self.check)

    def params_schema(self) -> dict[str, Any]:
        """The JSON schema of the parameters (a copy: the caller may change it)."""
        return copy.deepcopy(self._params_schema)

    @cached_property
    def _params_schema(self) -> dict[str, Any]:
        return self.params_model.model_json_schema()

    def validate_params(self, params: dict[str, Any]) -> dict[str, Any]:
        """Validated, canonical parameters (JSON-able) or a pydantic ValidationError."""
        return self.params_model.model_validate(params).model_dump(mode="json")

    def param_problems(self, error: pydantic.ValidationError) -> list[tuple[str, str]]:
        """(parameter, message) for each problem of a parameter validation."""

        allowed = list(self.params_model.model_fields)
        problems = []
        for item in error.errors():
            param = ".".join(str(p) for p in item["loc"])
            said = str(item["msg"]).removeprefix("Value error, ")  # pydantic's ValueError prefix
            if not param:  # the node's own check of the parameters together
                problems.append(("", f"{self.id}: {said}"))
                continue
            if item["type"] == "extra_forbidden":
                listing = ", ".join(allowed) if allowed else "none"
                message = (
                    f"unknown parameter '{param}' of {self.id}"
                    f"{did_you_mean(param, allowed)}; parameters: {listing}"
                )
            else:
                message = (
                    f"invalid value {item.get('input')!r} for parameter "
                    f"'{param}' of {self.id}: {said}"
                )
            problems.append((param, message))
        return problems

    def check_call(
        self, args: tuple[Any, ...], kwargs: dict[str, Any]
    ) -> tuple[list[Any], dict[str, Any]]:
        """Validated (inputs, parameters) of a direct call, as a run would validate them.

        Raises
        ------
        PortValueError
            An input is missing, or fails its port type, or two inputs of one
            type variable have different types (a gray and a colour image).
        ParameterError
            A parameter is unknown or invalid.
        """
        names = list(self.inputs)
        if len(args) > len(names):
            raise PortValueError(
                f"{self.id} takes {len(names)} input(s) ({', '.join(names)}), got {len(args)}"
            )
        given = dict(zip(names, args, strict=False))
        for name in names:
            if name in kwargs:
                if name in given:
                    raise PortValueError(f"{self.id}: input '{name}' given twice")
                given[name] = kwargs.pop(name)
        values: list[Any] = []
        bound: dict[str, type[PortType]] = {}
        for name, port in self.inputs.items():
            value = given.get(name)
            if value is None:
                if not port.optional:
                    raise PortValueError(f"{self.id}: missing input '{name}'")
                values.append(None)
                continue
            value, chosen = port.check(value, f"{self.id}: input '{name}'")
            if port.typevar:
                first = bound.setdefault(port.typevar, chosen)
                if not chosen.is_a(first):
                    raise PortValueError(
                        f"{self.id}: input '{name}' is {chosen.type_name()} but an earlier "
                        f"input of type {port.typevar} is {first.type_name()}"
                    )
            values.append(value)
        try:
            model = self.params_model.model_validate(kwargs)
        except pydantic.ValidationError as error:
            raise ParameterError(
                "; ".join(message for _, message in self.param_problems(error))
            ) from None
        return values, {name: getattr(model, name) for name in type(model).model_fields}

    def split_outputs(self, result: Any) -> dict[str, Any]:
        if self.output_tuple is None:
            return {SINGLE_OUTPUT: result}
        if not isinstance(result, tuple) or len(result) != len(self.outputs):
            raise TypeError(
                f"node {self.id} must return {self.output_tuple.__name__} "
                f"with fields {list(self.outputs)}, got {type(result).__name__}"
            )
        return dict(zip(self.outputs, result, strict=True))

    def _output_label(self, port: str) -> str:
        var = self.output_vars.get(port)
        for declared in self.inputs.values():
            if var and declared.typevar == var:
                return f"{declared.type_label()} (as connected)"
        return self.outputs[port].type_name()

    def describe(self) -> dict[str, Any]:
        return {
            "id": self.id,
            "version": self.version,
            "plugin": self.plugin,
            "function": f"{self.ref.module}:{self.ref.qualname}",
            "inputs": {
                k: {"type": p.type_label(), "optional": p.optional} for k, p in self.inputs.items()
            },
            "outputs": {k: self._output_label(k) for k in self.outputs},
            "params": self.params_schema(),
            "cache": self.cache,
            "conformance": self.conformance.describe() if self.conformance else None,
            "summary": self.summary,
            "doc": inspect.cleandoc(self.doc),  # reStructuredText, as written
            "text": plain_text(inspect.cleandoc(self.doc)),  # as `graphvision describe` shows it
        }


def params_model(
    id: str, fields: dict[str, Any], check: Callable[..., None] | None
) -> type[pydantic.BaseModel]:
    """The pydantic model of a node's parameters: no unknown names, defaults validated,
    no NaN or infinity."""
    validators: dict[str, Any] = {}
    if check is not None:
        together = check

        def check_together(model: Any) -> Any:
            together(**dict(model))
            return model

        validators["check_together"] = pydantic.model_validator(mode="after")(check_together)
    return pydantic.create_model(
        f"{id}.params",
        __config__=pydantic.ConfigDict(extra="forbid", validate_default=True, allow_inf_nan=False),
        __validators__=validators,
        **fields,
    )
