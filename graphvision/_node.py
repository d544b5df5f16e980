"""Nodes: a typed Python function plus a decorator.

::

    @node("filters.gaussian", version=1)
    def gaussian(image: ImageT, *, sigma: Annotated[float, Field(gt=0)] = 1.0) -> ImageT:
        '''NumPy-style docstring: the node's documentation.'''

* positional parameters are **input ports**, annotated with an alias of
  :mod:`graphvision.types` (``Annotated[value type, port type]``; a bare port
  class is still read) and ``Optional[T] = None`` makes the port optional;
* keyword-only parameters are **parameters**, with defaults, validated by a
  pydantic model built from their annotations (``Annotated[..., Field(...)]``
  for constraints, ``Literal[...]`` for choices);
* the return annotation is the **output**: one port type (port ``out``) or a
  ``NamedTuple`` whose fields are port types (one port per field);
* a ``TypeVar`` makes a node generic: ``def gaussian(image: ImageT) -> ImageT``
  with ``ImageT = TypeVar("ImageT", GrayImage, ColorImage, Image)`` gives a
  ``GrayImage`` out for a ``GrayImage`` in. The checker binds the variable to
  the first constraint the connected type is a subtype of (a bound works
  too, binding to the connected type itself).

Signatures are checked when a plugin registers (:func:`build_spec`), not when
the node first runs. The decorator returns the function wrapped so that a
direct call (``gaussian(image, sigma=2)`` in a script or a test) validates its
inputs with the same port types and its parameters with the same pydantic
model as a run does, and fails with a :class:`~graphvision.PortValueError` or
:class:`~graphvision.ParameterError` naming the node and the port or
parameter. The engine validates values itself and calls the unchecked
function (``NodeSpec.func``, also ``checked.__wrapped__``), so nothing is
checked twice on a run's hot path.
"""

from __future__ import annotations

import contextlib
import copy
import functools
import importlib
import inspect
import re
import sys
import types
import typing
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any, TypeVar, Union, get_args, get_origin

import pydantic

from ._errors import ParameterError, PortValueError, RegistrationError, did_you_mean
from ._fingerprint import code_fingerprint
from ._ports import PortType
from .types import port_of

__all__ = [
    "FunctionRef",
    "InputPort",
    "NodeSpec",
    "SourceSpec",
    "build_spec",
    "node",
    "source",
    "unchecked",
]

NODE_ID = re.compile(r"^[a-z][a-z0-9_]*\.[a-z][a-z0-9_]*$")
SINGLE_OUTPUT = "out"


@dataclass(frozen=True)
class _NodeMark:
    id: str
    version: int
    cache: bool
    overrides: bool
    check: Callable[..., None] | None = None


@dataclass(frozen=True)
class _SourceMark:
    scheme: str
    key: Callable[[str], str] | None = None


def node(
    id: str,
    *,
    version: int = 1,
    cache: bool = True,
    overrides: bool = False,
    check: Callable[..., None] | None = None,
) -> Callable[[Callable], Callable]:
    """Mark a function as the graphvision node ``id`` (``family.name``).

    Parameters
    ----------
    id : str
        Stable node id, ``family.name`` in lower snake case.
    version : int
        Bump it when the node's results change for reasons its own source does
        not show (a helper it calls changed); it is part of every cache key.
    cache : bool
        False opts the node out of caching (it is recomputed on every run).
    overrides : bool
        True lets this node replace another plugin's node of the same id.
    check : callable, optional
        ``check(**params)`` raises ``ValueError`` for parameter values that are
        each valid but not together (``p2 < p1``, an even window): it runs with
        the parameter model, so a pipeline is refused before anything runs and a
        direct call before the body, naming the node.
    """

    def mark(func: Callable) -> Callable:
        func.__graphvision_node__ = _NodeMark(id, version, cache, overrides, check)  # type: ignore[attr-defined]
        return _checked_call(func)

    return mark


def _checked_call(func: Callable) -> Callable:
    """``func`` behind the checks a run makes: inputs by port type, parameters by model."""
    specs: list[NodeSpec] = []  # built on the first call: registration stays the checker

    @functools.wraps(func)
    def checked(*args: Any, **kwargs: Any) -> Any:
        if not specs:
            specs.append(build_spec(func, plugin=func.__module__))
        inputs, params = specs[0].check_call(args, kwargs)
        return func(*inputs, **params)

    return checked


def unchecked(func: Callable) -> Callable:
    """The function a node decorator wrapped (``func`` itself when it is not a node)."""
    while hasattr(func, "__graphvision_node__") and hasattr(func, "__wrapped__"):
        func = func.__wrapped__
    return func


def source(
    scheme: str, *, key: Callable[[str], str] | None = None
) -> Callable[[Callable], Callable]:
    """Mark ``func(reference: str)`` as the loader of graph-input values ``scheme:reference``.

    The scheme ``file`` is used for values without a scheme (paths). ``key``,
    for a source whose values are fixed by the reference (data shipped with a
    library), gives the text that identifies the value without loading it
    (e.g. name and library version): the cache keys the input by that text,
    and a fully cached run never loads the value.
    """

    def mark(func: Callable) -> Callable:
        func.__graphvision_source__ = _SourceMark(scheme, key)  # type: ignore[attr-defined]
        return func

    return mark


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
                from ._plugins import import_file

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
        """(validated value, the port type it satisfies), or a PortValueError naming ``where``."""
        failures: dict[PortClass, str] = {}
        for choice in self.choices or (self.type,):
            try:
                return choice.validate(value), choice
            except PortValueError as error:
                failures[choice] = str(error)
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

    @property
    def family(self) -> str:
        return self.id.split(".", 1)[0]

    @property
    def summary(self) -> str:
        return self.doc.strip().splitlines()[0] if self.doc.strip() else ""

    @cached_property
    def source_hash(self) -> str:
        """Digest of the code the node runs, from the loaded code (see ``_fingerprint``)."""
        return code_fingerprint(self.func)

    @cached_property
    def params_model(self) -> type[pydantic.BaseModel]:
        """The pydantic model of the parameters, built on first use.

        Building the models of every node is most of what registering the
        built-in plugins costs, and a command or a run uses few of them.
        Registration has checked that the model builds (or the plugin index
        recorded that it did for the same files: :mod:`._plugin_index`).
        """
        return _params_model(self.id, self.param_fields, self.check)

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
            "doc": inspect.cleandoc(self.doc),
        }


def _port_type(annotation: Any) -> tuple[type[PortType] | None, bool]:
    """(port type, optional) of an input annotation, or (None, False).

    A ``TypeVar``'s port type is its bound's, or the most specific port type
    all its constraints share.
    """
    if isinstance(annotation, TypeVar):
        if annotation.__constraints__:
            choices = [port_of(c) for c in annotation.__constraints__]
            if any(c is None for c in choices):
                return None, False
            ports = typing.cast(list[type[PortType]], choices)
            common = next(c for c in ports[0].__mro__ if all(issubclass(o, c) for o in ports))
            return common, False
        return port_of(annotation.__bound__), False
    if get_origin(annotation) in (Union, types.UnionType):
        args = [a for a in get_args(annotation) if a is not type(None)]
        if len(args) == 1 and len(get_args(annotation)) == 2:
            inner, _ = _port_type(args[0])
            return inner, inner is not None
        return None, False
    return port_of(annotation), False


def type_label(annotation: Any) -> str:
    """An annotation as a reader writes it: ``numpy.ndarray``, ``float``, ``list[int]``."""
    if annotation is inspect.Parameter.empty:
        return "no annotation"
    if isinstance(annotation, type) and not get_args(annotation):
        module = annotation.__module__
        return (
            annotation.__qualname__
            if module == "builtins"
            else f"{module}.{annotation.__qualname__}"
        )
    return str(annotation).replace("typing.", "")


def _typevar_port(annotation: TypeVar) -> type[PortType]:
    """The port type of an output TypeVar, which an input's annotation has already checked."""
    port, _ = _port_type(annotation)
    if port is None:  # pragma: no cover - the same TypeVar annotates a checked input
        raise TypeError(f"type variable {annotation.__name__} has no port type")
    return port


def _typevar_choices(annotation: Any) -> tuple[type[PortType], ...]:
    if not isinstance(annotation, TypeVar):
        return ()
    return tuple(typing.cast(type[PortType], port_of(c)) for c in annotation.__constraints__)


def _is_named_tuple(obj: Any) -> bool:
    return isinstance(obj, type) and issubclass(obj, tuple) and hasattr(obj, "_fields")


def _ref_for(func: Callable) -> FunctionRef:
    module = sys.modules.get(func.__module__)
    path = getattr(module, "__graphvision_path__", "") if module else ""
    return FunctionRef(func.__module__, func.__qualname__, path)


def build_spec(func: Callable, plugin: str, *, params_checked: bool = False) -> NodeSpec:
    """Check a decorated function's signature and build its :class:`NodeSpec`.

    A spec is immutable and depends only on the function object and the plugin
    name, so it is built once per function and plugin and kept on the function:
    every ``discover()`` after the first (each ``run`` without a registry does
    one) costs no pydantic model building. A plugin file that changed is
    imported again, so its functions are new objects and get new specs.

    The parameter model is built, validated on the defaults and given its JSON
    schema here, so that a node whose parameters cannot be validated is refused
    when it registers, unless ``params_checked`` says that this was done for the
    same code already (the plugin index); then the model is built on first use.

    Raises
    ------
    RegistrationError
        Naming the plugin and the function, for any signature that is not a node.
    """
    func = unchecked(func)
    built: dict[str, NodeSpec] | None = getattr(func, "__graphvision_specs__", None)
    if built is not None and plugin in built:
        return built[plugin]
    spec = _build_spec(func, plugin, params_checked)
    if built is None:
        built = {}
        with contextlib.suppress(AttributeError, TypeError):  # e.g. a builtin: not kept
            func.__graphvision_specs__ = built  # type: ignore[attr-defined]
    built[plugin] = spec
    return spec


def _build_spec(func: Callable, plugin: str, params_checked: bool) -> NodeSpec:
    mark: _NodeMark = func.__graphvision_node__  # type: ignore[attr-defined]
    code = getattr(func, "__code__", None)
    place = f" at {code.co_filename}:{code.co_firstlineno}" if code else ""
    where = f"plugin '{plugin}', function {func.__qualname__}{place}"

    def reject(reason: str) -> RegistrationError:
        return RegistrationError(f"{where} (node '{mark.id}'): {reason}")

    if not NODE_ID.match(mark.id):
        raise reject("node id must be 'family.name' in lower snake case")
    if not isinstance(mark.version, int) or isinstance(mark.version, bool) or mark.version < 1:
        raise reject(f"version must be a positive integer, got {mark.version!r}")
    if not (func.__doc__ or "").strip():
        raise reject("a node needs a docstring (it is the node's documentation)")
    try:
        hints = typing.get_type_hints(func, include_extras=True)
    except Exception as error:  # NameError etc. from an unresolvable annotation
        raise reject(f"cannot resolve annotations: {error}") from error

    inputs: dict[str, InputPort] = {}
    fields: dict[str, Any] = {}
    for name, parameter in inspect.signature(func).parameters.items():
        annotation = hints.get(name, inspect.Parameter.empty)
        if parameter.kind in (parameter.VAR_POSITIONAL, parameter.VAR_KEYWORD):
            raise reject(f"*{name} / **{name} are not allowed; declare each port and parameter")
        if parameter.kind is parameter.POSITIONAL_ONLY or (
            parameter.kind is parameter.POSITIONAL_OR_KEYWORD
        ):
            port, optional = _port_type(annotation)
            if port is None:
                raise reject(
                    f"input '{name}' must be annotated with a port type "
                    f"(e.g. Image), got {type_label(annotation)}; parameters go after '*'"
                )
            if optional and parameter.default is not None:
                raise reject(f"optional input '{name}' must default to None")
            if not optional and parameter.default is not parameter.empty:
                raise reject(f"input '{name}' has a default; only Optional[...] = None inputs may")
            typevar = annotation.__name__ if isinstance(annotation, TypeVar) else ""
            inputs[name] = InputPort(port, optional, typevar, _typevar_choices(annotation))
        else:
            if parameter.default is parameter.empty:
                raise reject(f"parameter '{name}' needs a default value")
            if annotation is inspect.Parameter.empty:
                raise reject(f"parameter '{name}' needs a type annotation")
            fields[name] = (annotation, parameter.default)

    returned = hints.get("return", inspect.Parameter.empty)
    output_tuple = None
    output_vars: dict[str, str] = {}
    bound_vars = {port.typevar for port in inputs.values() if port.typevar}
    if isinstance(returned, TypeVar):
        if returned.__name__ not in bound_vars:
            raise reject(f"output type variable {returned.__name__} must also annotate an input")
        outputs = {SINGLE_OUTPUT: _typevar_port(returned)}
        output_vars[SINGLE_OUTPUT] = returned.__name__
    elif (single := port_of(returned)) is not None:
        outputs = {SINGLE_OUTPUT: single}
    elif _is_named_tuple(tuple_class := get_origin(returned) or returned):
        returned = tuple_class  # a generic NamedTuple's fields name its TypeVars
        field_hints = typing.get_type_hints(returned, include_extras=True)
        outputs = {}
        for name in returned._fields:
            hint = field_hints.get(name)
            if isinstance(hint, TypeVar) and hint.__name__ in bound_vars:
                outputs[name] = _typevar_port(hint)
                output_vars[name] = hint.__name__
            elif (field_port := port_of(hint)) is not None:
                outputs[name] = field_port
            else:
                raise reject(
                    f"output '{name}' of {returned.__name__} must be a port type "
                    "(or a type variable of an input)"
                )
        output_tuple = returned
    else:
        raise reject(
            "the return annotation must be a port type or a NamedTuple of port types, "
            f"got {type_label(returned)}"
        )

    spec = NodeSpec(
        id=mark.id,
        version=mark.version,
        func=func,
        ref=_ref_for(func),
        inputs=inputs,
        outputs=outputs,
        param_fields=fields,
        doc=func.__doc__ or "",
        plugin=plugin,
        cache=mark.cache,
        overrides=mark.overrides,
        output_tuple=output_tuple,
        output_vars=output_vars,
        check=mark.check,
    )
    if not params_checked:
        try:
            spec.params_model.model_validate({})
            spec.params_schema()
        except Exception as error:
            raise reject(f"parameters cannot be validated: {error}") from error
    return spec


def _params_model(
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
