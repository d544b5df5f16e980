"""What is known of a frozen array already: the port types it passed, its content key.

A frozen array (:func:`~graphvision.values.ports.is_frozen`: over immutable memory) has
the same values for as long as it lives, so what was worked out from them once holds
for its life: that it passed a port type's :meth:`~graphvision.PortType.validate`, and
its content key. A run that is given the same frozen array again (a script or a
benchmark running one pipeline on one image many times, a sweep, a batch of runs on a
loaded image), or a node that returns one of its inputs unchanged, then skips a pass
over its data for each (on ``coins.yaml``: the input checked twice and hashed once
per run, about 0.2 ms of a 12 ms run).

What is noted is kept by the array's ``id`` with a weak reference to it (a new array at
the same address is not taken for it: the reference no longer leads to it), and stamped
with its shape, strides and dtype: all can be set on an array in place (``array.shape =
...``), its memory cannot. Only frozen arrays are noted; everything else is worked out every
time. The notes of arrays that died are dropped together, when there are twice as many
notes as after the last such sweep (a callback per array, called at its death, was a
microsecond per frozen array of a run).
"""

from __future__ import annotations

import weakref
from typing import Any

import numpy as np

from graphvision.values.ports import PortType, freeze, freeze_all, is_frozen, is_plain_array_port
from graphvision.values.scalars import _ScalarPort, is_plain_table_port

__all__ = ["checked", "frozen_value", "note", "noted_new", "recall"]

_Stamp = tuple[tuple[int, ...], tuple[int, ...]]  # shape, strides
_NOTES: dict[int, tuple[weakref.ref[np.ndarray], _Stamp, np.dtype, dict[Any, Any]]] = {}
_SWEEP_AT = [1024]  # the number of notes at which those of dead arrays are dropped


def _sweep() -> None:
    """Drop the notes of arrays that died; sweep again at twice the notes left (at least
    1024): each note is looked at a bounded number of times on average."""
    for key in [key for key, entry in _NOTES.items() if entry[0]() is None]:
        del _NOTES[key]
    _SWEEP_AT[0] = max(1024, 2 * len(_NOTES))


def recall(value: Any, what: Any) -> Any:
    """What was noted of ``value`` under ``what`` (None when nothing, or not an array)."""
    if type(value) is not np.ndarray:
        return None
    entry = _NOTES.get(id(value))
    if entry is None or entry[0]() is not value:
        return None
    if entry[1] != (value.shape, value.strides) or entry[2] != value.dtype:  # set since
        return None
    return entry[3].get(what)


def note(value: Any, what: Any, fact: Any, frozen: bool = False) -> None:
    """Note ``fact`` of ``value`` under ``what``, if ``value`` is a frozen plain array
    (``frozen``: the caller has just frozen it, it is not looked at again)."""
    if type(value) is not np.ndarray or value.flags.writeable:
        return
    key = id(value)
    entry = _NOTES.get(key)
    if entry is None or entry[0]() is not value:
        if not frozen and not is_frozen(value):
            return
        entry = _new_entry(value, {})
    elif entry[1] != (value.shape, value.strides) or entry[2] != value.dtype:
        entry[3].clear()
        entry = _NOTES[key] = (entry[0], (value.shape, value.strides), value.dtype, entry[3])
    entry[3][what] = fact


def noted_new(value: np.ndarray, what: Any) -> np.ndarray:
    """:func:`note` that ``value`` passed ``what``, for an array object just made over
    immutable memory (:func:`~graphvision.values.memory.frozen_in_place`'s): no note of it
    can be alive (one under its ``id`` is of an array that died), so it is made without
    the look-ups :func:`note` makes (a run notes each array a node returns). Returns it."""
    _new_entry(value, {what: True})
    return value


def _new_entry(value: np.ndarray, facts: dict[Any, Any]) -> Any:
    """The note of ``value`` made anew, holding ``facts`` (the notes of dead arrays swept
    first when they are many)."""
    if len(_NOTES) >= _SWEEP_AT[0]:
        _sweep()
    entry = _NOTES[id(value)] = (
        weakref.ref(value),
        (value.shape, value.strides),
        value.dtype,
        facts,
    )
    return entry


def checked(kind: type[PortType], value: Any) -> Any:
    """``value`` validated by port type ``kind`` and frozen (:func:`frozen_value`); a frozen
    array ``kind`` accepted before is returned as it is. Raises what ``kind.validate``
    raises."""
    if recall(value, kind):
        return value
    return frozen_value(kind, kind.validate(value))


def frozen_value(kind: type[PortType], value: Any) -> Any:
    """A valid value of ``kind`` over immutable copies of its arrays (those not in immutable
    memory already), noted as accepted by ``kind``; a scalar as it is."""
    if issubclass(kind, _ScalarPort):
        return value
    if type(value) is np.ndarray and is_plain_array_port(kind):  # its one array as it is
        frozen: Any = freeze(value)
    elif type(value) is dict and is_plain_table_port(kind):  # its columns as they are
        frozen = freeze_all(value)
    else:
        arrays, meta = kind.encode(value)
        frozen = kind.decode(freeze_all(arrays), meta)
    note(frozen, kind, True, frozen=True)  # (what freeze and freeze_all return is frozen)
    return frozen
