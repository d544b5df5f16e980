"""MkDocs hooks: the generated navigation files are not pages, and a site that would
fetch anything from the network when read is refused."""

from __future__ import annotations

import re
from pathlib import Path

from mkdocs.exceptions import PluginError
from mkdocs.plugins import event_priority
from mkdocs.structure.files import InclusionLevel

# what a browser loads by itself: scripts, stylesheets, fonts, images, frames, CSS imports
_FETCHED = re.compile(
    r"""<(?:script|img|iframe|source|audio|video)\b[^>]*\bsrc=["']((?:https?:)?//[^"']+)"""
    r"""|<link\b[^>]*\bhref=["']((?:https?:)?//[^"']+)["'][^>]*>"""
    r"""|@import\s+(?:url\()?["']?((?:https?:)?//[^"')]+)"""
    r"""|url\(["']?((?:https?:)?//[^"')]+)""",
    re.IGNORECASE,
)


@event_priority(-200)  # after literate-nav (-100) has read them
def on_files(files, config, **kwargs):
    """The generated SUMMARY.md files feed literate-nav; they are not pages."""
    for file in files:
        if file.src_uri.endswith("SUMMARY.md"):
            file.inclusion = InclusionLevel.EXCLUDED
    return files


def on_post_build(config, **kwargs) -> None:
    site = Path(config["site_dir"])
    found = []
    for path in sorted(site.rglob("*")):
        if path.suffix not in {".html", ".css", ".js", ".svg"}:
            continue
        text = path.read_text(encoding="utf-8", errors="replace")
        for match in _FETCHED.finditer(text):
            url = next(g for g in match.groups() if g)
            tag = match.group(0)[:60]
            if tag.lower().startswith("<link") and not re.search(
                r"rel=[\"']?(stylesheet|preload|icon|manifest|modulepreload)", match.group(0), re.I
            ):
                continue  # rel=canonical and the like are links, not loads
            found.append(f"{path.relative_to(site)}: {url}")
    if found:
        listing = "\n  ".join(found[:20])
        raise PluginError(
            f"the site would fetch {len(found)} resource(s) from the network:\n  {listing}"
        )
