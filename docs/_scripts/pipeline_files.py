"""The pipeline-file reference's generated half: a validation run, and every field."""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Any

import mkdocs_gen_files

import graphvision as gv

BROKEN = """\
version: 1
name: broken
inputs:
  photo: {type: ColorImage, default: "sample:astronaut"}
nodes:
  a:      {op: filters.gaussian, in: {image: b}}
  b:      {op: filters.gaussian, in: {image: a}}
  blur:   {op: filters.gausian, in: {image: photo}}
  median: {op: filters.median, in: {image: photo}, params: {size: 4}}
  otsu:   {op: threshold.otsu, in: {image: photo}}
outputs:
  mask: otsu.mask
  smooth: a
"""


def validation_example() -> list[str]:
    with tempfile.TemporaryDirectory() as folder:
        Path(folder, "broken.yaml").write_text(BROKEN, encoding="utf-8")
        done = subprocess.run(
            [sys.executable, "-m", "graphvision", "validate", "broken.yaml"],
            cwd=folder,
            capture_output=True,
            text=True,
            env={**os.environ, "COLUMNS": "100"},
        )
    said = (done.stdout + done.stderr).strip()
    return [
        "For this file,",
        "",
        '```yaml title="broken.yaml"',
        BROKEN.rstrip(),
        "```",
        "",
        f"`graphvision validate broken.yaml` says (exit status {done.returncode}; run when",
        "this site was built):",
        "",
        "```text",
        f"$ graphvision validate broken.yaml\n{said}",
        "```",
        "",
    ]


def _fields(schema: dict[str, Any], model: dict[str, Any], where: str) -> list[str]:
    rows = []
    required = set(model.get("required", []))
    for name, field in model.get("properties", {}).items():
        text = " ".join(str(field.get("description", "")).split()).replace("|", "\\|")
        need = "required" if name in required else ""
        rows.append(f"| `{where}{name}` | {need} | {text} |")
    return rows


def field_table() -> list[str]:
    schema = gv.pipeline_json_schema()
    rows = ["| key | | meaning |", "| --- | --- | --- |"]
    rows += _fields(schema, schema, "")
    for name, model in schema.get("$defs", {}).items():
        where = {"InputModel": "inputs.NAME.", "NodeModel": "nodes.NAME."}.get(name)
        if where:
            rows += _fields(schema, model, where)
    return [
        "## Every key",
        "",
        "Read from `gv.pipeline_json_schema()` when this site was built.",
        "",
        *rows,
        "",
    ]


def generate() -> None:
    with mkdocs_gen_files.open("reference/pipeline-files.md", "a") as out:
        out.write("\n" + "\n".join(validation_example() + field_table()))
