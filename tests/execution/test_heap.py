"""A run in this process lets glibc keep the memory it frees (graphvision.execution.heap): a
node's next array of the same size reuses it instead of faulting in fresh pages."""

from __future__ import annotations

import subprocess
import sys
import textwrap

import pytest

SCRIPT = textwrap.dedent(
    """
    import resource

    import numpy as np

    import graphvision as gv

    if {run}:
        graph = gv.Graph("one")
        graph.output("out", graph.input("x", "Float", default=1.0))
        gv.run(graph, executor="sync")
    for _ in range(2):  # the second array: where the first one's memory went
        before = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
        array = np.ones(3 * 2**16)  # 1.5 MiB, every page written
        faults = resource.getrusage(resource.RUSAGE_SELF).ru_minflt - before
        del array
    print(faults)
    """
)


def faults_of_a_second_array(run: bool) -> int:
    done = subprocess.run(
        [sys.executable, "-c", SCRIPT.format(run=run)], capture_output=True, text=True, check=True
    )
    return int(done.stdout)


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="glibc's malloc")
def test_memory_freed_after_a_run_is_reused_without_page_faults():
    assert faults_of_a_second_array(run=False) >= 300  # 384 fresh 4 KiB pages
    assert faults_of_a_second_array(run=True) < 50
