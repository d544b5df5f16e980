"""Validation pauses the cyclic collector and always gives it back as it was."""

from __future__ import annotations

import gc

import pytest

import graphvision as gv
from graphvision.graph.collector import collector_paused
from graphvision.graph.pipeline_file import parse_pipeline


def test_the_collector_is_paused_inside_and_restored_after_an_error():
    assert gc.isenabled()
    with pytest.raises(RuntimeError, match="inside"), collector_paused():
        assert not gc.isenabled()
        raise RuntimeError("inside")
    assert gc.isenabled()


def test_a_disabled_collector_stays_disabled():
    gc.disable()
    try:
        with collector_paused():
            pass
        assert not gc.isenabled()
    finally:
        gc.enable()


def test_parsing_and_compiling_leave_the_collector_on_even_when_the_file_is_bad():
    with pytest.raises(gv.PipelineError, match=r"unknown op 'nope\.nothing'"):
        graph = parse_pipeline(
            "version: 1\nname: bad\nnodes:\n  a: {op: nope.nothing}\noutputs:\n  a: a\n", "bad.yaml"
        )
        assert gc.isenabled()
        gv.compile_graph(graph, gv.discover())
    assert gc.isenabled()
    with pytest.raises(gv.PipelineError, match=r"bad\.yaml"):
        parse_pipeline("version: 1\nname: [unclosed\n", "bad.yaml")
    assert gc.isenabled()
