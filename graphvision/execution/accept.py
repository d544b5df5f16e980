"""A node's result as the run keeps it: each output validated by its port type and frozen
(read-only for good), an array nobody else holds frozen in place, without a copy."""

from __future__ import annotations

import sys
from typing import Any

from numpy import ndarray

from graphvision.compiler.compile import Step
from graphvision.errors import PortValueError
from graphvision.execution.inputs import freeze_value
from graphvision.values.known import checked, frozen_value, noted_new, recall
from graphvision.values.memory import frozen_in_place
from graphvision.values.ports import is_plain_array_port

__all__ = ["accepted", "invalid_output"]

getrefcount = sys.getrefcount
# What ``accepted`` holds of a node's result: its argument, the value and getrefcount's
# (Python 3.14 counts the stack otherwise: there, nothing is frozen in place)
_OWN_REFS = 3 if sys.version_info < (3, 14) else -(2**20)
_TUPLE_REFS = 2  # of a tuple of outputs: its argument and getrefcount's
# of an array in it that nothing else holds: the tuple, two names (as given, as validated)
# and getrefcount's
_IN_TUPLE_REFS = _OWN_REFS + 1


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
        # frozen, accepted as ``kind`` before (a writable array is not: no note to look up)
        fresh = type(result) is ndarray and result.flags.writeable
        if not scalar and not fresh and recall(result, kind):
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
                return {port: noted_new(frozen, kind)}
        return {port: frozen_value(kind, value)}
    alone = getrefcount(result) <= held + _TUPLE_REFS  # (counted before the call holds it)
    return _accepted_outputs(step, result, alone)


def _accepted_outputs(step: Step, result: Any, alone: bool) -> dict[str, Any]:
    """:func:`accepted` of a node with several outputs (a tuple); ``alone``: nothing but the
    caller holds the tuple, so an array that nothing but the tuple (and this loop) holds is
    frozen where it lies, as a node's one output is; the others are copied."""
    outputs, kinds = {}, step.outputs
    ports = list(step.spec.split_outputs(result))  # (which checks the tuple; an iterator over
    for index, port in enumerate(ports):  # its pairs would hold the last value once more)
        kind, value = kinds[port], result[index]
        try:
            if alone and is_plain_array_port(kind) and not recall(value, kind):
                checked_value = kind.validate(value)
                if checked_value is value and getrefcount(value) <= _IN_TUPLE_REFS:
                    frozen = frozen_in_place(value)
                    if frozen is not None:
                        outputs[port] = noted_new(frozen, kind)
                        continue
                outputs[port] = frozen_value(kind, checked_value)
                continue
            outputs[port] = checked(kind, value)
        except PortValueError as error:
            raise invalid_output(port, error) from None
    return outputs


def invalid_output(port: str, error: PortValueError) -> PortValueError:
    """What a run says of an output its port type refused."""
    return PortValueError(f"node returned an invalid output '{port}': {error}")
