"""What is known of a frozen array (graphvision.values.known): kept for its life, for it alone."""

from __future__ import annotations

import gc
import warnings

import numpy as np
import pytest

import graphvision as gv
from graphvision.errors import PortValueError
from graphvision.values.images import GrayImagePort, ImagePort
from graphvision.values.known import checked, note, noted_new, recall
from graphvision.values.memory import frozen_copy, frozen_in_place


def test_a_frozen_array_accepted_once_is_not_checked_again(monkeypatch):
    image = frozen_copy(np.full((4, 5), 0.5, dtype=np.float32))
    first = checked(GrayImagePort, image)
    assert first is image  # frozen already: not copied
    calls = []
    monkeypatch.setattr(GrayImagePort, "validate", classmethod(lambda cls, v: calls.append(v)))
    assert checked(GrayImagePort, image) is image
    assert calls == []
    checked(ImagePort, image)  # another port type: checked by itself
    assert calls == []  # (ImagePort's own check ran, not GrayImage's)


def test_a_writable_array_is_checked_every_time():
    image = np.full((4, 5), 0.5, dtype=np.float32)
    frozen = checked(GrayImagePort, image)
    assert frozen is not image and not frozen.flags.writeable
    assert recall(image, GrayImagePort) is None  # nothing noted of what can change
    image[0, 0] = 2.0
    with pytest.raises(PortValueError, match=r"values in \[0, 1\], got range \[0.5, 2\]"):
        checked(GrayImagePort, image)


def test_a_note_does_not_outlive_its_array_nor_a_change_of_shape():
    image = frozen_copy(np.zeros((4, 6), dtype=np.float32))
    note(image, "fact", 1)
    assert recall(image, "fact") == 1
    image.shape = (6, 4)  # a shape can be set in place
    assert recall(image, "fact") is None
    note(image, "fact", 2)
    with warnings.catch_warnings():  # (setting strides is deprecated)
        warnings.simplefilter("ignore", DeprecationWarning)
        image.strides = (0, 4)  # and strides: the same shape and dtype, other values
    assert recall(image, "fact") is None
    address = id(image)
    del image
    gc.collect()
    other = frozen_copy(np.zeros((4, 6), dtype=np.float32))
    assert id(other) != address or recall(other, "fact") is None


def test_a_node_output_frozen_in_place_is_noted_as_its_port_type_took_it():
    """A node's array frozen where it lies is noted at once (without :func:`note`'s look-ups):
    accepted again as the same port type it is not checked again, as any other type it is;
    the note of an array that died at the same ``id`` is replaced, not added to."""
    array = np.full((128, 64), 0.5, dtype=np.float32)
    dead = noted_new(frozen_copy(array), GrayImagePort)
    note(dead, "other fact", 1)
    address = id(dead)
    del dead
    gc.collect()
    frozen = frozen_in_place(array)
    assert frozen is not None and noted_new(frozen, GrayImagePort) is frozen
    assert recall(frozen, GrayImagePort) is True and recall(frozen, ImagePort) is None
    assert id(frozen) != address or recall(frozen, "other fact") is None
    assert checked(GrayImagePort, frozen) is frozen


def test_a_frozen_input_given_again_is_keyed_and_checked_once(monkeypatch):
    graph = gv.Graph("again")
    graph.output("out", graph.input("image", "GrayImage"))
    image = frozen_copy(np.full((8, 8), 0.25, dtype=np.float32))
    registry = gv.discover([], entry_points=False)
    first = gv.run(graph, registry, inputs={"image": image}, executor="sync")
    calls = []
    original = GrayImagePort.validate.__func__
    monkeypatch.setattr(
        GrayImagePort, "validate", classmethod(lambda cls, v: calls.append(1) or original(cls, v))
    )
    second = gv.run(graph, registry, inputs={"image": image}, executor="sync")
    assert calls == []
    assert second.outputs["out"] is image
    assert second.record.inputs["image"]["key"] == first.record.inputs["image"]["key"]


def test_the_notes_of_dead_arrays_are_dropped_and_those_of_live_ones_kept():
    """Notes are dropped in sweeps (no callback per array): many arrays noted and let go
    leave a bounded number of notes, and an array still alive keeps its own throughout."""
    from graphvision.values import known

    kept = frozen_copy(np.arange(6, dtype=np.float32))
    note(kept, "fact", "kept")
    for k in range(5000):
        note(frozen_copy(np.full(3, k, dtype=np.int16)), "fact", k)  # dead at once
    assert len(known._NOTES) <= known._SWEEP_AT[0] < 5000
    assert recall(kept, "fact") == "kept"
    known._sweep()
    assert all(entry[0]() is not None for entry in known._NOTES.values())
    assert recall(kept, "fact") == "kept"
