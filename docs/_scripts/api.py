"""The Python API page: every public name of ``graphvision`` (its ``__all__``).

Names are documented by mkdocstrings from their docstrings, under their
top-level name (``graphvision.run``), so the page does not depend on the module
a name lives in. A name no group below lists still appears, under "Other".
"""

from __future__ import annotations

import mkdocs_gen_files

import graphvision as gv

GROUPS: list[tuple[str, str, list[str]]] = [
    (
        "Building and reading pipelines",
        "A pipeline is a `Graph`; files are read and written by these functions.",
        [
            "Graph",
            "Ref",
            "load_pipeline",
            "parse_pipeline",
            "dump_pipeline",
            "pipeline_json_schema",
            "compile_graph",
            "CompiledGraph",
            "NAME_PATTERN",
            "REF_PATTERN",
        ],
    ),
    (
        "Running",
        "One run, a batch of files, a grid of parameters; what they return.",
        [
            "run",
            "RunResult",
            "RunRecord",
            "NodeRecord",
            "RunHooks",
            "run_batch",
            "BatchResult",
            "BatchItem",
            "sweep",
            "SweepResult",
            "SweepInterrupted",
            "rewrite_report",
        ],
    ),
    (
        "Nodes and plugins",
        "Writing nodes and finding them.",
        ["node", "source", "NodeSpec", "discover", "Needs", "Registry"],
    ),
    (
        "Cache",
        "",
        [
            "Cache",
            "MemoryStore",
            "DiskStore",
            "default_cache_dir",
            "CacheWarning",
            "NotACacheError",
        ],
    ),
    (
        "Executors",
        "",
        ["make_executor", "SyncExecutor", "DaskExecutor", "one_blas_thread"],
    ),
    (
        "Values",
        "Records shared by several families, and the image dtype policy for scripts.",
        ["KeypointSet", "MatchSet", "PinholeCamera", "BoxSet", "to_float_image"],
    ),
    (
        "Errors",
        "Every error a user can cause derives from `GraphvisionError`.",
        [
            "GraphvisionError",
            "PipelineError",
            "Problem",
            "InputError",
            "RunError",
            "NodeExecutionError",
            "ParameterError",
            "PortValueError",
            "UnknownNameError",
            "RegistrationError",
            "DuplicateNodeError",
            "PluginLoadError",
            "OutputFolderError",
        ],
    ),
]


def _alias_table(names: list[str]) -> list[str]:
    """Annotation aliases (``GrayImage``...) and port classes, as a table read from the package."""
    rows = ["| alias | port type | description |", "| --- | --- | --- |"]
    for name in names:
        port = gv.port_of(getattr(gv, name))
        if port is None:
            continue
        text = " ".join((port.description or "").split()).replace("|", "\\|")
        rows.append(f"| `{name}` | `{port.__name__}` | {text} |")
    return rows


def generate() -> None:
    public = list(gv.__all__)
    listed = {name for _, _, names in GROUPS for name in names}
    ports = [n for n in public if n.endswith("Port") and n not in listed]
    aliases = [
        n for n in public if n not in listed and n not in ports and gv.port_of(getattr(gv, n))
    ]
    other = [n for n in public if n not in listed and n not in ports and n not in aliases]
    lines = [
        "# Python API",
        "",
        "Everything below is importable from the top-level package:",
        "`import graphvision as gv`, then `gv.run`, `gv.Graph`, `gv.node`... The page is",
        "generated from `graphvision.__all__` and the docstrings, so it lists every",
        "public name. `graphvision.testing.check_plugin` is the one public function",
        "outside it (see [Writing a node](writing-a-node.md)).",
        "",
    ]
    for title, intro, names in GROUPS:
        present = [n for n in names if n in public]
        if not present:
            continue
        lines += [f"## {title}", ""]
        if intro:
            lines += [intro, ""]
        for name in present:
            lines += [f"::: graphvision.{name}", ""]
    lines += [
        "## Annotations for node signatures",
        "",
        "Each alias is `Annotated[value type, port type]`: a type checker sees the value,",
        "the registry the port type ([Conventions](conventions.md)).",
        "",
        *_alias_table(aliases),
        "",
        "## Port types",
        "",
        "Subclass `PortType` to add one (a plugin may).",
        "",
    ]
    for name in ["PortType", *[p for p in ports if p != "PortType"]]:
        lines += [f"::: graphvision.{name}", "    options:", "      members: false", ""]
    if other:
        lines += ["## Other", ""]
        for name in other:
            lines += [f"::: graphvision.{name}", ""]
    lines += ["## Testing plugins", "", "::: graphvision.testing.check_plugin", ""]
    with mkdocs_gen_files.open("reference/python-api.md", "w") as out:
        out.write("\n".join(lines))
