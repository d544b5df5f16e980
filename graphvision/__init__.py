"""graphvision: a dataflow engine for classical computer vision.

Typed nodes in a plugin registry, pipelines as YAML or Python graphs, a
parallel scheduler, and a Merkle-keyed cache so that changing one parameter
recomputes only what depends on it. The engine holds no vision algorithm: the
algorithms are plugins (``graphvision_plugins`` ships the built-in ones).
"""

from ._cache import Cache, CacheWarning, DiskStore, MemoryStore, default_cache_dir
from ._compile import CompiledGraph, compile_graph
from ._errors import (
    DuplicateNodeError,
    GraphvisionError,
    InputError,
    NodeExecutionError,
    PipelineError,
    PluginLoadError,
    PortValueError,
    Problem,
    RegistrationError,
    RunError,
    UnknownNameError,
)
from ._executors import SyncExecutor, make_executor
from ._graph import Graph, Ref
from ._node import NodeSpec, node, source
from ._pipeline_file import dump_pipeline, load_pipeline, parse_pipeline, pipeline_json_schema
from ._plugins import discover
from ._ports import (
    Array,
    BinaryImage,
    Bool,
    ColorImage,
    Descriptors,
    Float,
    FloatImage,
    GrayImage,
    Homography,
    Image,
    Int,
    Kernel,
    LabelImage,
    Points2D,
    PortType,
    Record,
    Table,
    Text,
)
from ._records import Keypoints, KeypointSet, Matches, MatchSet
from ._registry import Registry
from ._run import NodeRecord, RunHooks, RunRecord, RunResult, run

__all__ = [
    "Array",
    "BinaryImage",
    "Bool",
    "Cache",
    "CacheWarning",
    "ColorImage",
    "CompiledGraph",
    "Descriptors",
    "DiskStore",
    "DuplicateNodeError",
    "Float",
    "FloatImage",
    "Graph",
    "GraphvisionError",
    "GrayImage",
    "Homography",
    "Image",
    "InputError",
    "Int",
    "Kernel",
    "KeypointSet",
    "Keypoints",
    "LabelImage",
    "MatchSet",
    "Matches",
    "MemoryStore",
    "NodeExecutionError",
    "NodeRecord",
    "NodeSpec",
    "PipelineError",
    "PluginLoadError",
    "Points2D",
    "PortType",
    "PortValueError",
    "Problem",
    "Record",
    "Ref",
    "RegistrationError",
    "Registry",
    "RunError",
    "RunHooks",
    "RunRecord",
    "RunResult",
    "SyncExecutor",
    "Table",
    "Text",
    "UnknownNameError",
    "compile_graph",
    "default_cache_dir",
    "discover",
    "dump_pipeline",
    "load_pipeline",
    "make_executor",
    "node",
    "parse_pipeline",
    "pipeline_json_schema",
    "run",
    "source",
]
