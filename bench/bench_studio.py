"""graphvision studio: from a change of RANSAC's threshold to the matches picture repainted.

Opens the studio on ``homography.yaml`` in Debian's Chromium (Playwright), lets the
first run finish, then changes ``fit.threshold`` 20 times (a new value each time, so
every change computes ``fit``, ``error`` and ``drawing`` and loads the rest from the
cache). Each change is timed in the page, from the request to the matches picture of the
new run drawn (its ``gv-node-painted`` event, sent as soon as the ``drawing`` node has
finished and its picture is on the canvas), and split into:

``server``   from the change sent to its run started on the server (the request, its
             validation; the page's and the server's clocks are this machine's)
``compute``  from the run started to the ``drawing`` node finished (its value stored and
             its event sent; the nodes, cache look-ups, values to and from the workers)
``encode``   what the picture's request waited for the matches picture as RGBA bytes
             (``Server-Timing``; the picture is made as soon as ``drawing`` finishes, on a
             thread of its own, so part of it overlaps the event and the description:
             ``made``, not part of the total, is what making it took)
``transfer`` the rest of that picture's request (Resource Timing) minus ``encode``
``paint``    the rest: the node's event reaching the page, the value's description (asked
             for while the picture travels), the picture made ready and drawn

Aim (issue 27): median under 150 ms. Run: ``python bench/bench_studio.py`` (``GV_BENCH_CHANGES=10``
for fewer changes).
"""

from __future__ import annotations

import os
import shutil
import statistics
from pathlib import Path

PIPELINE = Path(__file__).parent.parent / "pipelines" / "homography.yaml"
CHANGES = int(os.environ.get("GV_BENCH_CHANGES", "20"))

_CHANGE = """async (value) => {
  const t0 = performance.now();
  performance.clearResourceTimings();
  let resolvePaint;
  const painted = new Promise((resolve) => { resolvePaint = resolve; });
  const listen = (e) => { if (e.detail.node === "drawing") resolvePaint(e.detail.run); };
  window.addEventListener("gv-node-painted", listen);
  const r = await fetch("api/change", { method: "POST",
    headers: {"Content-Type": "application/json"},
    body: JSON.stringify({ overrides: { "fit.threshold": value } }) });
  const t1 = performance.now();
  const run = (await r.json()).run;
  const seen = await painted;
  const t2 = performance.now();
  window.removeEventListener("gv-node-painted", listen);
  const png = performance.getEntriesByType("resource")
    .find((e) => e.name.includes("/api/rgba/") && e.name.includes("/drawing/"));
  const timing = (name) => (png?.serverTiming.find((t) => t.name === name) || {}).duration || 0;
  return { total: t2 - t0, sent: performance.timeOrigin + t0, answered: t1 - t0, run, seen,
           png: png ? png.responseEnd - png.requestStart : 0,
           encode: timing("encode"), made: timing("made") };
}"""


def main() -> list[str]:
    from playwright.sync_api import sync_playwright

    import graphvision as gv

    browser_path = shutil.which("chromium") or shutil.which("chromium-browser")
    if browser_path is None:
        return ["no Chromium installed: skipped"]
    server = gv.studio(PIPELINE)
    rows = []
    try:
        with sync_playwright() as playwright:
            browser = playwright.chromium.launch(
                executable_path=browser_path, args=["--no-sandbox"]
            )
            page = browser.new_page(viewport={"width": 1500, "height": 950})
            page.goto(server.url)
            page.wait_for_selector("body[data-painted-run='1']", timeout=300_000)
            for i in range(CHANGES):
                found = page.evaluate(_CHANGE, 2.0 + 0.05 * i)
                studio_run = server.session.find_run(found["run"])
                computed = [n for n, v in studio_run.nodes.items() if v.get("status") == "computed"]
                began, ended = studio_run.began * 1e3, studio_run.nodes["drawing"]["ended"] * 1e3
                found["server"] = began - found["sent"]  # the same clock: this machine's
                found["compute"] = ended - began
                found["computed"] = sorted(computed)
                for node in ("fit", "error", "drawing"):  # when each ended, what its op took
                    found[f"{node} ended"] = studio_run.nodes[node]["ended"] * 1e3 - began
                    found[f"{node} op"] = studio_run.nodes[node]["seconds"] * 1e3
                rows.append(found)
            browser.close()
    finally:
        server.stop()
    return _table(rows)


def _table(rows: list[dict]) -> list[str]:
    def stats(key: str) -> tuple[float, float]:
        values = sorted(r[key] for r in rows)
        return statistics.median(values), values[int(0.9 * (len(values) - 1) + 0.5)]

    for r in rows:
        r["transfer"] = max(0.0, r["png"] - r["encode"])
        r["paint"] = max(0.0, r["total"] - r["server"] - r["compute"] - r["png"])
    lines = [
        f"{len(rows)} changes of fit.threshold on homography.yaml; recomputed each time: "
        f"{', '.join(rows[-1]['computed'])}; load average (1 min) at the end: "
        f"{os.getloadavg()[0]:.1f} on {os.cpu_count()} cores",
        "",
        "| part | median ms | p90 ms |",
        "| --- | ---: | ---: |",
    ]
    for key in ("server", "compute", "encode", "transfer", "paint", "total", "made"):
        median, p90 = stats(key)
        lines.append(f"| {key} | {median:.1f} | {p90:.1f} |")
    lines += ["", "compute, by node (from the run's start; the op's own time):", ""]
    lines += ["| node | ended median ms | op median ms |", "| --- | ---: | ---: |"]
    for node in ("fit", "error", "drawing"):
        ended, took = stats(f"{node} ended")[0], stats(f"{node} op")[0]
        lines.append(f"| {node} | {ended:.1f} | {took:.1f} |")
    return lines


if __name__ == "__main__":
    print("\n".join(main()))
