"""The gallery: one page per shipped pipeline, from its run in this build."""

from __future__ import annotations

import html
import re
from typing import Any

import mkdocs_gen_files
import runs

import graphvision as gv


def render_svg(graph: gv.Graph) -> str:
    """The graph's drawing: ``gv.render`` where the package exports it, else its notebook view."""
    render = getattr(gv, "render", None)
    return render(graph, "svg") if render is not None else graph._repr_svg_()


def op_link(op: str, depth: int) -> str:
    """A link from a page ``depth`` folders deep to the op's entry in the node reference."""
    family = op.split(".", 1)[0]
    up = "../" * depth
    return f"[`{op}`]({up}reference/nodes/{family}.md#{anchor(op)})"


def anchor(op: str) -> str:
    return "op-" + re.sub(r"[^a-z0-9]+", "-", op.lower())


def first_sentence(text: str) -> str:
    text = " ".join(text.split())
    match = re.match(r"(.+?[.:;])(\s|$)", text)
    return match.group(1) if match else text


def _cell(text: str) -> str:
    return text.replace("|", "\\|").replace("\n", " ")


def _value_cell(value: Any) -> str:
    if isinstance(value, str):
        return f"`{_cell(value)}`"
    return f"`{_cell(repr(value))}`"


def pictures(run: runs.PipelineRun) -> list[tuple[str, str]]:
    """(output name, file name) of each output with a picture, written beside the page."""
    shown = []
    assert run.result is not None
    for name, value in run.result.outputs.items():
        kind = run.result.compiled.output_type(name)
        image = runs.picture(kind, value)
        if image is None:
            continue
        file = f"{run.name}/{name}.png"
        with mkdocs_gen_files.open(f"gallery/{file}", "wb") as out:
            out.write(runs.png(image))
        shown.append((name, file))
    return shown


def headline(run: runs.PipelineRun) -> list[tuple[str, str]]:
    """(output, value) of every scalar output, as the run produced it."""
    assert run.result is not None
    return [
        (name, runs.scalar_text(value))
        for name, value in run.result.outputs.items()
        if runs.is_scalar(value)
    ]


def page(run: runs.PipelineRun) -> str:
    graph = run.graph
    lines = [f"# {run.name}", ""]
    if graph.description:
        lines += [" ".join(graph.description.split()), ""]
    lines += [
        "```sh",
        f"graphvision run pipelines/{run.path.name} -d out/{run.name}",
        "```",
        "",
        '<div class="gv-graph" markdown>',
        f"![The graph of {run.name}]({run.name}/graph.svg)",
        "</div>",
        "",
    ]
    with mkdocs_gen_files.open(f"gallery/{run.name}/graph.svg", "w") as out:
        out.write(render_svg(graph))
    if run.result is None:
        lines += ['!!! failure "This pipeline failed in the documentation build"', ""]
        lines += ["    ```text", *("    " + x for x in run.error.splitlines()), "    ```", ""]
        return "\n".join(lines)
    figures = headline(run)
    if figures:
        lines += ["## Headline figures", "", "| output | value |", "| --- | ---: |"]
        lines += [f"| `{name}` | {value} |" for name, value in figures]
        lines.append("")
    shown = pictures(run)
    if shown:
        lines += ["## Pictures", "", '<div class="gv-figures" markdown>']
        for name, file in shown:
            lines += [
                '<figure markdown="span">',
                f"  ![{name}]({file})",
                f"  <figcaption>{html.escape(name)}</figcaption>",
                "</figure>",
            ]
        lines += ["</div>", ""]
    others = [
        (name, run.result.compiled.output_type(name), value)
        for name, value in run.result.outputs.items()
        if not runs.is_scalar(value) and name not in dict(shown)
    ]
    if others:
        lines += ["## Other outputs", "", "| output | port type | value |", "| --- | --- | --- |"]
        for name, kind, value in others:
            lines.append(f"| `{name}` | `{kind.type_name()}` | {_cell(kind.summary(value))} |")
        lines.append("")
    lines += _inputs_and_params(graph)
    lines += _nodes(run)
    source = run.path.read_text(encoding="utf-8")
    lines += [f'??? example "pipelines/{run.path.name}"', "", "    ```yaml"]
    lines += ["    " + line if line else "" for line in source.splitlines()]
    lines += ["    ```", ""]
    return "\n".join(lines)


def _inputs_and_params(graph: gv.Graph) -> list[str]:
    lines = []
    if graph.inputs:
        lines += ["## Inputs", "", "| input | type | default |", "| --- | --- | --- |"]
        for name, decl in graph.inputs.items():
            default = _value_cell(decl.default) if decl.default is not None else "(required)"
            lines.append(f"| `{name}` | `{decl.type}` | {default} |")
        lines.append("")
    if graph.params:
        lines += ["Pipeline parameters (`-s params.NAME=VALUE` to change one):", ""]
        lines += ["| parameter | value |", "| --- | --- |"]
        lines += [f"| `{name}` | {_value_cell(v)} |" for name, v in graph.params.items()]
        lines.append("")
    return lines


def _nodes(run: runs.PipelineRun) -> list[str]:
    assert run.result is not None
    record = run.result.record
    counts: dict[str, int] = {}
    for node in record.nodes:
        counts[node.status] = counts.get(node.status, 0) + 1
    done = ", ".join(f"{n} {status}" for status, n in sorted(counts.items()))
    lines = [
        "## Nodes",
        "",
        f"In this build's run ({done}; `cached` means loaded from the cache a previous",
        "build filled, bit for bit the value computed):",
        "",
        "| node | op | status |",
        "| --- | --- | --- |",
    ]
    for node in record.nodes:
        lines.append(f"| `{node.name}` | {op_link(node.op, 1)} | {node.status} |")
    lines.append("")
    return lines


def generate() -> None:
    all_runs = runs.all_runs()
    index = [
        "# Gallery",
        "",
        "Every pipeline shipped in `pipelines/`, run when this site was built. Each page",
        "shows the graph, the pictures and the scalar outputs of that run: none is typed",
        "by hand, so none can go stale.",
        "",
        "| pipeline | what it does | headline figures |",
        "| --- | --- | --- |",
    ]
    summary = ["* [Gallery](index.md)"]
    for run in all_runs:
        with mkdocs_gen_files.open(f"gallery/{run.name}.md", "w") as out:
            out.write(page(run))
        figures = headline(run)[:3] if run.result is not None else [("failed", "")]
        shown = "<br>".join(f"`{name}` {value}" for name, value in figures)
        what = _cell(first_sentence(run.graph.description))
        index.append(f"| [{run.name}]({run.name}.md) | {what} | {shown} |")
        summary.append(f"* [{run.name}]({run.name}.md)")
    with mkdocs_gen_files.open("gallery/index.md", "w") as out:
        out.write("\n".join(index) + "\n")
    with mkdocs_gen_files.open("gallery/SUMMARY.md", "w") as out:
        out.write("\n".join(summary) + "\n")
