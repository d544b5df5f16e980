"""The pipeline file's structure: one pydantic model per section (``extra="forbid"``,
field descriptions as its documentation), and the JSON Schema published from them."""

from __future__ import annotations

from typing import Annotated, Any, Literal

from pydantic import BaseModel, BeforeValidator, ConfigDict, Field, StrictFloat, StringConstraints

from graphvision.graph.model import (
    NAME_PATTERN,
    REF_PATTERN,
)

__all__ = [
    "MAX_DEPTH",
    "MIN_VALUE_BUDGET",
    "Input",
    "InputModel",
    "Name",
    "NodeModel",
    "PipelineModel",
    "Reference",
    "pipeline_json_schema",
]

MAX_DEPTH = 64
"""Deepest nesting of mappings and sequences a pipeline file may have."""
MIN_VALUE_BUDGET = 100_000
"""Values a file may expand to through aliases, at least (10 per written value beyond)."""

Name = Annotated[str, StringConstraints(pattern=NAME_PATTERN)]
Reference = Annotated[str, StringConstraints(pattern=REF_PATTERN)]


_ONLY_NAMES: dict[str, Any] = {"additionalProperties": False}  # keys must match the name pattern


class _Section(BaseModel):
    model_config = ConfigDict(extra="forbid", populate_by_name=True)


class InputModel(_Section):
    type: str = Field(description="Port type of the input, e.g. Image, GrayImage, Float.")
    default: Any = Field(
        None, description="Value used when the run gives none: a literal, a path, or 'sample:NAME'."
    )
    description: str = Field("", description="What the input is for.")
    truth_of: list[Name] = Field(
        default_factory=list,
        min_length=1,
        description="Inputs this one is the ground truth of: its default holds for their "
        "defaults only, so when one of them is given and this one is not, the outputs that "
        "read it are skipped (one line says why).",
    )


def _type_shorthand(value: Any) -> Any:
    """``image: Image`` is short for ``image: {type: Image}``."""
    return {"type": value} if isinstance(value, str) else value


Input = Annotated[
    InputModel, BeforeValidator(_type_shorthand, json_schema_input_type=InputModel | str)
]


class NodeModel(_Section):
    op: str = Field(description="Id of the node to run, 'family.name' (see `graphvision nodes`).")
    in_: dict[str, Reference] = Field(
        default_factory=dict,
        alias="in",
        description="Input port -> 'node', 'node.port' or a graph input name.",
    )
    params: dict[str, Any] = Field(
        default_factory=dict,
        description="Node parameters; '${params.NAME}' substitutes a pipeline param.",
    )
    description: str = Field("", description="What this step does in the pipeline.")
    timeout: StrictFloat | None = Field(
        None,
        gt=0,
        allow_inf_nan=False,
        description="Seconds the node may run before it fails alone (the lower of this and "
        "--node-timeout applies).",
    )
    truth_of: list[Name] = Field(
        default_factory=list,
        min_length=1,
        description="Inputs whose defaults this node measures against a truth written into "
        "the pipeline: when one of them is given, the outputs that read this node are "
        "skipped (one line says why).",
    )
    backend: str | None = Field(
        None,
        description="Pin the backend that runs this node ('numpy', 'opencv', ...), "
        "whatever the run's lookup order.",
    )


class PipelineModel(_Section):
    version: Literal[1] = Field(1, description="Pipeline file format version.")
    name: str = Field(description="Name of the pipeline.")
    description: str = Field("", description="What the pipeline does.")
    plugins: list[str] = Field(
        default_factory=list, description="Local plugin files or folders, relative to this file."
    )
    backends: list[str] = Field(
        default_factory=list,
        description="Backend lookup order, e.g. [opencv, numpy]: each node runs with the "
        "first that implements its op (the reference, numpy, last). --backend overrides it.",
    )
    inputs: dict[Name, Input] = Field(
        default_factory=dict,
        description="Graph inputs: name -> {type, default} or a type name.",
        json_schema_extra=_ONLY_NAMES,
    )
    params: dict[str, Any] = Field(
        default_factory=dict, description="Pipeline-level values, used as '${params.NAME}'."
    )
    nodes: dict[Name, NodeModel] = Field(
        description="The steps, by name.", json_schema_extra=_ONLY_NAMES
    )
    outputs: dict[Name, Reference] = Field(
        description="Output name -> 'node' or 'node.port'; the name is the stem of its files.",
        json_schema_extra=_ONLY_NAMES,
    )


def pipeline_json_schema() -> dict[str, Any]:
    """JSON Schema of pipeline files (for editors and ``graphvision schema``)."""
    schema = PipelineModel.model_json_schema(by_alias=True)
    schema["$schema"] = "https://json-schema.org/draft/2020-12/schema"
    schema["title"] = "graphvision pipeline"
    return schema
