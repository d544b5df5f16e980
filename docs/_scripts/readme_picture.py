"""Write docs/assets/homography-matches.png, the README's picture, from a real run.

    .venv/bin/python docs/_scripts/readme_picture.py

It runs pipelines/homography.yaml (what ``make demo`` runs) and saves its
``matches_drawn`` output: SIFT matches between the astronaut and a seeded
perspective warp of it, RANSAC's inliers in green. The picture is committed,
so the README shows it without a build; run this again when the pipeline changes.
"""

from __future__ import annotations

from pathlib import Path

import runs

import graphvision as gv

TARGET = Path(__file__).resolve().parents[1] / "assets" / "homography-matches.png"


def main() -> None:
    result = gv.run(gv.load_pipeline(runs.PIPELINES / "homography.yaml"))
    TARGET.write_bytes(runs.png(result.outputs["matches_drawn"], longest=1024))
    print(f"wrote {TARGET} (corner error {result.outputs['corner_error']:.3f} px)")


if __name__ == "__main__":
    main()
