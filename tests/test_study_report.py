"""housner.reports.study (page, verdict, sections, figures) on small synthetic study directories of known fragility.

The directories follow the study format (study.json, fragility.parquet, exceedance.parquet,
fragility.json, results.parquet): outcomes are drawn from lognormal capacities (seeded), the
stripe and exceedance tables are computed from them, and the fits and comparisons are written
by hand so that each test controls its verdict exactly.
"""

from __future__ import annotations

import html
import json
import math
import re
from html.parser import HTMLParser
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from matplotlib.figure import Figure
from scipy import stats as sps

from housner.reports.page import fmt_g, fmt_signed
from housner.reports.study import figures as study_figures
from housner.reports.study import sections as study_sections
from housner.reports.study.page import render_study_report, write_study_report
from housner.reports.study.verdict import DISAGREE
from housner.scenarios.execution.rundir import jsonable
from housner.scenarios.studies.fragility import exceedance, proportion_intervals
from housner.scenarios.studies.study import load_study
from housner.scenarios.studies.study_fits import StudyFit

REF = "housner"
LEVELS = (0.5, 0.8, 1.2, 1.8, 2.7)  # spans 5.4x: a log intensity axis
SIZES = (0.5, 4.0)  # prototype heights [m], 8x: a log size axis
S = (1.0, 8.0)
THRESHOLDS = (0.5, 0.8, 1.0)
N_MOTIONS = 20
LABEL = "PGA / (g tan alpha) [-]"
#: True medians per size (the larger block is stronger) and beta of the synthetic capacities.
MEDIANS = {0.5: 1.1, 4.0: 1.6}
BETA = 0.4

SECTIONS = ("verdict", "fits", "fragility", "size-effect", "exceedance", "stripes", "failures", "provenance")


# ----------------------------------------------------------------------------
# synthetic study directories
def ok_fit(engine: str, size: float, median: float | None = None, beta: float = BETA) -> dict:
    m = MEDIANS[size] if median is None else median
    return {
        "engine": engine,
        "size": size,
        "S": S[SIZES.index(size)],
        "median": m,
        "median_low": 0.9 * m,
        "median_high": 1.1 * m,
        "beta": beta,
        "beta_low": beta - 0.1,
        "beta_high": beta + 0.1,
        "status": "ok",
        "message": "maximum-likelihood fit (7 iterations)",
        "n_boot": 200,
        "n_failed": 0,
    }


def degenerate_fit(engine: str, size: float, status: str, message: str, median=math.nan, beta=math.nan) -> dict:
    nan = math.nan
    return {
        **ok_fit(engine, size),
        "median": median,
        "beta": beta,
        "median_low": nan,
        "median_high": nan,
        "beta_low": nan,
        "beta_high": nan,
        "status": status,
        "message": message,
        "n_failed": 200,
    }


def comparison(engine: str, size: float, ratio=(1.02, 0.95, 1.10), diff=(0.01, -0.06, 0.08)) -> dict:
    return {
        "engine": engine,
        "reference": REF,
        "size": size,
        "S": S[SIZES.index(size)],
        "median_ratio": ratio[0],
        "ratio_low": ratio[1],
        "ratio_high": ratio[2],
        "beta_diff": diff[0],
        "diff_low": diff[1],
        "diff_high": diff[2],
        # the runner's rule (studies.fragility.compare_fits): an interval excludes 1 or 0; NaN never disagrees
        "disagree": bool(ratio[1] > 1 or ratio[2] < 1 or diff[1] > 0 or diff[2] < 0),
    }


def make_study(
    root: Path,
    engines: tuple[str, ...] = (REF, "mujoco"),
    *,
    fits: list[dict] | None = None,
    comparisons: list[dict] | None = None,
    failed: dict[tuple[str, float], list[tuple[int, int]]] | None = None,
    all_failed: tuple[str, ...] = (),
    nonfinite: str = "null",
    seed: int = 0,
) -> Path:
    """Write a study directory; returns its path.

    ``failed`` maps (engine, size) to (stripe, motion) records that fail; every record of an engine in
    ``all_failed`` fails. Fits default to "ok" at the true medians and comparisons to agreement.
    """
    rng = np.random.default_rng(seed)
    rows = []
    failed = failed or {}
    for e in engines:
        for size, s in zip(SIZES, S, strict=True):
            capacity = MEDIANS[size] * np.exp(BETA * rng.standard_normal(N_MOTIONS))
            for j, x in enumerate(LEVELS):
                for m in range(N_MOTIONS):
                    bad = e in all_failed or (j, m) in failed.get((e, size), [])
                    over = bool(x >= capacity[m])
                    rows.append(
                        {
                            "engine": e,
                            "S": s,
                            "size": size,
                            "stripe": j,
                            "intensity": x,
                            "motion_id": m,
                            "motion_name": f"rdk-{m:03d}",
                            "amplitude_factor": x,
                            "theta_max_over_alpha": math.nan if bad else (math.inf if over else x / capacity[m]),
                            "overturned": False if bad else over,
                            "n_impacts": 0 if bad else 3,
                            "wall_s": 0.01,
                            "status": "failed" if bad else "ok",
                            "error": "EngineError: solver diverged (NaN in qpos)" if bad else "",
                            "cached": False,
                        }
                    )
    results = pd.DataFrame(rows)
    frag, exc = [], []
    for (e, size), d in results.groupby(["engine", "size"], sort=False):
        s = S[SIZES.index(size)]
        th = np.full((N_MOTIONS, len(LEVELS)), np.nan)
        ok = d[d["status"] == "ok"]
        th[ok["motion_id"], ok["stripe"]] = ok["theta_max_over_alpha"]
        valid = ~np.isnan(th)
        n, k = valid.sum(axis=0), np.isinf(th).sum(axis=0)
        p, lo, hi = proportion_intervals(k, n)
        frag.append(
            pd.DataFrame(
                {
                    "engine": e,
                    "size": size,
                    "S": s,
                    "stripe": np.arange(len(LEVELS)),
                    "intensity": LEVELS,
                    "n": n,
                    "n_overturned": k,
                    "p": p,
                    "p_low": lo,
                    "p_high": hi,
                }
            )
        )
        ex = exceedance(th, THRESHOLDS, valid)
        exc.append(ex.assign(engine=e, size=size, S=s, intensity=np.asarray(LEVELS)[ex["stripe"]]))
    if fits is None:
        fits = [ok_fit(e, size) for e in engines for size in SIZES]
    if comparisons is None:
        comparisons = [comparison(e, size) for e in engines if e != REF for size in SIZES]
    meta = {
        "scenario": {"name": "synthetic-study", "description": "Synthetic fragility study", "file": None},
        "specimen": {"name": "Bachmann 2017 block", "height_m": 0.5},
        "study": {
            "intensity": "pga",
            "intensity_label": LABEL,
            "levels": list(LEVELS),
            "prototype_heights": list(SIZES),
            "S": list(S),
            "thresholds": list(THRESHOLDS),
            "n_motions": N_MOTIONS,
            "n_boot": 200,
            "seed": 0,
            "ci": 0.95,
            "reference": REF,
            "histories": False,
        },
        "engines": {e: {"settings": {"dt": 0.001}, "version": f"{e}-1.0", "wall_s": 3.25} for e in engines},
        "n_records": len(results),
        "n_failed": int((results["status"] != "ok").sum()),
        "wall_s": 12.5,
        "provenance": {"versions": {"python": "3.11"}, "git_commit": "abc123", "created": "2025-01-01T00:00:00"},
    }
    root.mkdir(parents=True, exist_ok=True)
    results.to_parquet(root / "results.parquet", index=False)
    pd.concat(frag, ignore_index=True).to_parquet(root / "fragility.parquet", index=False)
    cols = ["engine", "size", "S", "stripe", "intensity", "threshold", "n", "k", "p", "p_low", "p_high"]
    pd.concat(exc, ignore_index=True)[cols].to_parquet(root / "exceedance.parquet", index=False)
    fj = {"fits": fits, "comparisons": comparisons}
    (root / "fragility.json").write_text(json.dumps(jsonable(fj, nonfinite=nonfinite), indent=1))
    (root / "study.json").write_text(json.dumps(jsonable(meta, nonfinite=nonfinite), indent=1))
    return root


def section(page: str, sid: str) -> str:
    m = re.search(rf'<section id="{sid}">(.*?)</section>', page, re.S)
    assert m, f"no section {sid}"
    return m.group(1)


def verdict_items(page: str) -> dict[tuple[str, float], str]:
    """(engine, size) -> the verdict sentence of the headline."""
    out = {}
    head = section(page, "verdict")
    for engine, body in re.findall(r"</span>([\w-]+)</span> against housner<ul>(.*?)</ul>", head, re.S):
        for size, text in re.findall(r"<li>at prototype height ([\d.]+) m[^:]*: (.*?)</li>", body, re.S):
            out[(engine, float(size))] = text
    return out


def table_row(section_html: str, engine: str, size_heading: str) -> str:
    """The fit-table row of an engine under the heading of a size."""
    block = section_html.split(f"<h3>{size_heading}")[1].split("<h3>")[0]
    m = re.search(rf"<tr><td><span class=\"eng\">.*?</span>{engine}</span>.*?</tr>", block, re.S)
    assert m, f"no row for {engine}"
    return m.group(0)


class _Checker(HTMLParser):
    """Counts unbalanced tags: a page whose sections nest wrongly shows up here."""

    VOID = {"meta", "link", "img", "br", "hr", "input"}

    def __init__(self):
        super().__init__()
        self.stack: list[str] = []
        self.errors: list[str] = []

    def handle_starttag(self, tag, attrs):
        if tag not in self.VOID:
            self.stack.append(tag)

    def handle_endtag(self, tag):
        if not self.stack or self.stack[-1] != tag:
            self.errors.append(f"</{tag}> closes {self.stack[-1] if self.stack else 'nothing'}")
        else:
            self.stack.pop()


# ----------------------------------------------------------------------------
# the page
def test_page_has_every_section_and_writes_report_html(tmp_path):
    d = make_study(tmp_path / "study")
    page = render_study_report(d)
    checker = _Checker()
    checker.feed(page)
    assert checker.errors == [] and checker.stack == []
    for sid in SECTIONS:
        assert f'<section id="{sid}">' in page
    # what was run
    lead = section(page, "verdict")
    assert "2 engines" in lead and "2 sizes" in lead and "5 stripes" in lead
    assert f"{N_MOTIONS} ground motions" in lead and f"{2 * 2 * 5 * N_MOTIONS} records" in lead
    assert "none failed" in lead and "12.5 s" in lead
    # figures: one fragility and one exceedance figure per size, one size figure; none failed to draw
    assert page.count("<img ") == 2 * len(SIZES) + 1
    assert "could not be drawn" not in page
    assert section(page, "stripes").count("<details>") == len(SIZES)
    assert "No record failed." in section(page, "failures")
    prov = section(page, "provenance")
    assert "mujoco-1.0" in prov and "dt = 0.001" in prov and "abc123" in prov
    # every ok fit's median with its interval, in the table of its size
    fits = section(page, "fits")
    row = table_row(fits, "mujoco", "Prototype height 4 m")
    assert f"{fmt_g(1.6, 3)} <span class=ci>[{fmt_g(0.9 * 1.6, 3)}, {fmt_g(1.1 * 1.6, 3)}]" in row
    assert "AGREE" in row
    # write: report.html in the directory by default, anywhere with `out`
    assert write_study_report(d) == d / "report.html"
    assert (d / "report.html").read_text(encoding="utf-8").startswith("<!DOCTYPE html>")
    other = write_study_report(d, tmp_path / "elsewhere" / "r.html")
    assert other.is_file()


def test_stripe_table_counts_each_engine_at_each_stripe(tmp_path):
    d = make_study(tmp_path / "study", seed=3)
    fr = pd.read_parquet(d / "fragility.parquet")
    stripes = section(render_study_report(d), "stripes")
    for r in fr.itertuples():
        assert f"{r.n_overturned} / {r.n}<br>" in stripes
    # one row per stripe and size, one column per engine
    assert stripes.count("<tr><td>") == len(LEVELS) * len(SIZES)


def test_disagreement_sentence_appears_exactly_when_a_comparison_disagrees(tmp_path):
    engines = (REF, "mujoco", "pybullet")
    comps = [
        comparison("mujoco", 0.5, ratio=(1.35, 1.2, 1.5)),  # medians disagree
        comparison("mujoco", 4.0),  # agree
        comparison("pybullet", 0.5, ratio=(1.1, 1.0, 1.2)),  # the interval touches 1: it contains 1, agree
        comparison("pybullet", 4.0, diff=(0.3, 0.1, 0.5)),  # betas disagree
    ]
    page = render_study_report(make_study(tmp_path / "s", engines, comparisons=comps))
    items = verdict_items(page)
    assert set(items) == {(e, s) for e in engines[1:] for s in SIZES}
    for c in comps:
        text = items[(c["engine"], c["size"])]
        assert (DISAGREE in text) == c["disagree"], (c, text)
    assert [c["disagree"] for c in comps] == [True, False, False, True]
    # the ratio and the difference are named with their intervals
    assert "median 1.35 times the reference's [1.2, 1.5]: " + DISAGREE in items[("mujoco", 0.5)]
    assert "beta within the interval" in items[("mujoco", 0.5)]
    assert (
        f"(difference {fmt_signed(0.3)} [{fmt_signed(0.1)}, {fmt_signed(0.5)}]): {DISAGREE}" in items[("pybullet", 4.0)]
    )
    assert "beta 0.3 above the reference's" in items[("pybullet", 4.0)]
    assert "median within the interval: ratio to the reference's 1.1 [1, 1.2] contains 1" in items[("pybullet", 0.5)]
    # one badge per engine: any disagreement at any size makes it DISAGREE
    head = section(page, "verdict")
    for engine in ("mujoco", "pybullet"):
        badge = re.search(rf'<li><span class="badge (\w+)">(\w+)</span> <span class="eng">.*?{engine}</span>', head)
        assert badge.group(2) == "DISAGREE"
    assert "AGREE" in table_row(section(page, "fits"), "mujoco", "Prototype height 4 m")
    assert "DISAGREE" in table_row(section(page, "fits"), "mujoco", "Prototype height 0.5 m")


def test_interval_ends_next_to_the_boundary_are_not_rounded_onto_it(tmp_path):
    # 0.9996 would print as "1" at three digits and -0.001 as "+0.00": the sentence would contradict itself
    comps = [comparison("mujoco", 0.5, ratio=(0.9, 0.8, 0.9996)), comparison("mujoco", 4.0, diff=(0.1, -0.001, 0.2))]
    items = verdict_items(render_study_report(make_study(tmp_path / "s", comparisons=comps)))
    assert f"median 0.9 times the reference's [0.8, 0.9996]: {DISAGREE}" in items[("mujoco", 0.5)]
    assert "beta within the interval: difference +0.10 [-0.001, +0.20] contains 0" in items[("mujoco", 4.0)]


def test_agreeing_engines_get_no_disagreement_sentence(tmp_path):
    page = render_study_report(make_study(tmp_path / "s"))
    assert DISAGREE not in page
    assert '<span class="badge pass">AGREE</span> <span class="eng">' in section(page, "verdict")


def test_the_verdict_is_the_studys_flag_and_a_file_whose_intervals_contradict_it_says_so(tmp_path):
    # the runner decides `disagree` by the rule that words the intervals; only an edited file can differ
    d = make_study(tmp_path / "s")
    fj = json.loads((d / "fragility.json").read_text())
    assert not any(c["disagree"] for c in fj["comparisons"])
    fj["comparisons"][0]["disagree"] = True  # mujoco at 0.5 m, whose intervals contain 1 and 0
    (d / "fragility.json").write_text(json.dumps(fj))
    page = render_study_report(d)
    assert "DISAGREE" in table_row(section(page, "fits"), "mujoco", "Prototype height 0.5 m")
    assert "AGREE" in table_row(section(page, "fits"), "mujoco", "Prototype height 4 m")
    items = verdict_items(page)
    assert "median within the interval" in items[("mujoco", 0.5)] and DISAGREE not in items[("mujoco", 0.5)]
    assert "fragility.json marks this comparison disagree = true, but its intervals say otherwise" in page


@pytest.mark.parametrize("nonfinite", ["null", "string"])
def test_degenerate_fit_shows_its_message_and_no_fitted_number(tmp_path, nonfinite):
    no_over = (
        "no record overturned at any stripe (0 of 100): the likelihood keeps rising as the median goes to infinity"
    )
    separated = "the data are perfectly separated: no overturn up to IM = 1.2, every record overturned from IM = 1.8"
    fits = [
        ok_fit(REF, 0.5),
        ok_fit(REF, 4.0),
        degenerate_fit("mujoco", 0.5, "no_overturn", no_over),
        # a step reports a median and beta = 0; they are not a maximum-likelihood fit and must not be printed
        degenerate_fit("mujoco", 4.0, "separated", separated, median=7.777, beta=0.0),
    ]
    # the bootstrap may still flag a disagreement from its replicates; with a degenerate point fit it is no verdict
    comps = [
        comparison("mujoco", 0.5, ratio=(math.nan,) * 3, diff=(math.nan,) * 3),
        comparison("mujoco", 4.0, ratio=(5.55, 4.4, 6.6)),
    ]
    assert comps[1]["disagree"] and not comps[0]["disagree"]
    page = render_study_report(make_study(tmp_path / "s", fits=fits, comparisons=comps, nonfinite=nonfinite))
    assert html.escape(no_over) in page and html.escape(separated) in page
    for number in ("7.78", "7.777", "5.55", "4.4", "6.6"):
        assert number not in page, number
    assert DISAGREE not in page
    items = verdict_items(page)
    assert "its fit is degenerate (no overturn" in items[("mujoco", 0.5)]
    assert "its fit is degenerate (separated" in items[("mujoco", 4.0)]
    # the replicates' flag is mentioned where it is set, without its numbers
    assert "replicates that could be fitted do flag a difference" in items[("mujoco", 4.0)]
    assert "flag a difference" not in items[("mujoco", 0.5)]
    fits_html = section(page, "fits")
    for heading in ("Prototype height 0.5 m", "Prototype height 4 m"):
        row = table_row(fits_html, "mujoco", heading)
        assert "no fit" in row and "AGREE" not in row
    assert "2 fits are degenerate" in section(page, "verdict")


def test_degenerate_reference_leaves_the_engine_without_verdict(tmp_path):
    msg = "every record overturned at every stripe (100 of 100): no maximum-likelihood fit"
    fits = [
        ok_fit(REF, 0.5),
        degenerate_fit(REF, 4.0, "all_overturn", msg),
        ok_fit("mujoco", 0.5),
        ok_fit("mujoco", 4.0),
    ]
    page = render_study_report(make_study(tmp_path / "s", fits=fits))
    items = verdict_items(page)
    assert "the reference's fit is degenerate (all overturn" in items[("mujoco", 4.0)]
    assert "median within the interval" in items[("mujoco", 0.5)]
    assert html.escape(msg) in page
    # not every size was evaluated, so the engine's badge is not AGREE
    assert re.search(r'<span class="badge na">not evaluated</span> <span class="eng">.*?mujoco', page)


def test_failed_records_are_listed(tmp_path):
    bad = [(2, 3), (2, 4), (4, 0)]
    d = make_study(tmp_path / "s", failed={("mujoco", 0.5): bad})
    page = render_study_report(d)
    fail = section(page, "failures")
    rows = re.findall(r"<tr><td>(.*?)</tr>", fail, re.S)
    assert len(rows) == len(bad)
    for (stripe, motion), row in zip(sorted(bad), rows, strict=True):
        cells = re.findall(r"<td>(.*?)</td>", "<td>" + row)
        assert "mujoco" in cells[0] and cells[1] == "0.5" and cells[2] == str(stripe)
        assert cells[3] == fmt_g(LEVELS[stripe], 4) and cells[4] == f"{motion}: rdk-{motion:03d}"
        assert "solver diverged (NaN in qpos)" in cells[5]
    assert "3 record(s) failed (mujoco at 0.5 m: 3)" in fail
    head = section(page, "verdict")
    assert '<span class="bad">3 failed</span>' in head and 'href="#failures"' in head
    # the stripe counts leave them out
    fr = pd.read_parquet(d / "fragility.parquet")
    n = fr[(fr["engine"] == "mujoco") & (fr["size"] == 0.5)].set_index("stripe")["n"]
    assert n[2] == N_MOTIONS - 2 and n[4] == N_MOTIONS - 1


def test_engine_that_failed_entirely_is_reported_not_raised(tmp_path, monkeypatch):
    monkeypatch.setattr(study_sections, "MAX_FAILURE_ROWS", 50)
    engines = (REF, "mujoco", "pybullet")
    fits = [ok_fit(e, s) for e in engines[:2] for s in SIZES]
    fits += [degenerate_fit("pybullet", s, "no_data", "no valid record at any stripe") for s in SIZES]
    comps = [comparison("mujoco", s) for s in SIZES]  # the runner has no comparison for pybullet
    d = make_study(tmp_path / "s", engines, fits=fits, comparisons=comps, all_failed=("pybullet",))
    page = render_study_report(d)
    n = len(LEVELS) * N_MOTIONS * len(SIZES)
    assert f"pybullet</span>: every one of its {n} records failed; no fit, nothing to compare." in page
    assert "Every record of <span" in section(page, "failures")
    assert "could not be drawn" not in page
    rows = re.findall(r"<tr><td>", section(page, "failures"))
    assert len(rows) == 50  # the table is cut at MAX_FAILURE_ROWS ...
    assert f"First 50 of {n} failed records." in page  # ... and says so


@pytest.mark.parametrize("missing", ["study.json", "fragility.parquet", "exceedance.parquet", "results.parquet"])
def test_a_study_directory_is_read_by_load_study_and_a_missing_file_is_named(tmp_path, missing):
    # one reader of the format (load_study), so one message, whichever of the two is asked
    d = make_study(tmp_path / "s")
    (d / missing).unlink()
    with pytest.raises(ValueError) as page_error:
        render_study_report(d)
    with pytest.raises(ValueError) as load_error:
        load_study(d)
    assert str(page_error.value) == str(load_error.value)
    assert f"not a study directory (no {missing}" in str(page_error.value)
    with pytest.raises(ValueError, match="not a study directory"):
        render_study_report(tmp_path / "nowhere")


# ----------------------------------------------------------------------------
# figures
def _series(ax, kind: str) -> dict[str, object]:
    return {ln.get_gid().split(":", 1)[1]: ln for ln in ax.lines if (ln.get_gid() or "").startswith(kind + ":")}


def test_fragility_figure_has_points_and_curves_per_engine(tmp_path):
    d = make_study(tmp_path / "s", (REF, "mujoco", "pybullet"))
    fr = pd.read_parquet(d / "fragility.parquet")
    fits = [
        ok_fit(REF, 0.5),
        ok_fit("mujoco", 0.5, median=1.3, beta=0.3),
        degenerate_fit("pybullet", 0.5, "no_overturn", "none overturned"),
    ]
    fig = study_figures.plot_fragility(fr, [StudyFit.from_json(f) for f in fits], 0.5, LABEL)
    assert isinstance(fig, Figure)
    (ax,) = fig.axes
    points, curves = _series(ax, "points"), _series(ax, "curve")
    assert sorted(points) == ["housner", "mujoco", "pybullet"]
    assert sorted(curves) == ["housner", "mujoco"]  # no median, no curve
    assert len(ax.containers) == 3
    assert ax.get_xscale() == "log" and ax.get_ylim() == (-0.02, 1.02)
    assert ax.get_xlabel() == LABEL and ax.get_ylabel() == "P[overturn] [-]"
    # the curve is the lognormal CDF; 1e-12 allows only floating-point rounding between two evaluations
    x, y = curves["mujoco"].get_data()
    np.testing.assert_allclose(y, sps.norm.cdf(np.log(x / 1.3) / 0.3), rtol=0, atol=1e-12)
    assert curves["mujoco"].get_linestyle() == "-"
    # the points are the stripes' p, shifted per engine by less than a third of the gap to the next stripe
    sub = fr[(fr["engine"] == "mujoco") & (fr["size"] == 0.5)].sort_values("stripe")
    px, py = points["mujoco"].get_data()
    np.testing.assert_array_equal(py, sub["p"].to_numpy())
    shifts = {e: np.log(np.asarray(points[e].get_data()[0]) / np.asarray(LEVELS)) for e in points}
    for sh in shifts.values():
        assert np.ptp(sh) < 1e-12  # the same shift at every stripe, up to rounding of exp and log
        assert abs(sh[0]) < np.min(np.diff(np.log(LEVELS))) / 3
    assert len({round(float(sh[0]), 9) for sh in shifts.values()}) == 3  # a different shift per engine
    # the legend names engine, median and beta, and says when there is no fit
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert "mujoco: median 1.3, \N{GREEK SMALL LETTER BETA} = 0.30" in labels
    assert "pybullet: no lognormal fit (no overturn)" in labels


def test_fragility_figure_dashes_a_step_and_uses_a_linear_axis_for_a_narrow_range(tmp_path):
    fr = pd.read_parquet(make_study(tmp_path / "s").joinpath("fragility.parquet"))
    fr = fr[fr["stripe"].between(1, 3)]  # 0.8 .. 1.8: a span of 2.25, below LOG_SPAN
    fits = [ok_fit(REF, 4.0), degenerate_fit("mujoco", 4.0, "separated", "a step", median=1.5, beta=0.0)]
    (ax,) = study_figures.plot_fragility(fr, [StudyFit.from_json(f) for f in fits], 4.0, LABEL).axes
    curves = _series(ax, "curve")
    assert ax.get_xscale() == "linear"
    assert curves["mujoco"].get_linestyle() == "--" and curves[REF].get_linestyle() == "-"
    x, y = curves["mujoco"].get_data()
    assert np.all(y[x < 1.5] == 0) and np.all(y[x > 1.5] == 1)


def test_size_effect_figure_has_one_series_per_engine():
    fits = [ok_fit(e, s, median=MEDIANS[s] * (1.2 if e == "mujoco" else 1.0)) for e in (REF, "mujoco") for s in SIZES]
    fits += [
        degenerate_fit("pybullet", 0.5, "separated", "a step", median=1.0, beta=0.0),
        degenerate_fit("pybullet", 4.0, "no_overturn", "none"),
    ]
    fig = study_figures.plot_size_effect([StudyFit.from_json(f) for f in fits], label=LABEL)
    assert isinstance(fig, Figure)
    (ax,) = fig.axes
    med, steps = _series(ax, "median"), _series(ax, "not-a-fit")
    assert sorted(med) == ["housner", "mujoco"] and sorted(steps) == ["pybullet"]
    assert len(ax.containers) == 2
    x, y = med["mujoco"].get_data()
    np.testing.assert_array_equal(y, [1.2 * MEDIANS[0.5], 1.2 * MEDIANS[4.0]])
    # x is the prototype height, shifted by a few percent so that the bars stand apart
    np.testing.assert_allclose(x, SIZES, rtol=0.3)
    assert ax.get_xscale() == "log" and ax.get_xlabel() == "prototype height [m]"
    assert LABEL in ax.get_ylabel()
    # error bars: the bootstrap interval of each median
    bars = ax.containers[[c.lines[0] for c in ax.containers].index(med["mujoco"])].lines[2][0]
    segs = bars.get_segments()
    np.testing.assert_allclose([s[:, 1] for s in segs], [[0.9 * v, 1.1 * v] for v in y], rtol=1e-12)
    steps_x, steps_y = steps["pybullet"].get_data()
    assert list(steps_y) == [1.0] and len(steps_x) == 1


def test_exceedance_figure_has_one_panel_per_threshold(tmp_path):
    d = make_study(tmp_path / "s", (REF, "mujoco", "pybullet"))
    ex = pd.read_parquet(d / "exceedance.parquet")
    fig = study_figures.plot_exceedance(ex, 4.0, LABEL)
    assert isinstance(fig, Figure)
    panels = [ax for ax in fig.axes if ax.get_visible()]
    assert len(panels) == len(THRESHOLDS)
    for ax, t in zip(panels, THRESHOLDS, strict=True):
        pts = _series(ax, "points")
        assert sorted(pts) == ["housner", "mujoco", "pybullet"] and len(ax.containers) == 3
        assert f"{t:g}" in ax.get_title() and ax.get_xlabel() == LABEL
        sub = ex[(ex["engine"] == "mujoco") & (ex["size"] == 4.0) & (ex["threshold"] == t)].sort_values("stripe")
        np.testing.assert_array_equal(pts["mujoco"].get_data()[1], sub["p"].to_numpy())
    # exceeding a lower threshold is at least as likely as a higher one (same records)
    p = [_series(ax, "points")["mujoco"].get_data()[1] for ax in panels]
    assert np.all(np.diff(np.vstack(p), axis=0) <= 0)
    assert len(fig.legends) == 1 and [t.get_text() for t in fig.legends[0].get_texts()] == [
        "housner",
        "mujoco",
        "pybullet",
    ]


def test_a_corrupt_study_file_is_one_line_naming_it(tmp_path):
    from housner.errors import DataFileError
    from housner.scenarios.studies.study import STUDY_FILES, load_study

    for name in STUDY_FILES[:-1]:
        (tmp_path / name).write_text("{ not what it should be")
    with pytest.raises(DataFileError) as e:
        load_study(tmp_path)
    msg = str(e.value)
    assert "\n" not in msg and "fragility.json" in msg and "run the study again" in msg
