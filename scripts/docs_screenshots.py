"""Screenshots of the built documentation in headless Chromium: two pages and the tutorial's final figure.

Run from the repository root after ``mkdocs build --strict -d /tmp/site``::

    python scripts/docs_screenshots.py --site /tmp/site --out docs/assets/screenshots

Needs a ``chromium`` binary (Debian: ``apt-get install chromium``). The final figure is found as the last
tall block of the tutorial page's content column (the figure closes step 5) and cropped with a margin.
"""

from __future__ import annotations

import argparse
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
from PIL import Image

PAGES = {"explanation-diagnosis.png": "explanation/diagnosis", "reference-cli.png": "reference/cli"}


def shot(chromium: str, url: str, out: Path, height: int) -> None:
    subprocess.run(
        [
            chromium,
            "--headless=new",
            "--no-sandbox",
            "--disable-gpu",
            "--hide-scrollbars",
            f"--window-size=1280,{height}",
            f"--screenshot={out}",
            url,
        ],
        check=True,
        capture_output=True,
        timeout=120,
    )


def final_figure(full: Path) -> Image.Image:
    """The last image block (>= 400 px tall, drawn between x = 300 and 1000 on white) of a page screenshot."""
    im = Image.open(full).convert("RGB")
    px = np.asarray(im).astype(int)
    a = px[:, 300:1000, :].sum(axis=2) < 740
    # a code block is a grey panel whose padding (x = 300) is not white; a figure sits on the white page
    busy = (a.mean(axis=1) > 0.02) & (px[:, 300, :].sum(axis=1) >= 762)
    blocks, start = [], None
    for y, b in enumerate(busy):
        if b and start is None:
            start = y
        elif not b and start is not None:
            blocks.append((start, y))
            start = None
    # a figure: its blocks lie close together (panels); merge gaps below 40 px
    merged: list[list[int]] = []
    for lo, hi in blocks:
        if merged and lo - merged[-1][1] < 40:
            merged[-1][1] = hi
        else:
            merged.append([lo, hi])
    figs = [(lo, hi) for lo, hi in merged if hi - lo >= 400]
    if not figs:
        raise SystemExit("no figure found on the tutorial page")
    lo, hi = figs[-1]
    return im.crop((250, max(lo - 20, 0), 1030, min(hi + 20, im.size[1])))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--site", type=Path, default=Path("/tmp/site"))
    ap.add_argument("--out", type=Path, default=Path("docs/assets/screenshots"))
    args = ap.parse_args(argv)
    chromium = shutil.which("chromium") or shutil.which("chromium-browser")
    if chromium is None:
        print("scripts/docs_screenshots.py: no chromium on PATH (Debian: apt-get install chromium)", file=sys.stderr)
        return 2
    args.out.mkdir(parents=True, exist_ok=True)
    for name, page in PAGES.items():
        shot(chromium, (args.site / page / "index.html").resolve().as_uri(), args.out / name, 1600)
    with tempfile.TemporaryDirectory() as tmp:
        full = Path(tmp) / "tutorial.png"
        shot(chromium, (args.site / "tutorial" / "index.html").resolve().as_uri(), full, 14000)
        final_figure(full).save(args.out / "tutorial-final-figure.png", optimize=True)
    print(f"screenshots in {args.out}: {', '.join(sorted(p.name for p in args.out.glob('*.png')))}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
