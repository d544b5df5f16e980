"""report.html: every output shown, every picture a decodable PNG, clean in a real browser."""

from __future__ import annotations

import base64
import html
import io
import json
import re
import shutil
import subprocess
from html.parser import HTMLParser
from pathlib import Path

import imageio.v3 as iio
import numpy as np
import pytest

import graphvision as gv
from graphvision.graph.svg import STATUS_COLOURS
from graphvision.views.html import write_html_report

PIPELINES = Path(__file__).parents[2] / "pipelines"
BROWSERS = ("chromium", "chromium-browser", "google-chrome", "chrome")


class _Page(HTMLParser):
    """The images, headings and links of a page."""

    def __init__(self) -> None:
        super().__init__()
        self.images: list[str] = []
        self.headings: list[str] = []
        self.external: list[str] = []
        self._in_heading = False

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        found = dict(attrs)
        if tag == "img":
            self.images.append(found.get("src") or "")
        for attr in ("src", "href"):
            link = found.get(attr) or ""
            if link.startswith(("http:", "https:", "//")):
                self.external.append(link)
        self._in_heading = tag == "h3"

    def handle_data(self, data: str) -> None:
        if self._in_heading and data.strip():
            self.headings.append(data.strip())
            self._in_heading = False


@pytest.fixture(scope="module")
def coins_report(tmp_path_factory) -> Path:
    result = gv.run(gv.load_pipeline(PIPELINES / "coins.yaml"), cache=None)
    directory = tmp_path_factory.mktemp("coins")
    return write_html_report(result.compiled, result.outputs, result.record, directory)


def test_every_output_has_a_section_and_pictures_are_pngs(coins_report: Path) -> None:
    page = _Page()
    page.feed(coins_report.read_text())
    graph = gv.load_pipeline(PIPELINES / "coins.yaml")
    assert page.headings[: len(graph.outputs)] == list(graph.outputs)
    assert page.external == []  # self-contained: nothing from the network
    image_outputs = 2  # labels (coloured) and the overlay
    assert len(page.images) == image_outputs
    for source in page.images:
        assert source.startswith("data:image/png;base64,")
        picture = iio.imread(io.BytesIO(base64.b64decode(source.split(",", 1)[1])))
        assert picture.shape[0] > 0 and picture.shape[1] > 0
    text = coins_report.read_text()
    assert '<div class="value">24</div>' in text  # the count, as a number
    assert STATUS_COLOURS["computed"] in text  # the graph is coloured by status


def test_labels_are_coloured_and_background_black() -> None:
    from graphvision.values.pictures import label_colours

    labels = np.array([[0, 1, 2], [3, 0, 1]], np.int32)
    rgb = label_colours(labels)
    assert np.all(rgb[labels == 0] == 0)
    assert np.array_equal(rgb[0, 1], rgb[1, 2])  # one label, one colour
    assert len({tuple(rgb[0, 1]), tuple(rgb[0, 2]), tuple(rgb[1, 0])}) == 3


def _browser() -> str | None:
    return next((path for name in BROWSERS if (path := shutil.which(name))), None)


CHECK = """<script>
window.__errors = [];
window.addEventListener("error", e => __errors.push(String(e.message || e.target.src)), true);
const original = console.error;
console.error = (...args) => { __errors.push(args.join(" ")); original(...args); };
window.addEventListener("load", () => {
  const images = [...document.images];
  const broken = images.filter(i => !(i.complete && i.naturalWidth > 0)).length;
  const graph = document.querySelector(".graph svg").getBoundingClientRect();
  const fits = graph.left >= 0 && graph.right <= window.innerWidth && graph.width > 100;
  document.documentElement.setAttribute(
    "data-check", JSON.stringify({images: images.length, broken, errors: __errors, fits}));
});
</script>"""


@pytest.mark.skipif(_browser() is None, reason="no Chromium installed (CI installs one)")
def test_a_real_browser_loads_the_report_without_errors(coins_report: Path, tmp_path) -> None:
    checked = tmp_path / "checked.html"
    checked.write_text(coins_report.read_text().replace("<head>", "<head>" + CHECK, 1))
    command = [
        str(_browser()),
        "--headless",
        "--no-sandbox",
        "--disable-gpu",
        "--disable-background-networking",
        "--disable-component-update",
        "--disable-sync",
        "--no-first-run",
        f"--user-data-dir={tmp_path / 'profile'}",
        "--virtual-time-budget=5000",
        "--window-size=800,600",  # narrower than the coins graph is wide
        "--dump-dom",
        checked.as_uri(),
    ]
    dom = subprocess.run(command, capture_output=True, text=True, timeout=120).stdout
    found = re.search(r'data-check="([^"]*)"', dom)
    assert found, "the page's load handler did not run"
    check = json.loads(html.unescape(found.group(1)))
    assert check == {"images": 2, "broken": 0, "errors": [], "fits": True}


def test_a_run_result_shows_as_its_report_in_a_notebook(monkeypatch):
    import sys
    import types

    from graphvision.execution import display

    monkeypatch.setattr(display, "_RENDERERS", {})
    monkeypatch.delitem(gv.__dict__, "run", raising=False)  # looked up again, as in a kernel
    monkeypatch.setitem(sys.modules, "IPython", types.ModuleType("IPython"))
    monkeypatch.setattr(gv, "_WHERE", {})
    result = gv.run(gv.load_pipeline(PIPELINES / "line_fit.yaml"), cache=None)
    page = _Page()
    page.feed(result._repr_html_())
    assert page.headings[: len(result.compiled.outputs)] == list(result.compiled.outputs)
    assert len(page.images) == 1  # the points, drawn


def test_a_run_result_outside_a_kernel_shows_its_record_as_text(monkeypatch):
    from graphvision.execution import display

    monkeypatch.setattr(display, "_RENDERERS", {})
    result = gv.run(gv.load_pipeline(PIPELINES / "line_fit.yaml"), cache=None)
    shown = result._repr_html_()
    assert shown.startswith("<pre>") and "node" in shown and "<img" not in shown


def test_batch_page_has_a_card_per_file_linking_its_report(tmp_path):
    import imageio.v3 as iio

    folder = tmp_path / "in"
    folder.mkdir()
    for index in range(3):
        iio.imwrite(folder / f"img{index}.png", np.full((16, 16), 40 * index, np.uint8))
    (folder / "img3.png").write_text("not an image")
    graph = gv.load_pipeline(PIPELINES / "denoise.yaml")
    batch = gv.run_batch(graph, str(folder / "*.png"), input="image", output_dir=tmp_path / "out")
    text = (tmp_path / "out" / "batch.html").read_text()
    assert "3 of 4 files succeeded" in text
    assert text.count('class="card ') == 4 and text.count('href="./img0/report.html"') == 1
    assert 'src="./img0/' in text and "not an image" not in text.split("img3.png")[0]
    assert text.count("href=") == 3  # the failed file has no report to link to
    assert batch.failed == 1


@pytest.mark.parametrize(
    "name", ["javascript:alert(1).png", "a#b.png", "q?x=1.png", "per%41cent.png", 'qu"ote.png']
)
def test_batch_links_cannot_become_a_scheme_query_or_fragment(tmp_path, name):
    """File names become relative, percent-encoded URLs: a name such as
    'javascript:alert(1).png' was a link that ran script when clicked."""
    import re
    from urllib.parse import unquote

    import imageio.v3 as iio

    folder = tmp_path / "in"
    folder.mkdir()
    iio.imwrite(folder / name, np.full((16, 16), 90, np.uint8))
    graph = gv.load_pipeline(PIPELINES / "denoise.yaml")
    gv.run_batch(graph, str(folder / "*.png"), input="image", output_dir=tmp_path / "out")
    text = (tmp_path / "out" / "batch.html").read_text()
    urls = re.findall(r'(?:href|src)="([^"]*)"', text)
    assert len(urls) == 2
    for url in urls:
        assert url.startswith("./") and not re.search(r"[:#?\"<>]", url)
        assert (tmp_path / "out" / unquote(url)).is_file()  # the link still leads to the file


def test_keep_intermediates_adds_their_pictures_to_the_report(tmp_path):
    from graphvision.cli import main

    status = main(
        [
            "run",
            str(PIPELINES / "coins.yaml"),
            "--no-cache",
            "-d",
            str(tmp_path),
            "--keep-intermediates",
        ]
    )
    assert status == 0
    page = _Page()
    page.feed((tmp_path / "report.html").read_text())
    assert "Intermediate values" in (tmp_path / "report.html").read_text()
    for name in ("gray", "binary", "closed", "filled", "opened"):
        assert name in page.headings
    assert len(page.images) > 2


def test_the_written_page_is_the_page_text_in_utf8(tmp_path: Path) -> None:
    """write_html_report writes the constant style and scripts encoded once: the file is
    still html_report's text in UTF-8, byte for byte, failures and earlier runs included."""
    from graphvision.execution.history import Earlier
    from graphvision.views.html import html_report

    result = gv.run(gv.load_pipeline(PIPELINES / "coins.yaml"), cache=None)
    earlier = [Earlier("history/000001-x-0123abcd", "2026-11-27", {"seconds": 1.5})]
    options = {"failures": {"binary": "Ünicode <error> ½"}, "earlier": earlier}
    run = (result.compiled, result.outputs, result.record)
    written = write_html_report(*run, tmp_path, **options).read_bytes()
    assert written == html_report(*run, **options).encode()
    assert written.startswith(b'<!DOCTYPE html>\n<html lang="en"><head><meta charset="utf-8">')
    assert written.endswith(b"</body></html>\n")
    assert "Ünicode &lt;error&gt; ½".encode() in written  # the page's own text, in UTF-8
    assert b'<button type="button">\xe2\x88\x92</button>' in written  # the zoom's minus sign
    assert written.count(b"<style>") == 1 and b"</style></head><body>" in written
