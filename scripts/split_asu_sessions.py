"""Split an imported ASU campaign (``housner campaign from-asu``) into two by session date, to check a fitted
outcome model's transfer between parts of one rock's tests (issue 48): ``housner diagnose A --json A.json``, then
``housner diagnose B --model A.json --allow-outside`` (the halves read the records of the imported campaign).

Usage::

    python scripts/split_asu_sessions.py ../shared/data/asu-granite /tmp/asu-sp1 20210800 /tmp/asu-july /tmp/asu-august
"""

from __future__ import annotations

import csv
import re
import sys
from pathlib import Path


def split(data: Path, campaign: Path, cut: int, before: Path, after: Path) -> None:
    """Write ``before`` (tests dated before ``cut``, YYYYMMDD) and ``after`` (the others) from ``campaign``."""
    with (data / "index.csv").open() as f:
        date = {int(row["test"]): int(row["date"]) for row in csv.DictReader(f)}
    head, *blocks = (campaign / "campaign.toml").read_text().split("\n[[record]]\n")
    for out, keep, label in ((before, lambda d: d < cut, "before"), (after, lambda d: d >= cut, "from")):
        out.mkdir(parents=True, exist_ok=True)
        for name in ("records", *[p.name for p in campaign.glob("*.obj")]):
            link = out / name
            if not link.exists():
                link.symlink_to((campaign / name).resolve())
        chosen = [b for b in blocks if keep(date[int(re.search(r'id = "Test(\d+)"', b).group(1))])]
        title = re.sub(r'^name = "(.*)"', rf'name = "\1, sessions {label} {cut}"', head, count=1, flags=re.M)
        (out / "campaign.toml").write_text(title + "".join("\n[[record]]\n" + b for b in chosen))
        print(f"{out}: {len(chosen)} records, {sum('overturned = true' in b for b in chosen)} overturned")


if __name__ == "__main__":
    if len(sys.argv) != 6:
        sys.exit("usage: split_asu_sessions.py DATA CAMPAIGN YYYYMMDD BEFORE_DIR AFTER_DIR")
    split(Path(sys.argv[1]), Path(sys.argv[2]), int(sys.argv[3]), Path(sys.argv[4]), Path(sys.argv[5]))
