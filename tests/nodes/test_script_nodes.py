"""A node defined in a script or a notebook (``__main__``) runs with ``gv.run(graph)``,
without a registry call (issue 29 item 12): the run adds the nodes of ``__main__`` that
the graph uses and no plugin provides; a cell run again replaces its node."""

from __future__ import annotations

import subprocess
import sys

SCRIPT = '''
import numpy as np
import graphvision as gv
from graphvision import GrayImage, node


@node("mine.invert")
def invert(image: GrayImage) -> GrayImage:
    """One minus the image."""
    return 1.0 - image


graph = gv.Graph("script")
image = graph.input("image", "GrayImage")
graph.output("out", graph.add("inv", "mine.invert", image=image))
given = np.full((4, 5), 0.25, np.float32)
for executor in ("sync", "threads"):
    result = gv.run(graph, inputs={"image": given}, executor=executor)
    print(executor, float(result.outputs["out"].mean()))


@node("mine.invert")  # the cell run again, changed
def invert(image: GrayImage) -> GrayImage:
    """One minus the image, halved."""
    return (1.0 - image) / 2


print("again", float(gv.run(graph, inputs={"image": given}, cache=None).outputs["out"].mean()))
graph.add("other", "mine.unknown", image=image)
try:
    gv.run(graph, inputs={"image": given})
except gv.PipelineError as error:
    print("unknown", "unknown op 'mine.unknown'" in str(error))
'''


def test_a_node_defined_in_a_script_runs_with_gv_run(tmp_path):
    (tmp_path / "script.py").write_text(SCRIPT)
    done = subprocess.run(
        [sys.executable, "script.py"], cwd=tmp_path, capture_output=True, text=True, timeout=120
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout.split("\n") == [
        "sync 0.75",
        "threads 0.75",
        "again 0.375",
        "unknown True",
        "",
    ]
