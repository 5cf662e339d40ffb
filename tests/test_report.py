"""The HTML report: one self-contained page whose figures and numbers agree with independent computations."""

import base64
import inspect
import json
import subprocess
import sys
from html.parser import HTMLParser
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pandas as pd
import pytest
from scipy import stats as sps
from shared import windowed_sines

from housner import GroundMotion, Specimen
from housner.engines.analytic import HousnerEngine
from housner.engines.base import ENGINES, register_engine
from housner.engines.tuning import TuningResult
from housner.errors import DataFileError
from housner.reports import figures
from housner.reports.run import page as html
from housner.reports.run.sections import distribution as distribution_section
from housner.reports.run.sections import tuning as tuning_section
from housner.scenarios.execution.run_meta import RunMeta
from housner.scenarios.execution.rundir import provenance, write_run
from housner.scenarios.execution.runner import run_engines
from housner.scenarios.runs.chaos import RECORD_RTOL, chaos_floor, errors_from_dict, run_engine_errors
from housner.scenarios.runs.spread import AmplitudeFactor, EquivalentAmplitudes
from housner.scenarios.runs.view import BOOT_SEED
from housner.statistics import ensemble_stats as stats

ROOT = Path(__file__).resolve().parents[1]
SPEC = Specimen.bachmann2017()
CHROMIUM = Path("/usr/bin/chromium")


# ----------------------------------------------------------------------------
# engines registered for these tests: the analytic model with another r, and one that fails on a record
@register_engine("report-r80")
class R80Engine(HousnerEngine):
    """The analytic engine with r = 0.80 (a second engine whose results differ from the reference)."""

    def __init__(self, r: float = 0.80, substeps=None):
        super().__init__(r=r, substeps=substeps)


@register_engine("report-flaky")
class FlakyEngine(HousnerEngine):
    """The analytic engine (same r as the reference), except that it fails on the motion named 'm3'."""

    def _simulate(self, specimen, motion, effects):
        if motion.name == "m3":
            raise RuntimeError("solver diverged on purpose")
        return super()._simulate(specimen, motion, effects)


@pytest.fixture(autouse=True)
def _keep_registry():
    yield
    ENGINES.setdefault("report-r80", R80Engine)
    ENGINES.setdefault("report-flaky", FlakyEngine)


def shaking(n=12, seed=7):
    """Short windowed sines strong enough that some blocks rock, some overturn, some stay put."""
    return windowed_sines(n, seed)


SPREAD = {  # the layout of housner.scenarios.runs.spread.seed_spread after run.json
    "k": 3,
    "seeds": [1, 2, 3],
    "percentiles": {"25": [0.3, 0.35, 0.4], "50": [0.7, 0.75, 0.8], "75": ["inf", "inf", "inf"]},
    "overturn_fraction": [0.3, 0.32, 0.35],
    "overturn_fraction_range": [0.3, 0.32, 0.35],
    "summary": {"25": [0.3, 0.35, 0.4], "50": [0.7, 0.75, 0.8], "75": ["inf", "inf", "inf"]},
}


def make_run(out: Path, motions, engines, *, motions_meta=None, analysis=None, extra=None, scenario=None) -> Path:
    df, hist, info = run_engines(SPEC, motions, engines, jobs=1, use_cache=False, progress=False)
    meta = {
        "scenario": {"name": out.name, "description": "test run", "motions": {"source": "record"}, **(scenario or {})},
        "specimen": SPEC.describe(),
        "motions": motions_meta or {"source": "record", "S": 1.0},
        "n_motions": len(motions),
        "engines": info,
        "analysis": analysis or {"reference": "housner"},
        "failures": df[df.status != "ok"][["engine", "motion_id", "motion_name", "error"]].to_dict("records"),
        "wall_s": {"total": 1.0},
        "provenance": provenance(),
        **(extra or {}),
    }
    write_run(out, df, hist, motions, RunMeta.from_json(meta))
    return out


class Page(HTMLParser):
    """Tags, attributes, sections, images and tables (cell text) of a report."""

    def __init__(self, text: str):
        super().__init__(convert_charrefs=True)
        self.attrs: list[tuple[str, str, str]] = []
        self.sections: list[str] = []
        self.images: dict[str, list[str]] = {}
        self.tables: dict[str, list[list[list[str]]]] = {}
        self.tags: set[str] = set()
        self._section = ""
        self._cell: list[str] | None = None
        self.feed(text)

    def handle_starttag(self, tag, attrs):
        self.tags.add(tag)
        a = dict(attrs)
        for k, v in attrs:
            self.attrs.append((tag, k, v or ""))
        if tag == "section":
            self._section = a.get("id", "")
            self.sections.append(self._section)
        elif tag == "img":
            self.images.setdefault(self._section, []).append(a.get("src", ""))
        elif tag == "table":
            self.tables.setdefault(self._section, []).append([])
        elif tag == "tr":
            self.tables[self._section][-1].append([])
        elif tag in ("td", "th"):
            self._cell = []
        elif tag == "br" and self._cell is not None:
            self._cell.append(" ")

    def handle_endtag(self, tag):
        if tag in ("td", "th") and self._cell is not None:
            self.tables[self._section][-1][-1].append(" ".join("".join(self._cell).split()))
            self._cell = None

    def handle_data(self, data):
        if self._cell is not None:
            self._cell.append(data)

    def row(self, section: str, first_cell_startswith: str, table: int = 0) -> list[str]:
        for r in self.tables[section][table]:
            if r and r[0].startswith(first_cell_startswith):
                return r
        raise AssertionError(f"no row starting with {first_cell_startswith!r} in {section} table {table}")


@pytest.fixture(scope="module")
def shaken(tmp_path_factory):
    """A run of three engines on 12 motions, one failed record, the paper's Table 2 and a seed spread."""
    out = tmp_path_factory.mktemp("report") / "shaken"
    make_run(
        out,
        shaking(),
        {"housner": {}, "report-r80": {}, "report-flaky": {}},
        analysis={"reference": "housner", "paper_percentiles": {"25": 0.37, "50": 0.77, "75": "overturn"}},
        extra={
            "table2_spread": SPREAD,
            "engine_errors": run_engine_errors(SPEC, {"housner": {}, "report-r80": {}}, shaking()),
        },
    )
    path = html.write_report(out)
    return out, path, Page(path.read_text(encoding="utf-8"))


# ----------------------------------------------------------------------------
def test_one_self_contained_file(shaken):
    out, path, page = shaken
    assert path == out / "report.html"
    text = path.read_text(encoding="utf-8")
    assert text.startswith("<!DOCTYPE html>")
    # Nothing is fetched: no scripts, no external style sheets, every src/href is in-page or a data: URI.
    assert "script" not in page.tags
    for tag, key, value in page.attrs:
        if key in ("src", "href"):
            assert value.startswith(("#", "data:")), (tag, key, value[:80])
    assert "url(" not in text.split("</style>")[0].split("<style>")[1]
    assert "http://" not in text and "https://" not in text


def test_sections_and_table_of_contents(shaken):
    _, _, page = shaken
    expected = ["verdict", "specimen", "ensemble", "distribution", "agreement", "failures", "provenance", "glossary"]
    assert page.sections == expected  # no pulse or free-vibration section for a record ensemble
    toc = [v for tag, k, v in page.attrs if tag == "a" and k == "href" and v.startswith("#")]
    assert all(f"#{s}" in toc for s in expected)


def test_figures_are_embedded_pngs(shaken):
    _, _, page = shaken
    # CDF figure, agreement scatter and the time histories of the worst records.
    assert len(page.images["distribution"]) == 1
    assert len(page.images["agreement"]) == 2
    for srcs in page.images.values():
        for src in srcs:
            head, _, data = src.partition(",")
            assert head == "data:image/png;base64"
            png = base64.b64decode(data, validate=True)
            assert png[:8] == b"\x89PNG\r\n\x1a\n" and len(png) > 5000


def test_headline_numbers_agree_with_independent_computation(shaken):
    out, _, page = shaken
    df = pd.read_parquet(out / "results.parquet")
    ok = df[df.status == "ok"]
    ref = ok[ok.engine == "housner"]
    big = 1e6  # any value above every finite peak stands for an overturn in a rank statistic
    x_ref = np.where(ref.overturned, big, ref.theta_max_over_alpha)
    for engine in ("report-r80", "report-flaky"):
        mine = ok[ok.engine == engine]
        x = np.where(mine.overturned, big, mine.theta_max_over_alpha)
        row = page.row("verdict", engine)
        # KS distance: scipy on the stand-in values (exactly the statistic with overturns at +inf).
        ks = sps.ks_2samp(x, x_ref).statistic
        assert row[2].startswith(f"{ks:.3f}")
        # P[overturn] = k/n over the usable records, and its difference to the reference.
        p, p_ref = mine.overturned.mean(), ref.overturned.mean()
        assert row[3].startswith(f"{p:.2f}")
        assert row[4] in (f"{p - p_ref:+.3f}", "+0.000")
        # median of theta_max/alpha (numpy's linear percentile, inf for overturn)
        med = np.percentile(x, 50)
        assert row[5].startswith("overturn" if med > x[x < big].max(initial=0) else f"{med:.3f}")
        assert row[1] == (f"{len(mine)} / {int((df.engine == engine).sum() - len(mine))}")


def test_verdict_marks_failed_records(shaken):
    _, path, page = shaken
    # The flaky engine is the reference model itself, one record short: its KS distance to the reference
    # is at most 1/12 (one record moves an ECDF of 12 by 1/12), so it meets the KS tolerance; it still
    # fails, because a failed record fails the verdict (as in housner.reports.assertions.runs).
    row = page.row("verdict", "report-flaky")
    assert float(row[2].split()[0]) <= 1 / 12 + 1e-9
    assert row[-1] == "FAILS"
    assert row[1] == "11 / 1"
    line = next(li for li in path.read_text().split("<li>") if "report-flaky</span>:" in li).split("</li>")[0]
    # one badge, and the figure that decided it: the failed record, not the KS distance that passed
    assert line.count('class="badge') == 1 and '<span class="badge fail">FAILS</span>' in line
    assert "records failed to run: <strong>1 failed record</strong>" in line


def test_failed_records_are_listed(shaken):
    _, _, page = shaken
    rows = page.tables["failures"][0]
    assert rows[0] == ["engine", "motion", "name", "error"]
    assert len(rows) == 2
    assert rows[1][:3] == ["report-flaky", "3", "m3"]
    assert "RuntimeError: solver diverged on purpose" in rows[1][3]


def test_percentile_tables_show_paper_and_spread(shaken):
    out, _, page = shaken
    tables = page.tables["distribution"]
    header = tables[0][0]
    assert header[:2] == ["percentile", "seed paper (numerical, Table 2)"]
    assert page.row("distribution", "25th")[1] == "0.37"
    assert page.row("distribution", "75th")[1] == "overturn"
    # the reference's 25th percentile, numpy's linear rule on the usable records
    df = pd.read_parquet(out / "results.parquet")
    ref = df[(df.engine == "housner") & (df.status == "ok")]
    v = np.where(ref.overturned, np.inf, ref.theta_max_over_alpha)
    q25 = np.percentile(np.where(np.isinf(v), 1e6, v), 25)
    assert page.row("distribution", "25th")[2].startswith(f"{q25:.2f}")
    spread = tables[-1]
    assert spread[0] == ["", "min", "median", "max"]
    assert spread[1] == ["25th", "0.30", "0.35", "0.40"]
    assert spread[3] == ["75th", "overturn", "overturn", "overturn"]


def test_agreement_table_counts_records(shaken):
    out, _, page = shaken
    df = pd.read_parquet(out / "results.parquet")
    wide = df[df.status == "ok"].pivot(index="motion_id", columns="engine", values="overturned")
    both = wide[["report-r80", "housner"]].dropna()
    same = float((both["report-r80"] == both["housner"]).mean())
    row = page.row("agreement", "report-r80")
    assert row[5] == str(len(both))
    assert row[6] == f"{same:.0%}"


def test_agreement_table_gives_the_chaos_floor(shaken):
    """The floor cell: the analytic model's self-agreement under the engine's measured errors, by the report's rule."""
    out, path, page = shaken
    text = path.read_text(encoding="utf-8")
    errs = json.loads((out / "run.json").read_text())["engine_errors"]
    # the R80 engine keeps r = 0.80: its measured r error is 0.80 / 0.9465 - 1 = -15.5 % at every amplitude
    assert errs["report-r80"]["eps_r"] == pytest.approx(1 - 0.80 / SPEC.r_housner, abs=2e-3)
    df = pd.read_parquet(out / "results.parquet")
    ok = set(df[(df.engine == "housner") & (df.status == "ok")].motion_id) & set(
        df[(df.engine == "report-r80") & (df.status == "ok")].motion_id
    )
    ms = shaking()
    fl = chaos_floor(
        SPEC, [ms[i] for i in sorted(ok)], errors_from_dict(errs["report-r80"]), rtol=RECORD_RTOL, atol=0.0
    )
    row = page.row("agreement", "report-r80")
    # the floor is the lowest of the four perturbed shares (what the verdict is decided against), their range beside
    assert row[8] == f"{fl.share_min:.0%} (of {fl.share_min:.0%}\u2013{fl.share_max:.0%})"
    assert f"chaos floor of {fl.share_min:.0%}" in text and ("at the floor" in text or "below the floor" in text)


def test_cdf_figure_stops_at_one_minus_overturn_probability():
    samples = {"a": np.array([0.1, 0.4, 0.5, np.inf, np.inf]), "b": np.array([0.2, 0.3, 0.6, 0.9, np.inf])}
    fig = figures.plot_cdfs(samples, reference="a")
    curves = {ln.get_label().split(" ")[0]: ln for ln in fig.axes[0].get_lines() if "n=" in ln.get_label()}
    # The empirical CDF over all records ends at 1 - k/n (seed Fig. 10): 3/5 and 4/5 here.
    assert curves["a"].get_ydata()[-1] == pytest.approx(0.6, abs=1e-12)
    assert curves["b"].get_ydata()[-1] == pytest.approx(0.8, abs=1e-12)
    # and the steps sit at the finite values
    assert list(curves["a"].get_xdata()[1:4]) == [0.1, 0.4, 0.5]


def test_free_vibration_report_measures_each_engines_r(tmp_path):
    releases = [0.3, 0.7]
    motions = [GroundMotion.free_vibration(a * SPEC.alpha, 4.0, 0.002, name=f"release {a}") for a in releases]
    out = make_run(
        tmp_path / "fv",
        motions,
        {"housner": {}, "report-r80": {}},
        motions_meta={"source": "free_vibration", "theta0_over_alpha": releases},
    )
    page = Page(html.render_report(out))
    assert "free-vibration" in page.sections
    assert len(page.images["free-vibration"]) == 2  # the histories and r per impact
    # Housner's model loses exactly 1 - r of the energy at every impact (seed eq. 8): the report's fit
    # from the stored histories must give back r_housner = 0.94652 and 0.80. The analytic solver locates
    # impacts to ~1e-9 and histories are stored in float32 (relative 6e-8), so 4 decimals are exact.
    for a in releases:
        row = page.row("free-vibration", f"{a:.2f}")
        assert row[1].startswith(f"r = {SPEC.r_housner:.4f}")
        assert row[2].startswith("r = 0.8000")
        # p from the exact half-cycle durations is the specimen's p
        assert f"p = {SPEC.p:.4f} 1/s" in row[1]


def test_pulse_report_draws_rocking_spectra(tmp_path):
    from housner.pulse_response import pulses

    w, a = np.meshgrid([2.0, 4.0, 8.0], [1.5, 3.0, 5.0], indexing="ij")
    motions = []
    for wi, ai in zip(w.ravel(), a.ravel(), strict=True):
        g = pulses.ricker(ai * SPEC.uplift_acceleration, wi * SPEC.p, kind="symmetric", dt=0.002)
        motions.append(GroundMotion(g.acc, g.dt, f"ricker {wi} {ai}"))
    meta = {"source": "pulses", "pulse": "symmetric_ricker", "omega_ratio": w.ravel().tolist()}
    meta["accel_ratio"] = a.ravel().tolist()
    out = make_run(tmp_path / "pulses", motions, {"housner": {}, "report-r80": {}}, motions_meta=meta)
    page = Page(html.render_report(out))
    assert "rocking-spectra" in page.sections
    assert len(page.images["rocking-spectra"]) == 1
    df = pd.read_parquet(out / "results.parquet")
    wide = df.pivot(index="motion_id", columns="engine", values="overturned")
    differ = int((wide["housner"] != wide["report-r80"]).sum())
    assert page.row("rocking-spectra", "report-r80") == ["report-r80", "9", str(differ)]


def test_written_tables_from_any_engines(tmp_path, monkeypatch):
    """Only results.parquet, unknown engine names, no run.json: the page still renders, with a stand-in reference."""
    ref = np.linspace(0.05, 0.95, 20)
    other = ref + 1.0  # every value beyond the reference's largest: the CDFs never overlap, KS = 1
    rows = [
        {"engine": e, "motion_id": i, "theta_max_over_alpha": float(v), "overturned": False, "status": "ok"}
        for e, vals in (("alpha-engine", ref), ("beta-engine", other))
        for i, v in enumerate(vals)
    ]
    out = tmp_path / "bare"
    out.mkdir()
    pd.DataFrame(rows).to_parquet(out / "results.parquet")
    monkeypatch.setattr(tuning_section, "TUNING_DIR", tmp_path)
    tuning = {
        "engine": "beta-engine",
        "target_r": 0.9465,
        "rtol": 0.005,
        "settings": {"stiffness": 1e6},
        "met": False,
        "worst_rel_error": 0.012,
        "table": {"amplitude": [0.2, 0.5, 0.8], "r_engine": [0.95, 0.94, 0.935]},
        "date": "2017-06-15",
        "version": "9.9",
    }
    (tmp_path / "tuning-beta-engine.json").write_text(json.dumps(tuning))
    text = html.render_report(out)
    page = Page(text)
    assert "not in this run" in text  # the requested reference "housner" is absent
    row = page.row("verdict", "beta-engine")
    assert row[2].startswith("1.000")
    assert row[-1] == "FAILS"
    assert page.row("verdict", "alpha-engine")[-1] == "reference"
    # the tuning file is read: settings (the run recorded none), target, the failed check in words, verdict
    tuned = page.row("specimen", "beta-engine", table=-1)
    assert tuned[1] == "stiffness = 1000000.0 (the run recorded no settings)"
    assert tuned[2] == "0.9465"
    assert tuned[3].startswith("NOT MET: r of the first impact, 0.2-0.8 α: worst -1.22% at 0.8 α")
    assert tuned[4] == "NOT MET"
    assert len(page.images["specimen"]) == 1


def test_ensemble_spectra_get_the_prototype_motions(tmp_path, monkeypatch):
    """motions.npz holds model-scale motions; the spectra figure is given them back at prototype scale."""
    from housner.reports.run import ground_figures
    from housner.reports.run.sections import ensemble

    S = 10.0
    model = [m.to_model_scale(S) for m in shaking(3)]
    meta = {"source": "rdk", "S": S, "seed": 1, "record": {"name": "elcentro-peer1999", "dt": 0.01, "n": 4000}}
    meta["rdk_params"] = {"Ia_m_s": 1.7, "D5_95_s": 24.1, "zeta_f": 0.125, "model": "Rezaeian & Der Kiureghian (2010)"}
    scenario = {"motions": {"source": "rdk", "record": "elcentro"}}
    out = make_run(tmp_path / "rdk", model, {"housner": {}}, motions_meta=meta, scenario=scenario)
    seen = {}
    real = ground_figures.plot_ensemble_spectra

    def spy(record, motions, **kw):
        seen.update(dt=[m.dt for m in motions], n=[m.n for m in motions], S=kw.get("S"), record=record.name)
        return real(record, motions, **kw)

    monkeypatch.setattr(ensemble, "plot_ensemble_spectra", spy)
    page = Page(html.render_report(out))
    # time stretched back by sqrt(S) (seed eq. 9), samples untouched
    assert seen["dt"] == pytest.approx([0.002] * 3, rel=1e-12)
    assert seen["n"] == [m.n for m in model]
    assert seen["S"] == S
    assert seen["record"].startswith("elcentro")
    assert len(page.images["ensemble"]) == 1
    assert page.row("ensemble", "D", table=-1)[1:3] == ["24.1", "s"]
    assert page.row("ensemble", "ζ", table=-1)[1:3] == ["0.125", "–"]


def test_missing_run_directory_names_the_path(tmp_path):
    with pytest.raises(DataFileError, match="results.parquet"):
        html.render_report(tmp_path)
    with pytest.raises(DataFileError, match="not a directory"):
        html.render_report(tmp_path / "nowhere")


def test_verdict_tolerances_are_those_of_the_assertions():
    from housner.reports.assertions.runs import assert_cdf_agreement

    params = inspect.signature(assert_cdf_agreement).parameters
    # the headline's tolerances are housner.statistics.ensemble_stats' (the view reads them from there), the
    # assertions' defaults
    from housner.statistics.ensemble_stats import KS_MAX, OVERTURN_TOL

    assert KS_MAX == params["ks_max"].default
    assert OVERTURN_TOL == params["overturn_tol"].default


# ----------------------------------------------------------------------------
# the page in a real browser
SCRIPT = ROOT / "scripts" / "check_report_browser.py"


@pytest.mark.browser
@pytest.mark.skipif(not CHROMIUM.exists(), reason="needs Debian's chromium (apt-get install -y chromium)")
def test_report_loads_in_chromium_without_console_errors(shaken, tmp_path):
    _, path, _ = shaken
    shot = tmp_path / "cdf.png"
    res = subprocess.run(
        [sys.executable, str(SCRIPT), str(path), "--screenshot", str(shot), "--section", "distribution"],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert res.returncode == 0, res.stdout + res.stderr
    assert "OK" in res.stdout
    png = shot.read_bytes()
    assert png[:8] == b"\x89PNG\r\n\x1a\n"
    # the section photographed is at least as wide as the CDF figure (about 830 px at 110 dpi)
    width = int.from_bytes(png[16:20], "big")
    assert width >= 800


@pytest.mark.browser
@pytest.mark.skipif(not CHROMIUM.exists(), reason="needs Debian's chromium (apt-get install -y chromium)")
def test_browser_check_fails_on_console_errors_and_broken_images(tmp_path):
    bad = tmp_path / "bad.html"
    bad.write_text(
        "<!DOCTYPE html><html><head><title>bad</title></head><body>"
        '<img src="missing.png" alt="missing figure">'
        "<script>console.error('boom from the page')</script></body></html>"
    )
    res = subprocess.run([sys.executable, str(SCRIPT), str(bad)], capture_output=True, text=True, timeout=120)
    assert res.returncode == 1
    assert "boom from the page" in res.stderr
    assert "missing figure" in res.stderr  # the broken image is named by its alt text
    res = subprocess.run(
        [sys.executable, str(SCRIPT), str(tmp_path / "absent.html")], capture_output=True, text=True, timeout=60
    )
    assert res.returncode == 1
    assert "page not found" in res.stderr


# ----------------------------------------------------------------------------
# the tuning summary: series per sample step, settings once, what is not met in words
def tuning_file(engine: str, settings: dict, *, decay_40=-0.14) -> dict:
    """A tuning file as ``housner tune`` writes it: two sample steps, amplitudes interleaved as the tuner runs them."""
    amps = [0.2, 0.5, 0.9]
    small = [0.02, 0.1]
    r = {0.001: [0.947, 0.946, 0.9455], 0.00316: [0.9462, 0.9468, 0.9461]}
    table = {"dt": [], "amplitude": [], "r_engine": [], "r_target": [], "rel_error": []}
    small_table = {k: [] for k in table}
    for dt in (0.001, 0.00316):
        for a, x in zip(amps, r[dt], strict=True):
            for k, v in zip(table, (dt, a, x, 0.9465, x / 0.9465 - 1), strict=True):
                table[k].append(v)
        for a in small:
            for k, v in zip(small_table, (dt, a, 0.946, 0.9465, 0.946 / 0.9465 - 1), strict=True):
                small_table[k].append(v)
    decay = {"dt": [0.001] * 4, "impacts": [10, 20, 30, 40], "peak_analytic": [0.056, 0.032, 0.018, 0.0106]}
    decay["rel_error"] = [0.001, -0.031, -0.081, decay_40]
    decay["peak_engine"] = [p * (1 + e) for p, e in zip(decay["peak_analytic"], decay["rel_error"], strict=True)]
    return {
        "engine": engine,
        "target_r": 0.9465,
        "rtol": 0.005,
        "settings": settings,
        "met": abs(decay_40) <= 0.05,
        "worst_rel_error": 0.0011,
        "table": table,
        "small_table": small_table,
        "decay_table": decay,
        "date": "2026-11-21",
        "version": "0.1.0",
    }


@pytest.fixture(scope="module")
def tuned_run(tmp_path_factory):
    """The shaken run's engines with tuning files: report-r80 tuned to its own settings, not met (free decay)."""
    base = tmp_path_factory.mktemp("tuned")
    out = make_run(base / "run", shaking(), {"housner": {}, "report-r80": {}})
    tdir = base / "tuning"
    tdir.mkdir()
    settings = json.loads((out / "run.json").read_text())["engines"]["report-r80"]["settings"]
    (tdir / "tuning-report-r80.json").write_text(json.dumps(tuning_file("report-r80", settings)))
    return out, tdir


def test_tuning_series_are_one_line_per_sample_step_sorted_by_amplitude(tuned_run, monkeypatch):
    out, tdir = tuned_run
    monkeypatch.setattr(tuning_section, "TUNING_DIR", tdir)
    seen = {}
    real = figures.plot_tuning

    def spy(curves, **kw):
        seen["curves"], seen["kw"] = curves, kw
        return real(curves, **kw)

    monkeypatch.setattr(figures, "plot_tuning", spy)
    page = Page(html.render_report(out))
    assert len(page.images["specimen"]) == 1
    series = seen["curves"]["report-r80"]
    # one series per sample step, the small amplitudes joined to the large ones, each sorted by amplitude
    assert sorted(series) == ["1 ms sampling", "3.16 ms sampling"]
    for a, _ in series.values():
        assert list(a) == [0.02, 0.1, 0.2, 0.5, 0.9]
    assert list(series["1 ms sampling"][1]) == [0.946, 0.946, 0.947, 0.946, 0.9455]
    # and the figure draws them so: every line of the r panel runs left to right
    fig = real(seen["curves"], **seen["kw"])
    lines = [ln for ln in fig.axes[0].get_lines() if len(ln.get_xdata()) > 2]
    assert len(lines) == 2
    for ln in lines:
        assert np.all(np.diff(ln.get_xdata()) > 0)
    # the free-decay check is drawn too, with its tolerance
    assert seen["kw"]["decay_rtol"] == pytest.approx(0.05)
    assert list(seen["kw"]["decay"]["report-r80"]["1 ms sampling"][0]) == [10, 20, 30, 40]


def test_real_tuning_files_give_monotone_series():
    for engine in ("mujoco", "pybullet"):
        d = json.loads((ROOT / "engines" / "models" / f"tuning-{engine}.json").read_text())
        curves, decay = tuning_section._tuning_series(TuningResult.from_json(d))
        n_steps = len(set(d["table"]["dt"]))
        assert len(curves) == n_steps and len(decay) == n_steps
        for a, _ in curves.values():
            assert np.all(np.diff(a) > 0), engine
            assert a.size == (len(d["table"]["dt"]) + len(d["small_table"]["dt"])) // n_steps


def test_engine_settings_are_printed_once(tuned_run, monkeypatch):
    out, tdir = tuned_run
    monkeypatch.setattr(tuning_section, "TUNING_DIR", tdir)
    text = html.render_report(out)
    page = Page(text)
    # the engines table lists r = 0.8 once; the tuning table refers to it instead of repeating it
    assert text.count("<code>r = 0.8</code>") == 1
    assert page.row("specimen", "report-r80", table=-1)[1] == "the run's settings (above)"
    # a run that differs from its tuning says where
    d = tuning_file("report-r80", {"r": 0.75, "substeps": None})
    (tdir / "tuning-report-r80.json").write_text(json.dumps(d))
    try:
        row = Page(html.render_report(out)).row("specimen", "report-r80", table=-1)
    finally:
        settings = json.loads((out / "run.json").read_text())["engines"]["report-r80"]["settings"]
        (tdir / "tuning-report-r80.json").write_text(json.dumps(tuning_file("report-r80", settings)))
    assert row[1] == "the run differs: r: tuned 0.75, run 0.8"


def test_a_tuning_check_not_met_is_explained_under_the_verdict(tuned_run, monkeypatch):
    out, tdir = tuned_run
    monkeypatch.setattr(tuning_section, "TUNING_DIR", tdir)
    text = html.render_report(out)
    page = Page(text)
    row = page.row("verdict", "report-r80")
    head = next(li for li in text.split("<li>") if "report-r80</span>:" in li)
    assert "1 tuning check not met (below)" in head
    line = next(c for c in text.split('<div class="caveat">')[1:] if "report-r80</span>" in c.split("</strong>")[0])
    # what was not met, by how much, against what
    assert "Tuning not met" in line
    assert "after 40 impacts is -14.0% off the analytic 0.0106 &alpha;" in line
    assert "accepted &plusmn;5%" in line
    # and what it means for the verdict, with the verdict's own figure
    ks = float(row[2].split()[0])
    if row[-1] in ("AGREES", "ENSEMBLE ONLY"):
        assert "It does not change this verdict" in line and f"KS {ks:.3f}" in line
        # records of the reference at or below the largest failing peak (0.018 alpha) are counted
        df = pd.read_parquet(out / "results.parquet")
        ref = df[(df.engine == "housner") & (df.status == "ok")].theta_max_over_alpha.to_numpy()
        assert f"{int(np.sum(ref <= 0.018))} of the {ref.size} records peak there" in line
    else:
        assert "fails on its own criteria as well" in line
    # a met tuning adds nothing
    (tdir / "tuning-report-r80.json").write_text(json.dumps(tuning_file("report-r80", {}, decay_40=-0.02)))
    try:
        again = html.render_report(out)
    finally:
        settings = json.loads((out / "run.json").read_text())["engines"]["report-r80"]["settings"]
        (tdir / "tuning-report-r80.json").write_text(json.dumps(tuning_file("report-r80", settings)))
    assert "Tuning not met" not in again and "tuning check not met" not in again


def test_cdf_legend_names_the_overturn_strip_and_the_line_at_one():
    samples = {"a": np.array([0.1, 0.4, 0.5, np.inf]), "b": np.array([0.2, 0.3, 0.6, 0.9])}
    fig = figures.plot_cdfs(samples, reference="a")
    texts = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    assert any(t.startswith("overturned") and "P[overturn]" in t for t in texts), texts
    assert any(r"$\theta/\alpha$ = 1" in t for t in texts), texts


# ----------------------------------------------------------------------------
# Table 2: the gap to the paper and its measured cause
def test_record_against_itself_is_the_median_with_the_same_spectrum():
    from housner.engines.analytic import HousnerEngine as Analytic
    from housner.scenarios.runs.spread import record_against_ensemble

    rec = shaking(1)[0]
    S = 10.0
    same = [rec.to_model_scale(S)] * 4
    g = record_against_ensemble(SPEC, rec, same, S)
    x = Analytic().simulate(SPEC, rec.to_model_scale(S)).theta_max_over_alpha
    assert g.record_theta_max_over_alpha == pytest.approx(x, rel=1e-12)
    assert g.record_percentile == 50.0  # all ties, counted half
    assert g.band_ratio_min == pytest.approx(1.0, rel=1e-9) and g.band_ratio_max == pytest.approx(1.0, rel=1e-9)
    # half the amplitude: spectra are linear, and the record beats every member
    half = [m.scaled(amplitude=0.5) for m in same]
    g = record_against_ensemble(SPEC, rec, half, S)
    assert g.band_ratio_min == pytest.approx(0.5, rel=1e-9) and g.short_ratio_max == pytest.approx(0.5, rel=1e-9)
    assert g.arias_ensemble_mean_m_s == pytest.approx(0.25 * g.arias_record_m_s, rel=1e-9)
    assert g.record_percentile == (100.0 if x > 0 else 50.0)
    assert g.p_prototype_1_s == pytest.approx(SPEC.p / np.sqrt(S))
    assert g.omega_ratio_band == pytest.approx(
        [2 * np.pi / (1.25 * SPEC.p / np.sqrt(S)), 2 * np.pi / (0.5 * SPEC.p / np.sqrt(S))]
    )


def test_table2_says_whether_the_paper_lies_within_the_spread(shaken):
    _, path, _ = shaken
    text = path.read_text()
    gap = text.split('id="table2-gap"')[1]
    # SPREAD holds the paper's 0.37 / 0.77 / overturn between its min and max
    assert "lie within the spread of independent ensembles" in gap
    assert "0.30&ndash;0.40 / 0.70&ndash;0.80 / overturn&ndash;overturn" in gap
    # no record behind these motions: no cause is claimed
    assert "No measured cause on this page" in gap


@pytest.fixture(scope="module")
def rdk_run(tmp_path_factory):
    """Model-scale motions said to be simulated from El Centro, the paper's Table 2 and a spread far below it."""
    S = 10.0
    model = [m.to_model_scale(S) for m in shaking(8, seed=3)]
    meta = {"source": "rdk", "S": S, "seed": 1, "record": {"name": "elcentro-peer1999", "dt": 0.01, "n": 4000}}
    spread = {**SPREAD, "summary": {"25": [0.1, 0.12, 0.14], "50": [0.2, 0.22, 0.24], "75": [0.3, 0.32, 0.34]}}
    out = make_run(
        tmp_path_factory.mktemp("rdk") / "rdk",
        model,
        {"housner": {}},
        motions_meta=meta,
        scenario={"motions": {"source": "rdk", "record": "elcentro"}},
        analysis={"reference": "housner", "paper_percentiles": {"25": 0.37, "50": 0.77, "75": "overturn"}},
        extra={"table2_spread": spread},
    )
    return out, model, S


def test_table2_states_the_records_own_peak_and_rank(rdk_run):
    from housner.engines.analytic import HousnerEngine as Analytic
    from housner.scenarios.motions.elastic import ensemble_spectra, response_spectrum
    from housner.scenarios.motions.records import RECORDS

    out, model, S = rdk_run
    text = html.render_report(out)
    gap = text.split('id="table2-gap"')[1].split("</section>")[0]
    assert "lie outside the spread of independent ensembles at every percentile" in gap
    # the record through the same model at model scale, independently
    rec = RECORDS["elcentro"]()
    x = Analytic().simulate(SPEC, rec.to_model_scale(S)).theta_max_over_alpha
    df = pd.read_parquet(out / "results.parquet")
    v = df[df.engine == "housner"].theta_max_over_alpha.to_numpy()
    pct = 100 * (np.sum(v < x) + 0.5 * np.sum(v == x)) / v.size
    assert f"&theta;<sub>max</sub>/&alpha; = <strong>{x:.2f}</strong>" in gap
    assert f"higher than {'only ' if pct < 50 else ''}{pct:.0f} % of the {v.size} motions" in gap
    # the ensemble's mean 5 %-damped PSa against the record's, 0.5-1.25 s at prototype scale
    T = np.geomspace(0.5, 1.25, 16)
    psa, _ = ensemble_spectra([m.scaled(time=np.sqrt(S)) for m in model], T, 0.05)
    ratio = psa.mean(axis=0) / response_spectrum(rec, T, 0.05)[0]
    assert f"{ratio.min():.2f}&ndash;{ratio.max():.2f}" in gap
    assert "between 0.5 and 1.25 s" in gap


def test_table2_gives_the_factors_that_reach_the_papers_percentiles(rdk_run):
    from housner.scenarios.runs.spread import equivalent_amplitude

    out, model, S = rdk_run
    gap = html.render_report(out).split('id="table2-gap"')[1].split("</section>")[0]
    f = equivalent_amplitude(SPEC, model, {25: 0.37, 50: 0.77, 75: float("inf")}, seed=BOOT_SEED)
    assert "How much stronger, in effect, the paper's motions were" in gap
    for q, d in f.factors.items():
        label = f"for the {stats.percentile_label(q)}"
        if np.isfinite(d.factor):
            assert f"&times;{d.factor:.2f} [{d.low:.2f}, {d.high:.2f}] {label}" in gap
        else:  # these weak motions do not reach the paper's row within the search range
            assert f"none within &times;1/8&ndash;8 {label}" in gap


@pytest.mark.parametrize(
    "factors, says",
    [
        # the 25th needs less than the median, intervals apart: the paper's distribution is wider
        ({25: (1.2, 1.15, 1.24), 50: (1.58, 1.46, 1.58)}, ["No single factor does", "1.15&ndash;1.24", "wider"]),
        ({25: (1.6, 1.5, 1.7), 50: (1.2, 1.1, 1.3)}, ["No single factor does", "narrower"]),
        # overlapping intervals: one factor (the overlap) moves the whole row
        ({25: (1.3, 1.2, 1.4), 50: (1.35, 1.25, 1.5)}, ["One factor, 1.25&ndash;1.40, reaches them all"]),
    ],
)
def test_the_factor_line_says_whether_one_factor_reaches_the_whole_row(factors, says):
    f = EquivalentAmplitudes(
        factors={q: AmplitudeFactor(a, lo, hi, 0.5) for q, (a, lo, hi) in factors.items()},
        grid=(),
        evaluations=0,
        step=0.02,
        ci=0.9,
        engine="housner",
        n=100,
    )
    text = distribution_section._factor_line(SimpleNamespace(paper_factors=f))
    for s in says:
        assert s in text, text


# ----------------------------------------------------------------------------
# the one verdict: the page, the command line and users' CI ask the same
@register_engine("report-twin")
class TwinEngine(HousnerEngine):
    """The analytic engine itself under another name: it must agree with the reference on every record."""


def test_assert_verdict_says_what_the_page_says(shaken, tmp_path):
    from housner.reports.assertions.verdict import VerdictError, assert_verdict

    out, _, page = shaken
    # 12 motions: the flaky engine fails (a failed record), the r = 0.80 one is inconclusive (fewer than 20 records)
    for engine, badge in (("report-flaky", "FAILS"), ("report-r80", "INCONCLUSIVE")):
        assert page.row("verdict", engine)[-1] == badge
        with pytest.raises(VerdictError, match=f"{engine} against housner: {badge}: ") as e:
            assert_verdict(out, engine)
        assert e.value.verdict.badge == badge
    # 20 motions and a twin of the reference: KS 0, every record agrees, whatever the floor: AGREES
    engines, motions = {"housner": {}, "report-twin": {}}, shaking(20, seed=3)
    twin = make_run(
        tmp_path / "twin", motions, engines, extra={"engine_errors": run_engine_errors(SPEC, engines, motions)}
    )
    assert assert_verdict(twin, "report-twin", at_least="agrees").badge == "AGREES"
    table = pd.read_parquet(twin / "results.parquet")
    table.attrs["source"] = str(twin / "results.parquet")  # as the housner_results fixture gives it
    assert assert_verdict(table, "report-twin").kind == "agrees"
    with pytest.raises(ValueError, match="unknown verdict level `at_least` 'exact'"):
        assert_verdict(twin, "report-twin", at_least="exact")
    with pytest.raises(ValueError, match="did you mean 'report-twin'"):
        assert_verdict(twin, "report-twn")
