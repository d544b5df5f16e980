"""The README and the documentation work when followed to the letter.

Every page with Python code (the README, the tutorial, the how-to guides and
the reference pages) is run as written, in a fresh folder that sees the
repository's pipelines/ as a page's reader does from its root: first each code
block with a title (```yaml title="denoise.yaml"```) is written to that file,
then every Python block without one runs, in order, in one namespace. The
blocks assert what they claim (a median filter raises the PSNR, a blurred
picture is less sharp), so a page whose code or claim goes stale fails here.
"""

from __future__ import annotations

import re
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest

ROOT = Path(__file__).parent.parent
README = ROOT / "README.md"
DOCS = ROOT / "docs"

_FENCE = re.compile(
    r"^(?P<indent>[ ]*)```(?P<lang>[\w+-]+)(?P<attrs>[^\n]*)\n(?P<body>.*?)^(?P=indent)```[ ]*$",
    re.MULTILINE | re.DOTALL,
)
_TITLE = re.compile(r'title="([^"]+)"')


@dataclass
class Block:
    lang: str
    title: str
    code: str
    line: int


def blocks(page: Path) -> list[Block]:
    text = page.read_text(encoding="utf-8")
    found = []
    for match in _FENCE.finditer(text):
        indent = len(match.group("indent"))
        code = "\n".join(line[indent:] for line in match.group("body").splitlines()) + "\n"
        title = _TITLE.search(match.group("attrs"))
        line = text.count("\n", 0, match.start()) + 1
        found.append(Block(match.group("lang"), title.group(1) if title else "", code, line))
    return found


def runnable(page: Path) -> bool:
    return any(b.lang == "python" and not b.title for b in blocks(page))


PAGES = [README, *sorted(p for p in DOCS.rglob("*.md") if "_scripts" not in p.parts)]


def run_page(page: Path, folder: Path, monkeypatch: pytest.MonkeyPatch) -> dict:
    """Write the page's titled blocks, then run its Python blocks; return the namespace."""
    monkeypatch.chdir(folder)
    monkeypatch.syspath_prepend(str(folder))
    # A reader's environment: no pixel budget left behind by a command run in-process
    # earlier (the command line sets GRAPHVISION_MAX_PIXELS for its worker processes).
    monkeypatch.delenv("GRAPHVISION_MAX_PIXELS", raising=False)
    (folder / "pipelines").symlink_to(ROOT / "pipelines")  # pages run from the repository root
    before = set(sys.modules)
    found = blocks(page)
    for block in found:
        if block.title:
            path = folder / block.title
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_text(block.code, encoding="utf-8")
    namespace: dict = {"__name__": "__docs__"}
    try:
        for block in found:
            if block.lang == "python" and not block.title:
                where = f"{page.relative_to(ROOT)}:{block.line}"
                exec(compile(block.code, where, "exec"), namespace)
    finally:  # modules imported from the page's folder (my_nodes) must not leak to other pages
        for name in set(sys.modules) - before:
            origin = getattr(sys.modules[name], "__file__", None) or ""
            if origin.startswith(str(folder)):
                del sys.modules[name]
    return namespace


@pytest.mark.parametrize(
    "page", [p for p in PAGES if runnable(p)], ids=lambda p: str(p.relative_to(ROOT))
)
def test_the_page_runs_as_written(page, tmp_path, monkeypatch):
    run_page(page, tmp_path, monkeypatch)


def test_the_tutorial_and_the_readme_have_code_that_runs():
    """The harness above finds what it should: a page whose blocks it no longer
    recognised would pass without running anything."""
    tutorial = sorted((DOCS / "tutorial").glob("first-*.md"))
    assert len(tutorial) == 4 and all(runnable(p) for p in tutorial)
    readme = blocks(README)
    assert {b.lang for b in readme if b.title} >= {"yaml", "python"}
    assert runnable(README)


def test_the_readme_node_passes_check_plugin(tmp_path, monkeypatch):
    from graphvision.testing import check_plugin

    node_file = next(b for b in blocks(README) if b.lang == "python" and b.title)
    (tmp_path / node_file.title).write_text(node_file.code, encoding="utf-8")
    monkeypatch.syspath_prepend(str(tmp_path))
    module = __import__(Path(node_file.title).stem)
    try:
        assert check_plugin(module).nodes
    finally:
        del sys.modules[module.__name__]


def test_the_readme_stays_short_and_links_into_the_docs():
    text = README.read_text(encoding="utf-8")
    assert len(text.splitlines()) <= 200
    for target in re.findall(r"\]\((docs/[^)#]+)", text):
        assert (ROOT / target).exists(), f"the README links to {target}, which does not exist"


def test_the_readme_python_example_runs_with_its_files_in_another_folder(tmp_path, monkeypatch):
    """Run from the folder above its files (``gv.load_pipeline("try/denoise.yaml")``), the
    example still finds my_nodes.py beside the pipeline: it looked in the working folder."""
    monkeypatch.chdir(tmp_path)
    monkeypatch.delenv("GRAPHVISION_MAX_PIXELS", raising=False)
    found = blocks(README)
    for block in found:
        if block.title:
            (tmp_path / "try").mkdir(exist_ok=True)
            (tmp_path / "try" / block.title).write_text(block.code, encoding="utf-8")
    code = "".join(b.code for b in found if b.lang == "python" and not b.title)
    assert 'gv.load_pipeline("denoise.yaml")' in code
    code = code.replace('gv.load_pipeline("denoise.yaml")', 'gv.load_pipeline("try/denoise.yaml")')
    before = set(sys.modules)
    try:
        namespace: dict = {"__name__": "__docs__"}
        exec(compile(code, "README.md", "exec"), namespace)
    finally:
        for name in set(sys.modules) - before:
            if (getattr(sys.modules[name], "__file__", None) or "").startswith(str(tmp_path)):
                del sys.modules[name]
    assert list(namespace["graph"].plugins) == [str(tmp_path / "try" / "my_nodes.py")]
    assert namespace["graph"].plugins == ["my_nodes.py"]  # as the file would name it
