"""graphvision: a dataflow engine for classical computer vision.

Typed nodes in a plugin registry, pipelines as YAML or Python graphs, a
parallel scheduler, and a Merkle-keyed cache so that changing one parameter
recomputes only what depends on it. The engine holds no vision algorithm: the
algorithms are plugins (``graphvision_plugins`` ships the built-in ones).

Importing the package is cheap: each public name is imported from its module
on first use (PEP 562), so ``graphvision --help`` does not pay for NumPy,
pydantic and YAML. The ``TYPE_CHECKING`` block below is the one list of
public names: type checkers read it, and :func:`__getattr__` reads it too.
"""

from __future__ import annotations

import ast
import importlib
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from graphvision.cache.disk import DiskStore
    from graphvision.cache.entries import CacheWarning, NotACacheError
    from graphvision.cache.memory_store import MemoryStore
    from graphvision.cache.shared import FsspecStore
    from graphvision.cache.store import Cache
    from graphvision.compiler.compile import CompiledGraph, compile_graph
    from graphvision.errors import (
        DuplicateNodeError,
        FileWriteError,
        GraphvisionError,
        InputError,
        NodeExecutionError,
        OutputFolderError,
        ParameterError,
        PipelineError,
        PluginLoadError,
        PortValueError,
        Problem,
        RegistrationError,
        RunError,
        UnknownNameError,
    )
    from graphvision.execution.batch_files import BatchItem, BatchResult
    from graphvision.execution.blas import one_blas_thread
    from graphvision.execution.dask import DaskExecutor
    from graphvision.execution.executors import SyncExecutor, make_executor
    from graphvision.execution.limits import NodeLimitError
    from graphvision.execution.record import NodeRecord, RunHooks, RunRecord, RunResult
    from graphvision.execution.run import run
    from graphvision.execution.sweep import SweepInterrupted, SweepResult, sweep
    from graphvision.execution.truth import MissingTruthWarning
    from graphvision.graph.model import NAME_PATTERN, REF_PATTERN, Graph, Ref
    from graphvision.graph.pipeline_file import dump_pipeline, load_pipeline, parse_pipeline
    from graphvision.graph.schema import pipeline_json_schema
    from graphvision.locations import default_cache_dir
    from graphvision.nodes.backends import implements
    from graphvision.nodes.marks import Conformance
    from graphvision.nodes.node import node, source
    from graphvision.nodes.plugins import Needs, discover
    from graphvision.nodes.registry import Registry
    from graphvision.nodes.spec import NodeSpec
    from graphvision.studio.server import StudioServer, studio  # the package, callable
    from graphvision.types import (
        AnyImageT,
        Array,
        BinaryImage,
        Bool,
        Boxes,
        Camera,
        ColorImage,
        Descriptors,
        Float,
        FloatImage,
        GrayImage,
        Homography,
        Image,
        ImageT,
        Int,
        Kernel,
        Keypoints,
        LabelImage,
        Matches,
        Points2D,
        Points3D,
        Table,
        Text,
        port_of,
    )
    from graphvision.values.budget import check_array_file, check_pixels, max_pixels
    from graphvision.values.dtype_policy import to_float_image
    from graphvision.values.file_bytes import read_file_bytes
    from graphvision.values.geometry import (
        DescriptorsPort,
        HomographyPort,
        Points2DPort,
        Points3DPort,
    )
    from graphvision.values.images import (
        BinaryImagePort,
        ColorImagePort,
        FloatImagePort,
        GrayImagePort,
        ImagePort,
        KernelPort,
        LabelImagePort,
    )
    from graphvision.values.ports import ArrayPort, PortType, RecordPort
    from graphvision.values.records import (
        BoxesPort,
        BoxSet,
        CameraPort,
        KeypointSet,
        KeypointsPort,
        MatchesPort,
        MatchSet,
        PinholeCamera,
    )
    from graphvision.values.scalars import BoolPort, FloatPort, IntPort, TablePort, TextPort
    from graphvision.views.batch_page import run_batch
    from graphvision.views.report import rewrite_report


def _public_names() -> dict[str, str]:
    """Public name → module, read from this file's ``TYPE_CHECKING`` block."""
    tree = ast.parse(Path(__file__).read_text(encoding="utf-8"))
    block = next(
        n for n in tree.body if isinstance(n, ast.If) and "TYPE_CHECKING" in ast.dump(n.test)
    )
    return {
        alias.name: "." * item.level + (item.module or "")
        for item in block.body
        if isinstance(item, ast.ImportFrom)
        for alias in item.names
    }


_WHERE: dict[str, str] = {}


def __getattr__(name: str) -> Any:
    if not _WHERE:
        _WHERE.update(_public_names())
    if name not in _WHERE:
        raise AttributeError(f"module 'graphvision' has no attribute '{name}'")
    value = getattr(importlib.import_module(_WHERE[name], __name__), name)
    globals()[name] = value  # later look-ups are plain attribute reads
    if "IPython" in sys.modules and not _WHERE.get("__notebook__"):  # inside a kernel:
        _WHERE["__notebook__"] = "registered"  # results show their report page inline
        from graphvision.views.notebook import register

        register()
    return value


def __dir__() -> list[str]:
    return list(__all__)


__all__ = [
    "NAME_PATTERN",
    "REF_PATTERN",
    "AnyImageT",
    "Array",
    "ArrayPort",
    "BatchItem",
    "BatchResult",
    "BinaryImage",
    "BinaryImagePort",
    "Bool",
    "BoolPort",
    "BoxSet",
    "Boxes",
    "BoxesPort",
    "Cache",
    "CacheWarning",
    "Camera",
    "CameraPort",
    "ColorImage",
    "ColorImagePort",
    "CompiledGraph",
    "Conformance",
    "DaskExecutor",
    "Descriptors",
    "DescriptorsPort",
    "DiskStore",
    "DuplicateNodeError",
    "FileWriteError",
    "Float",
    "FloatImage",
    "FloatImagePort",
    "FloatPort",
    "FsspecStore",
    "Graph",
    "GraphvisionError",
    "GrayImage",
    "GrayImagePort",
    "Homography",
    "HomographyPort",
    "Image",
    "ImagePort",
    "ImageT",
    "InputError",
    "Int",
    "IntPort",
    "Kernel",
    "KernelPort",
    "KeypointSet",
    "Keypoints",
    "KeypointsPort",
    "LabelImage",
    "LabelImagePort",
    "MatchSet",
    "Matches",
    "MatchesPort",
    "MemoryStore",
    "MissingTruthWarning",
    "Needs",
    "NodeExecutionError",
    "NodeLimitError",
    "NodeRecord",
    "NodeSpec",
    "NotACacheError",
    "OutputFolderError",
    "ParameterError",
    "PinholeCamera",
    "PipelineError",
    "PluginLoadError",
    "Points2D",
    "Points2DPort",
    "Points3D",
    "Points3DPort",
    "PortType",
    "PortValueError",
    "Problem",
    "RecordPort",
    "Ref",
    "RegistrationError",
    "Registry",
    "RunError",
    "RunHooks",
    "RunRecord",
    "RunResult",
    "StudioServer",
    "SweepInterrupted",
    "SweepResult",
    "SyncExecutor",
    "Table",
    "TablePort",
    "Text",
    "TextPort",
    "UnknownNameError",
    "check_array_file",
    "check_pixels",
    "compile_graph",
    "default_cache_dir",
    "discover",
    "dump_pipeline",
    "implements",
    "load_pipeline",
    "make_executor",
    "max_pixels",
    "node",
    "one_blas_thread",
    "parse_pipeline",
    "pipeline_json_schema",
    "port_of",
    "read_file_bytes",
    "rewrite_report",
    "run",
    "run_batch",
    "source",
    "studio",
    "sweep",
    "to_float_image",
]
