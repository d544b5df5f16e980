"""The architecture page's generated half: the layers drawn, the modules listed.

The layers are read from the import-linter ``layers`` contract of pyproject.toml
(the one ``make lint`` checks), so the drawing is the rule the build enforces.
Without such a contract the engine's subpackages are drawn in the order the
layout plans (``PLANNED``). The module table is read from the source files.
"""

from __future__ import annotations

import ast
import html
import tomllib

import mkdocs_gen_files
import runs

ENGINE = runs.ROOT / "graphvision"
# Bottom to top, as the layout plans it; used only when pyproject.toml declares no layers.
PLANNED = ["errors", "values", "graph", "nodes", "compiler", "cache", "execution", "views", "cli"]


def contract_layers() -> tuple[list[list[str]], str]:
    """Layers from top to bottom (each a list of sibling modules) and where they came from."""
    config = tomllib.loads((runs.ROOT / "pyproject.toml").read_text(encoding="utf-8"))
    contracts = config.get("tool", {}).get("importlinter", {}).get("contracts", [])
    for contract in contracts:
        if contract.get("type") == "layers" and any(
            "graphvision" in str(layer) for layer in contract.get("layers", [])
        ):
            layers = []
            for layer in contract["layers"]:
                names = [n.strip().strip("()") for n in str(layer).replace(":", "|").split("|")]
                layers.append([n.removeprefix("graphvision.") for n in names if n])
            name = contract.get("name", "layers")
            return layers, f"the import-linter contract “{name}” in pyproject.toml"
    found = {p.name for p in ENGINE.iterdir() if (p / "__init__.py").exists()}
    layers = [[name] for name in reversed(PLANNED) if name in found]
    if layers:
        return layers, "the engine's subpackages, in the order the layout plans"
    return [[name] for name in reversed(PLANNED)], "the planned layout (not yet in the tree)"


def _modules(package: str) -> list[str]:
    """The modules of a subpackage (a module layer is its own one)."""
    folder = ENGINE / package.replace(".", "/")
    if folder.is_dir():
        return sorted(p.stem for p in folder.glob("*.py") if p.stem != "__init__")
    return [package] if folder.with_suffix(".py").exists() else []


def _wrapped(names: list[str], chars: int) -> list[str]:
    lines = [""]
    for name in names:
        piece = name if not lines[-1] else f", {name}"
        if lines[-1] and len(lines[-1]) + len(piece) > chars:
            lines[-1] += ","
            lines.append(name)
        else:
            lines[-1] += piece
    return lines


def layers_svg(layers: list[list[str]]) -> str:
    """Boxes stacked top to bottom, siblings side by side, each listing its modules."""
    width, gap, left = 720, 14, 40
    boxes = []  # per layer: (box width, [(name, module lines)]), its height
    for layer in layers:
        box = (width - left - 10 - (len(layer) - 1) * 10) / len(layer)
        chars = int(box / 6.4) - 3
        rows = [(name, _wrapped(_modules(name), chars)) for name in layer]
        tallest = max(len(lines) for _, lines in rows)
        boxes.append((box, rows, 34 + 15 * tallest))
    height = sum(row for _, _, row in boxes) + gap * len(boxes) + 10
    out = [
        f'<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" '
        f'viewBox="0 0 {width} {height}" font-family="sans-serif" font-size="13">',
        '<defs><marker id="a" viewBox="0 0 10 10" refX="9" refY="5" markerWidth="7" '
        'markerHeight="7" orient="auto"><path d="M0,0 L10,5 L0,10 z" fill="#555"/></marker></defs>',
        f'<line x1="18" y1="20" x2="18" y2="{height - 20}" stroke="#555" stroke-width="2" '
        'marker-end="url(#a)"/>',
        f'<text x="12" y="{height / 2}" transform="rotate(-90 12 {height / 2})" '
        'text-anchor="middle" fill="#555" font-size="11">imports go down only</text>',
    ]
    y = 10
    for i, (box, rows, row) in enumerate(boxes):
        shade = 0.92 - 0.5 * i / max(1, len(boxes) - 1)
        fill = f"hsl(230, 45%, {shade * 100:.0f}%)"
        ink = "#fff" if shade < 0.6 else "#111"
        for j, (name, lines) in enumerate(rows):
            x = left + j * (box + 10)
            out += [
                f'<rect x="{x:.0f}" y="{y}" width="{box:.0f}" height="{row}" rx="6" '
                f'fill="{fill}" stroke="#334"/>',
                f'<text x="{x + 10:.0f}" y="{y + 22}" font-weight="bold" fill="{ink}">'
                f"graphvision.{html.escape(name)}</text>",
            ]
            for k, line in enumerate(lines):
                out.append(
                    f'<text x="{x + 10:.0f}" y="{y + 40 + 15 * k}" font-size="11" fill="{ink}">'
                    f"{html.escape(line)}</text>"
                )
        y += row + gap
    out.append("</svg>")
    return "\n".join(out)


def module_rows() -> list[str]:
    rows = ["| module | lines | what it holds |", "| --- | ---: | --- |"]
    for path in sorted(ENGINE.rglob("*.py")):
        source = path.read_text(encoding="utf-8")
        doc = ast.get_docstring(ast.parse(source)) or ""
        first = " ".join(doc.strip().split("\n\n")[0].split()).replace("|", "\\|")
        name = path.relative_to(runs.ROOT).as_posix()
        rows.append(f"| `{name}` | {len(source.splitlines())} | {first} |")
    return rows


def generate() -> None:
    layers, origin = contract_layers()
    with mkdocs_gen_files.open("assets/generated/layers.svg", "w") as out:
        out.write(layers_svg(layers))
    text = [
        "",
        "## The layers, as checked",
        "",
        f"Drawn when this site was built from {origin}; top to bottom, a layer may",
        "import only the layers below it.",
        "",
        "![The engine's layers](assets/generated/layers.svg)",
        "",
        "## Every engine module",
        "",
        "Listed from the source tree when this site was built, with the first",
        "paragraph of each module's docstring.",
        "",
        *module_rows(),
        "",
    ]
    with mkdocs_gen_files.open("architecture.md", "a") as out:
        out.write("\n".join(text))
