"""Run every shipped pipeline once for the documentation build.

The gallery and the node reference show what these runs produce: pictures of
outputs and intermediate values, and the scalar outputs as headline figures.
Nothing here is typed by hand; it uses only the public API (``import
graphvision as gv``). Runs go through the disk cache (``$GRAPHVISION_CACHE_DIR``
or ``~/.cache/graphvision``) unless ``GRAPHVISION_DOCS_CACHE=off``, so a
second build loads the values a first one computed (bit for bit the same).
"""

from __future__ import annotations

import io
import os
import time
from dataclasses import dataclass, field
from functools import cache
from pathlib import Path
from typing import Any

import numpy as np

import graphvision as gv

ROOT = Path(__file__).resolve().parents[2]
PIPELINES = ROOT / "pipelines"


@dataclass
class PipelineRun:
    """One pipeline's run: its graph, outputs, intermediate values, record and time."""

    path: Path
    graph: gv.Graph
    result: gv.RunResult | None
    error: str = ""
    seconds: float = 0.0
    # "node" or "node.port" -> (port type, value), outputs and intermediates alike
    values: dict[str, tuple[type[gv.PortType], Any]] = field(default_factory=dict)

    @property
    def name(self) -> str:
        return self.path.stem


def docs_cache() -> gv.Cache | None:
    """The build's cache: ``$GRAPHVISION_DOCS_CACHE_DIR`` or ``.graphvision-cache/docs``."""
    if os.environ.get("GRAPHVISION_DOCS_CACHE", "").lower() in {"off", "0", "no"}:
        return None
    folder = os.environ.get("GRAPHVISION_DOCS_CACHE_DIR") or ROOT / ".graphvision-cache" / "docs"
    return gv.Cache(gv.MemoryStore(), gv.DiskStore(folder))


def _every_port(graph: gv.Graph, registry: gv.Registry) -> dict[str, str]:
    """Extra output name -> "node" or "node.port", for every node port not yet an output."""
    named = {str(ref) for ref in graph.outputs.values()}
    extra = {}
    for node, decl in graph.nodes.items():
        ports = list(registry.nodes[decl.op].outputs)
        for port in ports:
            ref = node if ports == ["out"] else f"{node}.{port}"
            if ref not in named:
                extra[f"docs__{node}__{port}"] = ref
    return extra


def run_pipeline(path: Path, registry: gv.Registry, cache: gv.Cache | None) -> PipelineRun:
    """Run ``path`` asking for every node's every output, so that a warm build (values
    loaded from the cache) shows the same intermediate pictures as a cold one."""
    graph = gv.load_pipeline(path)
    full = gv.load_pipeline(path)
    extra = _every_port(full, registry)
    for name, ref in extra.items():
        full.output(name, ref)
    start = time.perf_counter()
    try:
        result = gv.run(full, registry, cache=cache)
    except gv.GraphvisionError as error:  # shown on the page; the build goes on
        return PipelineRun(path, graph, None, str(error), time.perf_counter() - start)
    seconds = time.perf_counter() - start
    values: dict[str, tuple[type[gv.PortType], Any]] = {}
    for name, value in result.outputs.items():
        values[str(full.outputs[name])] = (result.compiled.output_type(name), value)
    result.outputs = {name: v for name, v in result.outputs.items() if name not in extra}
    return PipelineRun(path, graph, result, "", seconds, values)


@cache
def registry() -> gv.Registry:
    return gv.discover()


@cache
def all_runs() -> tuple[PipelineRun, ...]:
    """Every pipeline in pipelines/, run once per build (sorted by file name)."""
    cache_ = docs_cache()
    return tuple(
        run_pipeline(path, registry(), cache_) for path in sorted(PIPELINES.glob("*.yaml"))
    )


def picture(kind: type, value: Any) -> np.ndarray | None:
    """The port type's own picture of a value (as in report.html), or None."""
    try:
        shown = kind.preview(value)  # type: ignore[attr-defined]
    except Exception:  # a value without a picture is shown as text instead
        return None
    if shown is None:
        return None
    shown = np.asarray(shown)
    if shown.ndim not in (2, 3) or min(shown.shape[:2]) < 1:
        return None
    return shown


def png(image: np.ndarray, longest: int = 640, smallest: int = 64) -> bytes:
    """PNG bytes of a [0, 1] picture, shrunk to ``longest`` pixels, tiny ones enlarged."""
    from PIL import Image

    data = np.clip(np.nan_to_num(np.asarray(image, np.float32)), 0.0, 1.0)
    pil = Image.fromarray(np.round(data * 255).astype(np.uint8))
    scale = longest / max(pil.size)
    if scale < 1:
        pil = pil.resize(
            (max(1, round(pil.width * scale)), max(1, round(pil.height * scale))),
            Image.Resampling.LANCZOS,
        )
    elif min(pil.size) < smallest:
        factor = -(-smallest // min(pil.size))
        pil = pil.resize((pil.width * factor, pil.height * factor), Image.Resampling.NEAREST)
    buffer = io.BytesIO()
    pil.save(buffer, format="PNG", optimize=True)
    return buffer.getvalue()


def is_scalar(value: Any) -> bool:
    return isinstance(value, (bool, int, float, np.integer, np.floating)) or (
        isinstance(value, np.ndarray) and value.ndim == 0
    )


def scalar_text(value: Any) -> str:
    """A scalar as the page shows it: 4 significant digits for floats."""
    if isinstance(value, np.ndarray):
        value = value.item()
    if isinstance(value, (bool, np.bool_)):
        return str(bool(value))
    if isinstance(value, (int, np.integer)):
        return f"{int(value):,}"
    value = float(value)
    if not np.isfinite(value):
        return str(value)
    return f"{value:.4g}"
