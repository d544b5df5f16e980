"""Reading a node function's signature into a :class:`~graphvision.nodes.spec.NodeSpec`:
port types from the annotations (aliases, type variables, named tuples), parameters into
a pydantic model, checked when the plugin registers."""

from __future__ import annotations

import contextlib
import inspect
import sys
import types
import typing
from collections.abc import Callable
from typing import Any, TypeVar, Union, get_args, get_origin

from graphvision.errors import RegistrationError
from graphvision.nodes.marks import NODE_ID, SINGLE_OUTPUT, NodeMark, unchecked
from graphvision.nodes.spec import FunctionRef, InputPort, NodeSpec
from graphvision.types import port_of
from graphvision.values.ports import PortType

__all__ = [
    "build_spec",
    "type_label",
]


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
    mark: NodeMark = func.__graphvision_node__  # type: ignore[attr-defined]
    reject = _rejecter(func, plugin, mark.id)
    hints = _checked_mark_and_hints(func, mark, reject)
    inputs, fields = _ports_and_parameters(func, hints, reject)
    outputs, output_tuple, output_vars = _outputs(hints, inputs, reject)
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
        conformance=mark.conformance,
    )
    if not params_checked:
        try:
            spec.params_model.model_validate({})
            spec.params_schema()
        except Exception as error:
            raise reject(f"parameters cannot be validated: {error}") from error
    return spec


Reject = Callable[[str], RegistrationError]


def _rejecter(func: Callable, plugin: str, node_id: str) -> Reject:
    """A function making the registration error of ``func``, naming plugin, function and place."""
    code = getattr(func, "__code__", None)
    place = f" at {code.co_filename}:{code.co_firstlineno}" if code else ""
    where = f"plugin '{plugin}', function {func.__qualname__}{place}"
    return lambda reason: RegistrationError(f"{where} (node '{node_id}'): {reason}")


def _checked_mark_and_hints(func: Callable, mark: NodeMark, reject: Reject) -> dict[str, Any]:
    """The id, version and docstring checked; the resolved annotations."""
    if not NODE_ID.match(mark.id):
        raise reject("node id must be 'family.name' in lower snake case")
    if not isinstance(mark.version, int) or isinstance(mark.version, bool) or mark.version < 1:
        raise reject(f"version must be a positive integer, got {mark.version!r}")
    if not (func.__doc__ or "").strip():
        raise reject("a node needs a docstring (it is the node's documentation)")
    try:
        return typing.get_type_hints(func, include_extras=True)
    except Exception as error:  # NameError etc. from an unresolvable annotation
        raise reject(f"cannot resolve annotations: {error}") from error


def _ports_and_parameters(
    func: Callable, hints: dict[str, Any], reject: Reject
) -> tuple[dict[str, InputPort], dict[str, Any]]:
    """Input ports (positional, annotated with port types) and parameters (keyword-only)."""
    inputs: dict[str, InputPort] = {}
    fields: dict[str, Any] = {}
    for name, parameter in inspect.signature(func).parameters.items():
        annotation = hints.get(name, inspect.Parameter.empty)
        if parameter.kind in (parameter.VAR_POSITIONAL, parameter.VAR_KEYWORD):
            raise reject(f"*{name} / **{name} are not allowed; declare each port and parameter")
        if parameter.kind in (parameter.POSITIONAL_ONLY, parameter.POSITIONAL_OR_KEYWORD):
            inputs[name] = _input_port(name, parameter, annotation, reject)
        else:
            if parameter.default is parameter.empty:
                raise reject(f"parameter '{name}' needs a default value")
            if annotation is inspect.Parameter.empty:
                raise reject(f"parameter '{name}' needs a type annotation")
            fields[name] = (annotation, parameter.default)
    return inputs, fields


def _input_port(
    name: str, parameter: inspect.Parameter, annotation: Any, reject: Reject
) -> InputPort:
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
    return InputPort(port, optional, typevar, _typevar_choices(annotation))


def _outputs(
    hints: dict[str, Any], inputs: dict[str, InputPort], reject: Reject
) -> tuple[dict[str, type[PortType]], Any, dict[str, str]]:
    """Output ports from the return annotation: one port type, a type variable of an
    input, or a (generic) NamedTuple of those; with the tuple class and bound variables."""
    returned = hints.get("return", inspect.Parameter.empty)
    output_vars: dict[str, str] = {}
    bound_vars = {port.typevar for port in inputs.values() if port.typevar}
    if isinstance(returned, TypeVar):
        if returned.__name__ not in bound_vars:
            raise reject(f"output type variable {returned.__name__} must also annotate an input")
        return {SINGLE_OUTPUT: _typevar_port(returned)}, None, {SINGLE_OUTPUT: returned.__name__}
    if (single := port_of(returned)) is not None:
        return {SINGLE_OUTPUT: single}, None, output_vars
    if not _is_named_tuple(tuple_class := get_origin(returned) or returned):
        raise reject(
            "the return annotation must be a port type or a NamedTuple of port types, "
            f"got {type_label(returned)}"
        )
    field_hints = typing.get_type_hints(tuple_class, include_extras=True)
    outputs = {}
    for name in tuple_class._fields:  # a generic NamedTuple's fields name its TypeVars
        hint = field_hints.get(name)
        if isinstance(hint, TypeVar) and hint.__name__ in bound_vars:
            outputs[name] = _typevar_port(hint)
            output_vars[name] = hint.__name__
        elif (field_port := port_of(hint)) is not None:
            outputs[name] = field_port
        else:
            raise reject(
                f"output '{name}' of {tuple_class.__name__} must be a port type "
                "(or a type variable of an input)"
            )
    return outputs, tuple_class, output_vars
