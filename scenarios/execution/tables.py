"""Statistics of the runner's results table: engines against a reference, Table 2 of the seed.

The results table has one row per engine (or series "ENGINE + EFFECTS") and
motion; the columns these helpers read are :data:`REQUIRED_COLUMNS`. Failed
rows (status not "ok", or a NaN peak) are left out of every statistic and
counted; an overturned row's theta_max/alpha is +inf. The statistics are those
of :mod:`housner.statistics.ensemble_stats` on the rows of each engine.

References
----------
Bachmann, J. A., Strand, M., Vassiliou, M. F., Broccardo, M., Stojadinovic, B.
(2017). Probabilistic validation of the Housner rocking model. COMPDYN 2017,
Sec. 6, Fig. 10 and Table 2.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
import pandas as pd

from housner.errors import unknown_choice
from housner.statistics.ensemble_stats import (
    PercentileEstimate,
    ks_2samp,
    per_record_agreement,
    percentile_label,
    percentiles,
    wasserstein,
)
from housner.statistics.proportions import ProportionCI, overturn_probability

__all__ = [
    "REQUIRED_COLUMNS",
    "EngineSummary",
    "Estimate",
    "compare_engines",
    "engine_summaries",
    "percentile_table",
    "split_failed",
]

#: Columns of the results table that these helpers (and every reader of a run) need.
REQUIRED_COLUMNS = ("engine", "motion_id", "theta_max_over_alpha", "overturned", "status")


def _check_table(results: pd.DataFrame) -> None:
    if not isinstance(results, pd.DataFrame):
        raise ValueError(f"`results` must be a pandas DataFrame (the runner's results table), got {type(results)}")
    missing = [c for c in REQUIRED_COLUMNS if c not in results.columns]
    if missing:
        raise ValueError(
            f"`results` lacks column(s) {', '.join(missing)}; a results table has "
            f"{', '.join(REQUIRED_COLUMNS)} (one row per engine and motion)"
        )


def split_failed(results: pd.DataFrame) -> tuple[pd.DataFrame, pd.DataFrame]:
    """Split a results table into usable rows and failed rows.

    A row fails when its ``status`` is not ``"ok"`` or its
    ``theta_max_over_alpha`` is NaN. Usable rows get ``theta_max_over_alpha``
    set to +inf where ``overturned`` is true, so that both columns agree.

    Returns
    -------
    ok, failed : pandas.DataFrame
    """
    _check_table(results)
    theta = results["theta_max_over_alpha"].astype(np.float64)
    bad = (results["status"].astype(str) != "ok") | theta.isna()
    ok = results.loc[~bad].copy()
    ok["theta_max_over_alpha"] = np.where(
        ok["overturned"].astype(bool).to_numpy(), np.inf, ok["theta_max_over_alpha"].astype(np.float64).to_numpy()
    )
    return ok, results.loc[bad].copy()


def _engines(results: pd.DataFrame, reference: str | None) -> list[str]:
    names = [str(e) for e in dict.fromkeys(results["engine"].astype(str))]
    if reference is not None:
        if reference not in names:
            raise unknown_choice("reference engine", reference, names)
        names.remove(reference)
        names.insert(0, reference)
    return names


def _paired(ok: pd.DataFrame, engine: str, reference: str) -> tuple[np.ndarray, np.ndarray]:
    """theta_max/alpha of ``engine`` and ``reference`` on the motions both ran successfully."""
    sub = ok[ok["engine"].astype(str).isin([engine, reference])]
    dup = sub.duplicated(["engine", "motion_id"])
    if dup.any():
        row = sub.loc[dup].iloc[0]
        raise ValueError(
            f"`results` has more than one row for engine {row['engine']!r} and motion_id {row['motion_id']}; "
            "select one scenario and one set of effects before comparing engines"
        )
    wide = sub.pivot(index="motion_id", columns="engine", values="theta_max_over_alpha").dropna()
    return wide[engine].to_numpy(np.float64), wide[reference].to_numpy(np.float64)


#: Columns of :func:`compare_engines` that compare an engine with the reference.
_VERSUS_COLUMNS = (
    "ks_distance",
    "ks_pvalue",
    "wasserstein",
    "overturn_diff",
    "n_paired",
    "agreement_share",
    "verdict_share",
)


def compare_engines(
    results: pd.DataFrame,
    reference: str = "housner",
    *,
    q: Sequence[float] = (25, 50, 75),
    ci: float = 0.90,
    p_ci: float = 0.95,
    p_method: str = "wilson",
    n_boot: int = 2000,
    seed=0,
    rtol: float = 0.1,
    atol: float = 0.05,
) -> pd.DataFrame:
    """One row of statistics per engine, each compared with a reference engine.

    Parameters
    ----------
    results : pandas.DataFrame
        The runner's results table (one row per engine and motion; columns
        ``engine``, ``motion_id``, ``theta_max_over_alpha``, ``overturned``,
        ``status``, optionally ``wall_s``).
    reference : str
        Engine the others are compared with (it gets the first row).
    q : sequence of float
        Percentile levels [%].
    ci : float
        Confidence level of the bootstrap intervals on percentiles [-].
    p_ci, p_method
        Confidence level and method of the interval on P[overturn]; see
        :func:`overturn_probability`.
    n_boot, seed
        Bootstrap resamples and their seed. Every engine is resampled with the
        same seed, so adding an engine to the table does not change the others' intervals.
    rtol, atol
        Tolerances of :func:`per_record_agreement`.

    Returns
    -------
    pandas.DataFrame
        Indexed by engine, with columns ``n`` (rows), ``n_failed``, ``n_ok``;
        ``q25``, ``q25_low``, ``q25_high``, ... (theta_max/alpha [-], +inf =
        overturn); ``p_overturn``, ``p_overturn_low``, ``p_overturn_high``;
        versus the reference: ``ks_distance``, ``ks_pvalue``, ``wasserstein``
        [alpha], ``overturn_diff`` (P_engine - P_reference), ``n_paired``,
        ``agreement_share``, ``verdict_share``; ``wall_s_median`` and
        ``wall_s_total`` [s] when the table has ``wall_s``. The comparison
        columns are NaN on the reference row.
    """
    ok, failed = split_failed(results)
    names = _engines(results, reference)
    qa = np.atleast_1d(np.asarray(q, dtype=np.float64))
    ref_ok = ok.loc[ok["engine"].astype(str) == reference, "theta_max_over_alpha"].to_numpy(np.float64)
    rows = []
    for name in names:
        mine = ok["engine"].astype(str) == name
        v = ok.loc[mine, "theta_max_over_alpha"].to_numpy(np.float64)
        n_failed = int((failed["engine"].astype(str) == name).sum())
        row: dict[str, float] = {"engine": name, "n": v.size + n_failed, "n_failed": n_failed, "n_ok": v.size}
        row.update(_distribution_columns(v, qa, ci, p_ci, p_method, n_boot, seed))
        cmp = dict.fromkeys(_VERSUS_COLUMNS, math.nan)
        if name != reference and v.size and ref_ok.size:
            cmp.update(_versus_reference(ok, name, reference, v, ref_ok, rtol, atol))
        row.update(cmp)
        if "wall_s" in results.columns:
            w = results.loc[results["engine"].astype(str) == name, "wall_s"].astype(np.float64)
            row["wall_s_median"] = float(w.median())
            row["wall_s_total"] = float(w.sum())
        rows.append(row)
    return pd.DataFrame(rows).set_index("engine")


def _distribution_columns(
    v: np.ndarray, qa: np.ndarray, ci: float, p_ci: float, p_method: str, n_boot: int, seed
) -> dict[str, float]:
    """One engine's percentiles ``q25``, ``q25_low``, ``q25_high``... and P[overturn] with its interval, from its
    usable theta_max/alpha ``v`` (NaN without one)."""
    if v.size:
        pe = percentiles(v, qa, ci=ci, n_boot=n_boot, seed=seed)
        po = overturn_probability(np.isposinf(v), ci=p_ci, method=p_method)
    else:
        nan = np.full(qa.shape, np.nan)
        pe = PercentileEstimate(qa, nan, nan, nan)
        po = ProportionCI(math.nan, math.nan, math.nan)
    row: dict[str, float] = {}
    for k, qn in enumerate(_percentile_column(x) for x in qa):
        row[qn], row[f"{qn}_low"], row[f"{qn}_high"] = pe.value[k], pe.low[k], pe.high[k]
    row["p_overturn"], row["p_overturn_low"], row["p_overturn_high"] = po
    return row


def _percentile_column(q: float) -> str:
    """The column of :func:`compare_engines` that holds the percentile at level ``q`` [%]: ``q25``, ``q50``..."""
    return f"q{q:g}"


class Estimate(NamedTuple):
    """A statistic with the two ends of its confidence interval (same units as the statistic)."""

    value: float
    low: float
    high: float


@dataclass(frozen=True)
class EngineSummary:
    """One engine's row of :func:`compare_engines`: its records, its distribution of theta_max/alpha and how far
    it lies from the reference's.

    Attributes
    ----------
    n, n_failed, n_ok : int
        The engine's records: all, failed, usable.
    percentiles : dict of float to Estimate
        theta_max/alpha [-] (+inf: the percentile falls in the overturned records) at each percentile level [%],
        with its percentile-bootstrap interval (NaN without usable records).
    p_overturn : Estimate
        P[overturn] [-] with its interval.
    ks_distance, ks_pvalue : float
        Two-sample Kolmogorov-Smirnov distance to the reference's distribution [-] and its p-value [-].
    wasserstein : float
        Wasserstein distance W1 to the reference's non-overturned peaks [alpha].
    overturn_diff : float
        P[overturn] of the engine minus the reference's [-].
    n_paired : float
        Records both the engine and the reference ran (a float: NaN where not compared).
    agreement_share, verdict_share : float
        Shares of the paired records that agree in theta_max/alpha, and in overturning or not [-].
    wall_s_median, wall_s_total : float
        Wall time per record (median) and in all [s]; NaN when the results table has no ``wall_s``.

    The comparisons with the reference (``ks_distance`` to ``verdict_share``) are NaN on the reference's row and
    where either engine has no usable record.
    """

    n: int
    n_failed: int
    n_ok: int
    percentiles: dict[float, Estimate]
    p_overturn: Estimate
    ks_distance: float
    ks_pvalue: float
    wasserstein: float
    overturn_diff: float
    n_paired: float
    agreement_share: float
    verdict_share: float
    wall_s_median: float = math.nan
    wall_s_total: float = math.nan

    @property
    def median(self) -> Estimate:
        """The median theta_max/alpha [-] with its interval (NaN where the table has no 50th percentile)."""
        return self.percentile(50.0)

    def percentile(self, q: float) -> Estimate:
        """theta_max/alpha [-] at the percentile level ``q`` [%] with its interval (NaN: a level not computed)."""
        return self.percentiles.get(float(q), Estimate(math.nan, math.nan, math.nan))

    @classmethod
    def from_row(cls, row: pd.Series) -> EngineSummary:
        """The summary of one row of :func:`compare_engines` (the one place that reads its columns by name)."""

        def num(col: str) -> float:
            return float(row[col]) if col in row.index else math.nan

        def estimate(col: str) -> Estimate:
            return Estimate(num(col), num(f"{col}_low"), num(f"{col}_high"))

        levels = [float(c[1:]) for c in row.index if _is_percentile_column(str(c), row.index)]
        return cls(
            n=int(row["n"]),
            n_failed=int(row["n_failed"]),
            n_ok=int(row["n_ok"]),
            percentiles={q: estimate(_percentile_column(q)) for q in levels},
            p_overturn=estimate("p_overturn"),
            ks_distance=num("ks_distance"),
            ks_pvalue=num("ks_pvalue"),
            wasserstein=num("wasserstein"),
            overturn_diff=num("overturn_diff"),
            n_paired=num("n_paired"),
            agreement_share=num("agreement_share"),
            verdict_share=num("verdict_share"),
            wall_s_median=num("wall_s_median"),
            wall_s_total=num("wall_s_total"),
        )


def _is_percentile_column(col: str, columns: pd.Index) -> bool:
    """Whether ``col`` is a percentile's column of :func:`compare_engines` (``q25``, with ``q25_low`` beside it)."""
    if not (col.startswith("q") and f"{col}_low" in columns):
        return False
    try:
        return _percentile_column(float(col[1:])) == col
    except ValueError:
        return False


def engine_summaries(table: pd.DataFrame) -> dict[str, EngineSummary]:
    """Engine -> its :class:`EngineSummary`, for every row of a :func:`compare_engines` table, in its order."""
    return {str(e): EngineSummary.from_row(row) for e, row in table.iterrows()}


def _versus_reference(
    ok: pd.DataFrame, name: str, reference: str, v: np.ndarray, ref_ok: np.ndarray, rtol: float, atol: float
) -> dict[str, float]:
    """The :data:`_VERSUS_COLUMNS` of engine ``name`` (usable values ``v``) against the reference's ``ref_ok``."""
    cmp: dict[str, float] = {}
    cmp["ks_distance"], cmp["ks_pvalue"] = ks_2samp(v, ref_ok)
    cmp["wasserstein"] = wasserstein(v, ref_ok)
    cmp["overturn_diff"] = float(np.isposinf(v).mean() - np.isposinf(ref_ok).mean())
    a, b = _paired(ok, name, reference)
    agreement = per_record_agreement(a, b, rtol=rtol, atol=atol)
    cmp["n_paired"] = agreement.n
    cmp["agreement_share"] = agreement.share
    cmp["verdict_share"] = agreement.verdict_share
    return cmp


def percentile_table(
    results: pd.DataFrame,
    reference: str = "housner",
    *,
    engines: Iterable[str] | None = None,
    q: Sequence[float] = (25, 50, 75),
    formatted: bool = False,
    digits: int = 2,
) -> pd.DataFrame:
    """Percentiles of theta_max/alpha per engine in the layout of Table 2 of the seed paper.

    Parameters
    ----------
    results : pandas.DataFrame
        The runner's results table; failed rows are left out.
    reference : str
        The engine the others are compared with (the seed's "exp" column).
    engines : iterable of str, optional
        Engines to show after the reference (default: all others, in table order).
    q : sequence of float
        Percentile levels [%].
    formatted : bool
        If true, return strings: values to ``digits`` decimals, "overturn" for
        +inf, "-" where a difference is undefined, as printed in the paper.
    digits : int
        Decimals when ``formatted``.

    Returns
    -------
    pandas.DataFrame
        Index "25th", "50th", ... ; columns "<reference> [alpha]", then per
        engine "<engine> [alpha]", "<engine> - <reference> [alpha]" and
        "(<engine> - <reference>)/<reference> [-]". Numbers are
        theta_max/alpha; +inf is an overturn, and a difference involving an
        overturn is NaN.

    References
    ----------
    Bachmann et al. (2017), Table 2 (numerical vs experimental percentiles).
    """
    ok, _ = split_failed(results)
    names = _engines(results, reference)
    if engines is not None:
        wanted = [str(e) for e in engines]
        for e in wanted:
            if e not in names:
                raise unknown_choice("engine", e, names)
        names = [reference] + [e for e in wanted if e != reference]
    qa = np.atleast_1d(np.asarray(q, dtype=np.float64))
    index = pd.Index([percentile_label(x) for x in qa], name="percentile")

    def pct(name: str) -> np.ndarray:
        v = ok.loc[ok["engine"].astype(str) == name, "theta_max_over_alpha"].to_numpy(np.float64)
        return percentiles(v, qa, n_boot=0).value if v.size else np.full(qa.shape, np.nan)

    ref = pct(reference)
    cols: dict[str, np.ndarray] = {f"{reference} [alpha]": ref}
    for name in names[1:]:
        mine = pct(name)
        with np.errstate(invalid="ignore", divide="ignore"):
            diff = np.where(np.isfinite(mine) & np.isfinite(ref), mine - ref, np.nan)
            rel = np.where(ref != 0, diff / ref, np.nan)
        cols[f"{name} [alpha]"] = mine
        cols[f"{name} - {reference} [alpha]"] = diff
        cols[f"({name} - {reference})/{reference} [-]"] = rel
    table = pd.DataFrame(cols, index=index)
    if not formatted:
        return table

    def fmt(x: float) -> str:
        if np.isposinf(x):
            return "overturn"
        if np.isnan(x):
            return "-"
        return f"{x:.{digits}f}"

    return table.map(fmt)
