"""The outcome report (housner.reports.diagnosis.outcomes) of a synthetic campaign of outcome records.

The campaign is made in memory: 60 one-cycle sine pulses of the table (10 s at 100 Hz, seeded period and
amplitude) under the ETH block, whose outcomes are the analytic model's for the same block standing on a
contact 0.75 of its width (a convex base): both outcomes occur (39 overturn), the plain model misses the
overturns and the contact effect is added. It is diagnosed once for the module (about 1 s).
"""

from __future__ import annotations

import html
import math
import re
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from shared import page_section, page_text

from housner.model import theta_max_many
from housner.motion import GroundMotion
from housner.reports.diagnosis import render_outcome_report, write_outcome_report
from housner.reports.diagnosis.outcome_figures import GRID, baseline_label, fit_soft_logistic, level_lines
from housner.reports.diagnosis.outcome_text import outcome_pointer_text
from housner.reports.diagnosis.outcomes import MISSES_SHOWN, STATUS, step_label
from housner.scenarios.campaigns.campaign import Campaign
from housner.scenarios.campaigns.campaign_records import OutcomeRecord
from housner.scenarios.diagnosis.outcomes.outcome_diagnosis import diagnose_outcomes
from housner.scenarios.diagnosis.outcomes.outcome_scores import SCORE_KEYS
from housner.specimen import Specimen

#: Records of the synthetic campaign [-], their duration [s] and sample step [s].
N_RECORDS, DURATION, DT = 60, 10.0, 0.01
#: The true contact's share of the block's width [-] (the effect the diagnosis has to find).
CONTACT_SHARE = 0.75
#: Seconds the diagnosis of the synthetic campaign may take (it takes about 1 s).
DIAGNOSIS_BUDGET_S = 20.0


def synthetic_campaign(seed: int = 0, n: int = N_RECORDS) -> Campaign:
    """``n`` one-cycle sine pulses (period 0.15-1.2 s, amplitude 1-6 m/s^2, log-uniform) under the ETH block;
    the outcomes are the analytic model's for the block on a contact CONTACT_SHARE of its width."""
    spec = Specimen.bachmann2017()
    rng = np.random.default_rng(seed)
    t = np.arange(round(DURATION / DT)) * DT
    accs = []
    for _ in range(n):
        period = math.exp(rng.uniform(math.log(0.15), math.log(1.2)))
        amp = math.exp(rng.uniform(math.log(1.0), math.log(6.0)))
        accs.append(np.where((t >= 1.0) & (t < 1.0 + period), amp * np.sin(2 * np.pi * (t - 1.0) / period), 0.0))
    truth = Specimen(height=spec.height, width=CONTACT_SHARE * spec.width, depth=spec.depth, mass=spec.mass, p=spec.p)
    _, overturned, _ = theta_max_many(truth, accs, DT)
    recs = [
        OutcomeRecord(
            id=f"pulse{i:02d}",
            kind="ground_motion",
            file=Path(f"pulse{i:02d}.csv"),
            motion=GroundMotion(a, DT, name=f"pulse{i:02d}"),
            overturned=bool(o),
        )
        for i, (a, o) in enumerate(zip(accs, overturned, strict=True))
    ]
    return Campaign(name="synthetic-pulses", specimen=spec, records=[], outcomes=recs)


@pytest.fixture(scope="module")
def diag():
    campaign = synthetic_campaign()
    t0 = time.perf_counter()
    d = diagnose_outcomes(campaign, folds=3, seed=0)
    took = time.perf_counter() - t0
    assert took < DIAGNOSIS_BUDGET_S, f"the diagnosis took {took:.1f} s"
    assert 0 < int(d.observed.sum()) < len(d.ids), "both outcomes must occur"
    return d


@pytest.fixture(scope="module")
def page(diag):
    return render_outcome_report(diag)


# ----------------------------------------------------------------------------
# the page
def test_the_page_is_one_self_contained_document(page):
    assert page.startswith("<!DOCTYPE html>") and page.count("<html") == 1 and page.rstrip().endswith("</html>")
    assert "<script" not in page.lower()
    assert "http://" not in page and "https://" not in page
    assert not re.search(r'(src|href)="(?!data:|#)', page), "every resource is inline, every link in the page"
    assert page.count('src="data:image/png;base64,iVBORw0KGgo') >= 2  # the outcome map and the calibration


def test_the_verdict_is_stated_once_at_the_top(diag, page):
    words = STATUS[diag.status][0]
    text = page_text(page)
    assert text.count(words) == 1
    assert words in page_text(page_section(page, "verdict"))
    assert page.index('<section id="verdict">') < page.index('<section id="scores">') < page.index('id="map"')
    for other, (w, _, _) in STATUS.items():
        if other != diag.status and w not in words:
            assert w not in text, f"a second verdict: {w}"


@pytest.mark.parametrize("status", sorted(STATUS))
def test_every_status_is_stated_once_and_alone(diag, status):
    """The page of each status (the diagnosis edited to it): its words once, no other status's words, and for a
    floor missed, the distance to it in words."""
    at_floor = status in ("no_misfit", "explained")
    steps = diag.steps if status in ("explained", "partly_explained") else diag.steps[:1]
    d = replace(
        diag,
        status=status,
        steps=steps,
        floor=replace(diag.floor, at_floor=at_floor),
        misses=[m for m in diag.misses if m.model in {s.name for s in steps}],
    )
    text = page_text(render_outcome_report(d))
    assert text.count(STATUS[status][0]) == 1
    assert not [w for k, (w, _, _) in STATUS.items() if k != status and w not in STATUS[status][0] and w in text]
    assert ("at the floor" in text) == at_floor and ("above the floor" in text) != at_floor


def test_the_verdict_gives_the_model_its_scores_the_floor_and_the_baseline(diag, page):
    v = page_text(page_section(page, "verdict"))
    s = diag.final.scores
    assert f"log loss {s.log_loss:.3f} [{s.log_loss_ci[0]:.3f}, {s.log_loss_ci[1]:.3f}]" in v
    assert f"accuracy {s.accuracy:.3f} [{s.accuracy_ci[0]:.3f}, {s.accuracy_ci[1]:.3f}]" in v
    assert f"F1 {s.f1:.3f}" in v
    assert f"{diag.floor.log_loss:.3f} [{diag.floor.log_loss_ci[0]:.3f}, {diag.floor.log_loss_ci[1]:.3f}]" in v
    assert f"measured {diag.floor.measured_log_loss:.3f}" in v
    best = min(diag.baselines, key=lambda k: diag.baselines[k].log_loss)
    ahead = s.log_loss < diag.baselines[best].log_loss
    assert baseline_label(best) in v and ("the model is ahead" if ahead else "the model is NOT ahead") in v
    n_miss = s.fn + s.fp
    assert f"{n_miss} of {len(diag.ids)} records {'is' if n_miss == 1 else 'are'} missed" in v
    if diag.final.name != "plain":
        assert "alpha_eff" in v and "rad" in v


def test_the_table_has_every_ladder_step_and_every_baseline(diag, page):
    t = page_section(page, "scores")
    for st in diag.steps:
        assert f"<td>{html.escape(step_label(st.name))}" in t
    for name in diag.baselines:
        assert f"<td>{baseline_label(name)}" in t
    assert "logistic on log PGA and log PGV" in t
    rows = t.count("<tr>") - 1  # the header
    assert rows == len(diag.steps) + len(diag.baselines)
    assert t.count("<th>") == 1 + len(SCORE_KEYS)


def test_the_confusion_matrices_add_up(diag, page):
    c = page_text(page_section(page, "confusion"))
    for st in {id(s): s for s in (diag.steps[0], diag.final)}.values():
        sc = st.scores
        assert sc.tp + sc.fp + sc.fn + sc.tn == len(diag.ids)
        assert step_label(st.name) in c


def test_the_misses_table_lists_each_models_misses(diag, page):
    w = page_section(page, "where")
    assert html.escape(outcome_pointer_text(diag.pointer)[:40]) in w
    models = {m.model for m in diag.misses}
    assert models == {s.name for s in (diag.steps[0], diag.final) if s.scores.fn + s.scores.fp}
    for m in diag.misses:  # fewer than MISSES_SHOWN per model here: every one is listed
        assert f"<code>{m.id}</code>" in w


def test_the_misses_table_stops_at_its_rows_per_model_and_counts_the_rest(diag):
    many = [replace(diag.misses[0], id=f"extra{i:03d}", predicted_p=0.5 + 0.001 * i) for i in range(MISSES_SHOWN + 7)]
    w = page_section(render_outcome_report(replace(diag, misses=many)), "where")
    assert w.count("<code>extra") == MISSES_SHOWN
    assert "<code>extra036</code>" in w and "<code>extra006</code>" not in w  # the most confident first
    assert f"7 more of {step_label(many[0].model)} not listed" in w


def test_the_candidates_and_the_settings_are_shown(diag, page):
    c = page_section(page, "candidates")
    for cand in diag.candidates:
        assert f"<code>{cand.name.split('+')[0]}</code>" in c
    s = page_text(page_section(page, "settings"))
    assert f"{diag.geometry.h_m:.5g} m" in s and f"{diag.folds} (stratified)" in s


def test_write_outcome_report_writes_the_page(diag, tmp_path):
    out = write_outcome_report(diag, tmp_path / "deep" / "outcomes.html")
    assert out.is_file() and out.read_text(encoding="utf-8").startswith("<!DOCTYPE html>")
    assert not list(out.parent.glob("*.tmp"))


# ----------------------------------------------------------------------------
# the P = 0.5 line
def test_the_soft_fit_puts_a_step_in_pga_where_it_is():
    """P = 1[PGA > x0] over scattered records: the traced 0.5 line is the vertical PGA = x0.

    Tolerance: where inside the gap between the two records that flank x0 the boundary lies the data cannot say
    (half that gap), and the line is traced by linear interpolation on a grid, which places it within one cell
    of its true place (one grid step). So |ln PGA_line - ln x0| <= half the flanking gap + one grid step.
    """
    rng = np.random.default_rng(1)
    pga = np.exp(rng.uniform(np.log(0.05), np.log(1.0), 400))
    ratio = np.exp(rng.uniform(np.log(0.02), np.log(0.3), 400))
    x0 = 0.2
    p = (pga > x0).astype(float)
    lim_x, lim_y = (0.05, 1.0), (0.02, 0.3)
    segs = level_lines(fit_soft_logistic(pga, ratio, p), lim_x, lim_y)
    assert segs, "no 0.5 line in the range"
    pts = np.vstack(segs)
    step = np.log(lim_x[1] / lim_x[0]) / (GRID - 1)
    u = np.log(np.sort(pga))
    k = np.searchsorted(u, np.log(x0))
    tol = 0.5 * (u[k] - u[k - 1]) + step
    assert np.max(np.abs(np.log(pts[:, 0]) - np.log(x0))) <= tol
    assert pts[:, 1].min() < 0.03 and pts[:, 1].max() > 0.25, "the line crosses the whole range of PGV/PGA"


def test_a_linear_fit_recovers_a_baseline_line():
    """P of a logistic on ln PGV (= ln PGA + ln PGV/PGA) is linear in the logs: the plane fitted to it as soft
    targets gives back its 0.5 line PGV = v0, i.e. PGV/PGA = v0 / PGA, within one grid step of either axis."""
    rng = np.random.default_rng(2)
    pga = np.exp(rng.uniform(np.log(0.05), np.log(1.0), 300))
    ratio = np.exp(rng.uniform(np.log(0.02), np.log(0.3), 300))
    v0 = 0.02  # [g s]
    p = 1.0 / (1.0 + np.exp(-3.0 * np.log(pga * ratio / v0)))
    lim_x, lim_y = (0.05, 1.0), (0.02, 0.3)
    pts = np.vstack(level_lines(fit_soft_logistic(pga, ratio, p, quadratic=False), lim_x, lim_y))
    step = max(np.log(lim_x[1] / lim_x[0]), np.log(lim_y[1] / lim_y[0])) / (GRID - 1)
    assert np.max(np.abs(np.log(pts[:, 0] * pts[:, 1] / v0))) <= step


def test_no_line_where_p_does_not_cross_one_half():
    pga, ratio = np.geomspace(0.1, 1, 20), np.geomspace(0.05, 0.2, 20)
    assert level_lines(fit_soft_logistic(pga, ratio, np.full(20, 0.9)), (0.1, 1), (0.05, 0.2)) == []
