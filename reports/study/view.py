"""A study directory as the report reads it: the study's own result, and the look-ups the sections share.

:meth:`StudyView.load` reads the directory through
:func:`housner.scenarios.studies.study.load_study`, the one reader of its
format (and of its errors); the view adds what the page needs around it: the
reference and the engine order, the sizes and their scale factors, the fit and
comparison of an (engine, size), and the usable and failed records.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path
from typing import Any

import pandas as pd

from housner._values import json_number
from housner.reports.figures import engine_colors
from housner.reports.page import esc
from housner.scenarios.studies.study import StudyMeta, StudyResult, StudySettings, load_study
from housner.scenarios.studies.study_fits import StudyComparison, StudyFit

__all__ = ["StudyView", "count", "is_ok", "key", "status_words"]


def key(size: Any) -> float:
    """A size as a dictionary key: sizes pass through JSON and parquet, so equal ones may differ in the last bits."""
    return round(json_number(size), 9)


def count(x: Any, default: int = 0) -> int:
    """A count from JSON; ``default`` when it is absent or not a number (null, "nan")."""
    v = json_number(x)
    return int(v) if math.isfinite(v) else default


def is_ok(fit: StudyFit | None) -> bool:
    """A maximum-likelihood fit (status "ok"): the only kind whose median and beta the page prints."""
    return fit is not None and fit.ok


def status_words(fit: StudyFit | None) -> str:
    if fit is None:
        return "no fit in fragility.json"
    return (fit.status or "unknown").replace("_", " ")


@dataclass
class StudyView:
    """A study directory read into memory (:class:`~housner.scenarios.studies.study.StudyResult`) with look-ups."""

    path: Path
    result: StudyResult

    @classmethod
    def load(cls, study_dir: str | Path) -> StudyView:
        result = load_study(study_dir)
        return cls(Path(result.out).resolve(), result)

    # --- the study's tables
    @property
    def meta(self) -> StudyMeta:
        """study.json."""
        return self.result.meta

    @property
    def fragility(self) -> pd.DataFrame:
        return self.result.fragility

    @property
    def exceedance(self) -> pd.DataFrame:
        return self.result.exceedance

    @property
    def results(self) -> pd.DataFrame:
        return self.result.results

    @property
    def fits(self) -> list[StudyFit]:
        return self.result.fits

    @property
    def comparisons(self) -> list[StudyComparison]:
        return self.result.comparisons

    # --- the study's settings
    @property
    def settings(self) -> StudySettings:
        return self.meta.study

    @property
    def reference(self) -> str:
        return str(self.settings.reference or "housner")

    @property
    def label(self) -> str:
        return str(self.settings.intensity_label or self.settings.intensity or "intensity")

    @property
    def ci(self) -> float:
        c = json_number(0.95 if self.settings.ci is None else self.settings.ci)
        return c if 0.0 < c < 1.0 else 0.95

    @cached_property
    def engines(self) -> list[str]:
        """Engines of study.json in order, then any found only in the tables; the reference first."""
        names = list(self.meta.engines)
        for frame in (self.fragility, self.results):
            if "engine" in frame:
                names.extend(str(e) for e in frame["engine"].unique())
        names.extend(str(f.engine) for f in self.fits)
        names = list(dict.fromkeys(names))
        return sorted(names, key=lambda n: n != self.reference)

    @property
    def others(self) -> list[str]:
        return [e for e in self.engines if e != self.reference]

    @cached_property
    def colors(self) -> dict[str, str]:
        return engine_colors(self.engines, self.reference)

    @cached_property
    def sizes(self) -> list[float]:
        """Prototype heights [m], ascending: those of study.json and any found in the tables."""
        found = {key(s) for s in self.settings.prototype_heights}
        found |= {key(s) for s in (self.fragility["size"] if "size" in self.fragility else pd.Series(dtype=float))}
        found |= {key(f.size) for f in self.fits}
        return sorted(s for s in found if math.isfinite(s))

    def scale(self, size: float) -> float:
        """The scale factor S of a size (NaN when not recorded)."""
        heights = [key(s) for s in self.settings.prototype_heights]
        factors = self.settings.S
        if size in heights and len(factors) == len(heights):
            return json_number(factors[heights.index(size)])
        for f in self.fits:
            if key(f.size) == size and not math.isnan(json_number(f.S)):
                return json_number(f.S)
        rows = self.fragility[self.fragility["size"].map(key) == size] if "size" in self.fragility else []
        return float(rows["S"].iloc[0]) if len(rows) and "S" in rows else math.nan

    def size_title(self, size: float) -> str:
        s = self.scale(size)
        return f"prototype height {size:g} m" + (f" (S = {s:g})" if math.isfinite(s) else "")

    def size_heading(self, size: float) -> str:
        """The size's title as a heading of its part of a section."""
        title = self.size_title(size)
        return f"<h3>{esc(title[:1].upper() + title[1:])}</h3>"  # str.capitalize would lower "S = 1" to "s = 1"

    # --- fits and comparisons
    def fit(self, engine: str, size: float) -> StudyFit | None:
        return _find(self.fits, engine, size)

    def comparison(self, engine: str, size: float) -> StudyComparison | None:
        return _find(self.comparisons, engine, size)

    # --- records
    @cached_property
    def failed(self) -> pd.DataFrame:
        r = self.results
        if "status" not in r:
            return pd.DataFrame()
        return r[r["status"].astype(str) != "ok"]

    @cached_property
    def _counts(self) -> dict[tuple[str, float], tuple[int, int]]:
        """(engine, size) -> (usable, failed) records: from results.parquet, else the stripes' valid counts."""
        r = self.results
        if {"engine", "size", "status"} <= set(r.columns):
            ok = (r["status"].astype(str) == "ok").rename("ok")
            g = ok.groupby([r["engine"].astype(str), r["size"].map(key)]).agg(["sum", "size"])
            return {(e, s): (int(row["sum"]), int(row["size"] - row["sum"])) for (e, s), row in g.iterrows()}
        fr = self.fragility
        g = fr["n"].groupby([fr["engine"].astype(str), fr["size"].map(key)]).sum()
        return {(e, s): (int(n), 0) for (e, s), n in g.items()}

    def record_counts(self, engine: str, size: float | None = None) -> tuple[int, int]:
        """(usable, failed) records of an engine, at one size or over all sizes."""
        hits = [v for (e, s), v in self._counts.items() if e == engine and (size is None or s == size)]
        return sum(v[0] for v in hits), sum(v[1] for v in hits)

    def valid_at(self, engine: str, size: float) -> int:
        """Records of an engine at a size that entered the stripe counts (0 when every one failed)."""
        fr = self.fragility
        sub = fr[(fr["engine"].astype(str) == engine) & (fr["size"].map(key) == size)]
        return int(sub["n"].sum()) if len(sub) else 0


def _find(rows: list, engine: str, size: float):
    """The row of fragility.json's fits or comparisons for an engine at a size (None when it has none)."""
    for r in rows:
        if str(r.engine) == engine and key(r.size) == size:
            return r
    return None
