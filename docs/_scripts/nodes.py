"""The node reference: every op of the registry, with a picture from a gallery run."""

from __future__ import annotations

import importlib
import json
from collections import defaultdict
from typing import Any

import docstrings
import mkdocs_gen_files
import runs
from gallery import anchor, first_sentence

import graphvision as gv


def _family_doc(specs: list[gv.NodeSpec]) -> str:
    """The family package's docstring (first paragraphs), as Markdown."""
    module = specs[0].func.__module__
    parts = module.split(".")
    package = ".".join(parts[:2]) if parts[0] == "graphvision_plugins" else parts[0]
    try:
        doc = importlib.import_module(package).__doc__ or ""
    except ImportError:
        return ""
    return docstrings.blocks(docstrings.parse(doc).summary + "\n\n" + docstrings.parse(doc).body)


def _schema_type(schema: dict[str, Any]) -> str:
    if "anyOf" in schema:
        return " or ".join(_schema_type(s) for s in schema["anyOf"])
    if "enum" in schema:
        return " \\| ".join(f"`{json.dumps(v)}`" for v in schema["enum"])
    if "const" in schema:
        return f"`{json.dumps(schema['const'])}`"
    kind = schema.get("type", "any")
    if kind == "array":
        if "prefixItems" in schema:
            return "[" + ", ".join(_schema_type(s) for s in schema["prefixItems"]) + "]"
        if "items" in schema:
            return f"list of {_schema_type(schema['items'])}"
    return str(kind)


def _bounds(schema: dict[str, Any]) -> str:
    if "anyOf" in schema:
        return "; ".join(b for b in (_bounds(s) for s in schema["anyOf"]) if b)
    found = []
    for key, sign in (
        ("minimum", "≥"),
        ("exclusiveMinimum", ">"),
        ("maximum", "≤"),
        ("exclusiveMaximum", "<"),
        ("minLength", "length ≥"),
        ("maxLength", "length ≤"),
        ("minItems", "items ≥"),
        ("maxItems", "items ≤"),
    ):
        if key in schema:
            found.append(f"{sign} {schema[key]}")
    if "pattern" in schema:
        found.append(f"matches `{schema['pattern']}`")
    return ", ".join(found)


def _resolve(schema: dict[str, Any], root: dict[str, Any]) -> dict[str, Any]:
    ref = schema.get("$ref", "")
    if ref.startswith("#/$defs/"):
        return root.get("$defs", {}).get(ref.split("/")[-1], schema)
    return schema


def _described(doc: docstrings.Docstring, section: str) -> dict[str, docstrings.Entry]:
    return {name: entry for entry in doc.entries(section) for name in entry.names}


def _cell(text: str) -> str:
    return docstrings.inline(" ".join(text.split()), table=True) if text else ""


def _pictures(op: str) -> tuple[list[str], list[tuple[str, str, str, str]]]:
    """Pipelines using ``op`` and, from the first whose run gives one, each output's
    picture or value: (pipeline, node, port, "png:FILE" or "text:...")."""
    used: list[str] = []
    shown: list[tuple[str, str, str, str]] = []
    for run in runs.all_runs():
        users = [name for name, decl in run.graph.nodes.items() if decl.op == op]
        if not users:
            continue
        used.append(run.name)
        if shown or run.result is None:
            continue
        for node in users:
            for ref, (kind, value) in run.values.items():
                name, _, port = ref.partition(".")
                if name != node:
                    continue
                image = runs.picture(kind, value)
                if image is not None:
                    file = f"{op.replace('.', '/')}/{node}{'.' + port if port else ''}.png"
                    with mkdocs_gen_files.open(f"reference/nodes/{file}", "wb") as out:
                        out.write(runs.png(image, longest=480))
                    shown.append((run.name, node, port or "out", f"png:{file}"))
                elif runs.is_scalar(value):
                    shown.append((run.name, node, port or "out", f"text:{runs.scalar_text(value)}"))
                else:
                    shown.append((run.name, node, port or "out", f"text:{kind.summary(value)}"))
            if any(item[3].startswith("png:") for item in shown):
                break
    return used, shown


def op_section(spec: gv.NodeSpec, backends: dict[str, bool] | None = None) -> str:
    described = spec.describe()
    doc = docstrings.parse(described["doc"])
    params_doc = _described(doc, "Parameters")
    returns_doc = _described(doc, "Returns")
    lines = [f"## {spec.id} {{ #{anchor(spec.id)} }}", "", docstrings.inline(doc.summary), ""]
    if doc.body:
        lines += [docstrings.blocks(doc.body), ""]
    flags = f"version {spec.version}" + ("" if spec.cache else ", not cached")
    lines += [f"`{described['function']}` · plugin `{spec.plugin}` · {flags}", ""]
    if backends and len(backends) > 1:  # more implementations than the reference
        names = ", ".join(f"`{b}`" for b in backends)
        rule = spec.conformance
        agree = f"; they agree by {rule.metric} within {rule.tolerance:g}" if rule else ""
        lines += [f"Backends: {names}{agree}. {rule.note if rule else ''}".rstrip(), ""]
    if described["inputs"]:
        lines += ["| input | port type | description |", "| --- | --- | --- |"]
        for name, port in described["inputs"].items():
            entry = params_doc.get(name)
            optional = " (optional)" if port["optional"] else ""
            text = _cell(entry.text or entry.kind) if entry else ""
            lines.append(f"| `{name}`{optional} | `{port['type']}` | {text} |")
        lines.append("")
    lines += ["| output | port type | description |", "| --- | --- | --- |"]
    for name, kind in described["outputs"].items():
        entry = returns_doc.get(name) or (
            next(iter(returns_doc.values()))
            if len(described["outputs"]) == 1 and returns_doc
            else None
        )
        text = _cell(" ".join(x for x in (entry.kind, entry.text) if x)) if entry else ""
        lines.append(f"| `{name}` | `{kind}` | {text} |")
    lines.append("")
    schema = described["params"]
    properties = schema.get("properties", {})
    if properties:
        lines += [
            "| parameter | type | default | bounds | description |",
            "| --- | --- | --- | --- | --- |",
        ]
        for name, prop in properties.items():
            prop = _resolve(prop, schema)
            entry = params_doc.get(name)
            text = _cell(entry.text if entry else prop.get("description", ""))
            default = f"`{json.dumps(prop['default'])}`" if "default" in prop else "(required)"
            lines.append(
                f"| `{name}` | {_schema_type(prop)} | {default} | {_bounds(prop)} | {text} |"
            )
        lines += ["", '??? note "Parameters as JSON schema"', "", "    ```json"]
        lines += ["    " + line for line in json.dumps(schema, indent=2).splitlines()]
        lines += ["    ```", ""]
    raises = doc.entries("Raises")
    if raises:
        lines += ["**Raises**", ""]
        lines += [
            f"- `{', '.join(e.names)}`: {docstrings.inline(' '.join(e.text.split()))}"
            for e in raises
        ]
        lines.append("")
    for section in ("Notes", "Examples"):
        if section in doc.sections:
            lines += [f"**{section}**", "", docstrings.blocks(doc.sections[section]), ""]
    papers = docstrings.references(doc.sections.get("References", ""))
    if papers:
        lines += ["**References**", ""]
        lines += [f"{i}. {paper}" for i, paper in enumerate(papers, 1)]
        lines.append("")
    used, shown = _pictures(spec.id)
    if used:
        links = ", ".join(f"[{name}](../../gallery/{name}.md)" for name in used)
        lines += [f"**In the gallery:** {links}.", ""]
    else:
        lines += ["*No shipped pipeline uses this op.*", ""]
    pictures = [s for s in shown if s[3].startswith("png:")]
    texts = [s for s in shown if s[3].startswith("text:")]
    if pictures:
        lines.append('<div class="gv-figures" markdown>')
        for pipeline, node, port, what in pictures:
            lines += [
                '<figure markdown="span">',
                f"  ![{node}.{port}]({what[4:]})",
                f"  <figcaption>{pipeline}: {node}.{port}</figcaption>",
                "</figure>",
            ]
        lines += ["</div>", ""]
    if texts:
        pipeline = texts[0][0]
        lines += [f"In the [{pipeline}](../../gallery/{pipeline}.md) run:", ""]
        lines += [f"- `{node}.{port}`: {_cell(what[5:])}" for _, node, port, what in texts]
        lines.append("")
    return "\n".join(lines)


def generate() -> None:
    registry = runs.registry()
    families: dict[str, list[gv.NodeSpec]] = defaultdict(list)
    for op in sorted(registry.nodes):
        families[registry.nodes[op].family].append(registry.nodes[op])
    index = [
        "# Nodes",
        "",
        "Every op the installed plugins register (`gv.discover()`), written from the",
        "registry when this site was built: ports and their types, parameters with",
        "bounds and defaults (each op's JSON schema), the docstring with its formulas",
        "and papers, and a picture of the op's output from a [gallery](../../gallery/index.md)",
        "run that uses it. `graphvision nodes` and `graphvision describe OP` print the same.",
        "",
        "| family | ops | |",
        "| --- | ---: | --- |",
    ]
    summary = ["* [Nodes](index.md)"]
    for family, specs in families.items():
        intro = _family_doc(specs)
        page = [f"# {family}", ""]
        if intro:
            page += [intro, ""]
        page += ["| op | summary |", "| --- | --- |"]
        page += [f"| [`{s.id}`](#{anchor(s.id)}) | {_cell(s.summary)} |" for s in specs]
        page.append("")
        page += [op_section(spec, registry.backends_of(spec.id)) for spec in specs]
        with mkdocs_gen_files.open(f"reference/nodes/{family}.md", "w") as out:
            out.write("\n".join(page))
        first = _cell(first_sentence(docstrings.parse(intro).summary)) if intro else ""
        index.append(f"| [{family}]({family}.md) | {len(specs)} | {first} |")
        summary.append(f"* [{family}]({family}.md)")
    with mkdocs_gen_files.open("reference/nodes/index.md", "w") as out:
        out.write("\n".join(index) + "\n")
    with mkdocs_gen_files.open("reference/nodes/SUMMARY.md", "w") as out:
        out.write("\n".join(summary) + "\n")
