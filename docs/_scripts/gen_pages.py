"""Generate the documentation's pages from real runs and from the registry (mkdocs-gen-files).

- ``gallery/``: every pipeline in pipelines/ is run (``gv.run``); its page shows
  the graph (``gv.render(graph, "svg")``), its pictures, its scalar outputs and
  how each node went.
- ``reference/nodes/``: every op of the registry (``gv.discover()``): ports, port
  types, parameters with bounds and defaults (its JSON schema), the docstring
  with its formulas and papers, and a picture of its output from a gallery run.
- ``reference/python-api.md``: every name of ``graphvision.__all__``.
- ``benchmarks.md``: ``bench/results/latest.md`` as ``make bench`` wrote it.
- ``reference/cli.md``: each command's ``--help``, appended.
- ``reference/pipeline-files.md``: a validation run and every key of the format.
- ``reference/trust-and-errors.md``: the exception hierarchy.
- ``architecture.md``: the layers drawn from the import-linter contracts of
  pyproject.toml, and the engine's modules listed from their docstrings.

Nothing here is typed by hand: a figure on a generated page comes from a run of
this build (or from bench/results/latest.md).
"""

from __future__ import annotations

import logging
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))

import api
import architecture
import benchmarks
import cli_help
import errors_tree
import gallery
import nodes
import pipeline_files

log = logging.getLogger("mkdocs.plugins.graphvision")
for part in (gallery, nodes, api, benchmarks, architecture, cli_help, pipeline_files, errors_tree):
    began = time.perf_counter()
    part.generate()
    log.info("graphvision docs: %s generated in %.1f s", part.__name__, time.perf_counter() - began)
