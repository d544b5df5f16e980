"""A node's result as the run keeps it: each output validated by its port type and frozen
(read-only for good), an array nobody else holds frozen in place, without a copy."""

from __future__ import annotations

import sys
from typing import Any

from graphvision.compiler.compile import Step
from graphvision.errors import PortValueError
from graphvision.execution.inputs import freeze_value
from graphvision.values.known import checked, frozen_value, note, recall
from graphvision.values.memory import frozen_in_place

__all__ = ["accepted", "invalid_output"]

getrefcount = sys.getrefcount
# What ``accepted`` holds of a node's result: its argument, the value and getrefcount's
# (Python 3.14 counts the stack otherwise: there, nothing is frozen in place)
_OWN_REFS = 3 if sys.version_info < (3, 14) else -(2**20)


def accepted(step: Step, result: Any, held: int, encoded: bool) -> dict[str, Any]:
    """Validated, frozen outputs of ``step`` from its ``result`` (``encoded``: as a worker
    process sent them); an array only the caller (``held`` references) holds is frozen
    without a copy."""
    if encoded:
        return {
            port: freeze_value(kind, kind.decode(arrays, meta))
            for port, (kind, arrays, meta) in result.items()
        }
    only = step.only_output
    if only is not None:  # one output: no tuple to split
        port, kind, scalar, plain = only
        if not scalar and recall(result, kind):  # frozen, accepted as ``kind`` before
            return {port: result}
        try:
            value = kind.validate(result)
        except PortValueError as error:
            raise invalid_output(port, error) from None
        if scalar:
            return {port: value}
        if plain and value is result and getrefcount(value) <= held + _OWN_REFS:
            frozen = frozen_in_place(value)  # nothing else holds it: no copy
            if frozen is not None:
                note(frozen, kind, True, frozen=True)
                return {port: frozen}
        return {port: frozen_value(kind, value)}
    outputs = {}
    for port, value in step.spec.split_outputs(result).items():
        try:
            outputs[port] = checked(step.outputs[port], value)
        except PortValueError as error:
            raise invalid_output(port, error) from None
    return outputs


def invalid_output(port: str, error: PortValueError) -> PortValueError:
    """What a run says of an output its port type refused."""
    return PortValueError(f"node returned an invalid output '{port}': {error}")
