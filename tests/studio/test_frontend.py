"""The page's own modules (layout, widgets, colour maps), tested by node's test runner on
the built bundle that ships in the package; and the bundle is what frontend/ builds."""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).parents[2]
STATIC = ROOT / "graphvision" / "studio" / "static"


@pytest.mark.skipif(shutil.which("node") is None, reason="node is not installed")
def test_the_page_modules_pass_their_tests() -> None:
    done = subprocess.run(
        ["node", "--test", "test/"], cwd=ROOT / "frontend", capture_output=True, text=True,
        timeout=120,
    )  # fmt: skip
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-2000:]
    assert "# fail 0" in done.stdout


def test_the_static_files_ship_with_their_licences_and_fetch_nothing() -> None:
    for name in ("index.html", "studio.js", "viewers.js", "studio.css", "katex/katex.min.js"):
        assert (STATIC / name).is_file(), name
    licences = {path.name for path in (STATIC / "licences").iterdir()}
    assert {"dagre.LICENSE", "graphlib.LICENSE", "katex.LICENSE"} <= licences
    page = (STATIC / "index.html").read_text()
    assert "http://" not in page and "https://" not in page  # no CDN
    lock = (ROOT / "frontend" / "package-lock.json").read_text()
    assert '"node_modules/@dagrejs/dagre"' in lock  # pinned
