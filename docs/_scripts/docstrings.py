"""NumPy-style docstrings (reStructuredText) as Markdown for the node reference.

Only what the node docstrings use: the summary and description, ``.. math::``
blocks and ``:math:`` roles (rendered by KaTeX through pymdownx.arithmatex),
double-backtick literals, ``:func:``-style roles, literal blocks, and the
sections Parameters, Returns, Raises, References, Notes, Examples.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field

_SECTION = re.compile(r"^([A-Z][A-Za-z ]+)\n-{3,}\s*$", re.MULTILINE)
_ROLE = re.compile(r":(?:func|class|mod|meth|attr|obj|data|exc|ref|py:\w+):`~?\.?([^`]+)`")
_MATH_ROLE = re.compile(r":math:`([^`]+)`")
_LITERAL = re.compile(r"``(.+?)``")
_CITATION = re.compile(r"\[(\d+|#\w*)\]_")
_TAG = re.compile(r"<(?=[A-Za-z/!?])")


@dataclass
class Entry:
    """One ``name : type`` entry of a section, with its description."""

    names: list[str]
    kind: str
    text: str


@dataclass
class Docstring:
    summary: str
    body: str
    sections: dict[str, str] = field(default_factory=dict)

    def entries(self, section: str) -> list[Entry]:
        return parse_entries(self.sections.get(section, ""))


def parse(doc: str) -> Docstring:
    """Split a cleaned docstring into summary, body and named sections."""
    doc = doc.strip("\n")
    parts = _SECTION.split(doc)
    head, sections = parts[0], {}
    for title, text in zip(parts[1::2], parts[2::2], strict=True):
        sections[title.strip()] = text.strip("\n")
    head = head.strip()
    summary, _, body = head.partition("\n\n")
    return Docstring(" ".join(summary.split()), body.strip(), sections)


def parse_entries(text: str) -> list[Entry]:
    entries: list[Entry] = []
    for line in text.splitlines():
        if line and not line[0].isspace():
            name, sep, kind = line.partition(" : ")
            if not sep and line.rstrip().endswith(" :"):
                name, kind = line.rstrip()[:-2], ""
            names = [n.strip() for n in name.split(",") if n.strip()]
            entries.append(Entry(names, kind.strip(), ""))
        elif entries:
            entries[-1].text += line.strip() + "\n" if line.strip() else "\n"
    for entry in entries:
        entry.text = entry.text.strip()
    return entries


def _protect(text: str, pattern: re.Pattern[str], store: list[str], render) -> str:
    def keep(match: re.Match[str]) -> str:
        store.append(render(match))
        return f"\x00{len(store) - 1}\x00"

    return pattern.sub(keep, text)


def inline(text: str, *, table: bool = False) -> str:
    """Inline reStructuredText as Markdown: math, literals, roles, citations."""
    store: list[str] = []
    text = _protect(text, _MATH_ROLE, store, lambda m: f"${m.group(1).strip()}$")
    text = _protect(
        text, _LITERAL, store, lambda m: f"`{m.group(1)}`" if "`" not in m.group(1) else m.group(0)
    )
    text = _protect(text, _ROLE, store, lambda m: f"`{m.group(1)}`")
    text = _protect(text, re.compile(r"`[^`\n]+`"), store, lambda m: m.group(0))
    text = _CITATION.sub(lambda m: f"[{m.group(1)}]", text)
    text = _TAG.sub("&lt;", text)
    if table:
        text = text.replace("|", "\\|").replace("\n", " ")
    for _ in range(2):  # a literal may hold a protected role
        text = re.sub("\x00(\\d+)\x00", lambda m: store[int(m.group(1))], text)
    if table:
        text = re.sub(r"(?<!\\)\|", "\\|", text)
    return text


def _indent(line: str) -> int:
    return len(line) - len(line.lstrip())


def blocks(text: str) -> str:
    """Block-level reStructuredText as Markdown: math blocks, literal blocks, paragraphs."""
    lines = text.splitlines()
    out: list[str] = []
    i = 0
    while i < len(lines):
        line = lines[i]
        stripped = line.strip()
        if stripped.startswith(".. math::"):
            formula = [stripped[len(".. math::") :].strip()]
            base = _indent(line)
            i += 1
            while i < len(lines) and (not lines[i].strip() or _indent(lines[i]) > base):
                formula.append(lines[i].strip())
                i += 1
            body = "\n".join(f for f in formula if f)
            out += ["", "$$", body, "$$", ""]
            continue
        if stripped.startswith(">>>"):
            code = []
            while i < len(lines) and lines[i].strip():
                code.append(lines[i].strip())
                i += 1
            out += ["", "```pycon", *code, "```", ""]
            continue
        if stripped.endswith("::") and not stripped.startswith(".."):
            lead = stripped[:-2].rstrip()
            if lead:
                out.append(inline(line.rstrip()[:-1]))  # "text::" -> "text:"
            base = _indent(line)
            i += 1
            code = []
            while i < len(lines) and (not lines[i].strip() or _indent(lines[i]) > base):
                code.append(lines[i])
                i += 1
            while code and not code[-1].strip():
                code.pop()
            while code and not code[0].strip():
                code.pop(0)
            if code:
                cut = min(_indent(c) for c in code if c.strip())
                out += ["", "```text", *(c[cut:] for c in code), "```", ""]
            continue
        if stripped.startswith(".. ") and "::" in stripped:  # other directives: their text
            directive = stripped[3:].split("::", 1)
            title = directive[0].strip().capitalize()
            out += ["", f"**{title}.** {inline(directive[1].strip())}"]
            i += 1
            continue
        out.append(inline(line.strip()) if stripped else "")
        i += 1
    markdown = "\n".join(out)
    # a list needs a blank line before it in Markdown (reST often has one already)
    markdown = re.sub(r"(\S)\n([*-] )", r"\1\n\n\2", markdown)
    return re.sub(r"\n{3,}", "\n\n", markdown).strip()


def references(text: str) -> list[str]:
    """The ``.. [n] ...`` items of a References section (or its plain lines)."""
    items: list[str] = []
    for line in text.splitlines():
        match = re.match(r"\s*\.\. \[([^\]]+)\]\s*(.*)", line)
        if match:
            items.append(match.group(2).strip())
        elif line.strip() and items:
            items[-1] += " " + line.strip()
        elif line.strip():
            items.append(line.strip())
    return [inline(item) for item in items]
