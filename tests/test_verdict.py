"""The diagnosis' verdict (campaigns.verdict): the measured correct-model floor, the residual test, and
campaigns whose hidden effect is NOT in the effect library.

The campaigns come from tests/campaign_generators.py (an integrator written apart from the library):
``OUTSIDE`` holds three effects the library does not have (quadratic air drag, a Coulomb friction
moment at the pivot, a restitution that varies from impact to impact). The verdict must say
``partly_explained`` or ``unexplained`` for them, with the right localisation class first, and
``explained`` / ``no_misfit`` where the library has the truth; the slow matrix checks every case at
two split seeds and that the answer does not change with the split.
"""

from __future__ import annotations

import dataclasses
import json
import math

import campaign_generators as cg
import numpy as np
import pytest

from housner.reports.diagnosis.document import write_diagnosis_json
from housner.reports.diagnosis.verdict_text import diagnosis_summary, verdict_paragraph, verdict_text
from housner.scenarios.campaigns.campaign import load_campaign
from housner.scenarios.diagnosis.diagnose import diagnose
from housner.scenarios.diagnosis.selection.record_scoring import cv_folds
from housner.scenarios.diagnosis.verdict.correct_model_floor import Floor, _perturbed
from housner.scenarios.diagnosis.verdict.decision import VerdictFacts, decide
from housner.scenarios.diagnosis.verdict.residual_test import RATIO_MISFIT, residual_test
from housner.scenarios.diagnosis.verdict.status import STATUSES, status_rule
from housner.specimen import Specimen

_CACHE: dict = {}


@pytest.fixture(scope="module")
def base(tmp_path_factory):
    return tmp_path_factory.getbasetemp() / "campaigns"


def _diag(base, hidden, split_seed=0, campaign_seed=0):
    key = (hidden, split_seed, campaign_seed)
    if key not in _CACHE:
        info = cg.cached_campaign(base, hidden, seed=campaign_seed)
        _CACHE[key] = (info, diagnose(load_campaign(info["root"]), seed=split_seed, compare_steps=False))
    return _CACHE[key]


# ----------------------------------------------------------------------------
# pieces
def test_folds_hold_every_record_out_once_and_spread_the_free_vibrations(base):
    camp = load_campaign(cg.cached_campaign(base, "none")["root"])
    folds = cv_folds(camp, 5, seed=0)
    ids = [i for f in folds for i in f]
    assert sorted(ids) == sorted(r.id for r in camp.records)  # each exactly once
    assert [sum(i.startswith("fv") for i in f) for f in folds].count(1) == 3  # three folds hold one each
    assert max(map(len, folds)) - min(map(len, folds)) <= 1
    assert folds == cv_folds(camp, 5, seed=0) and folds != cv_folds(camp, 5, seed=1)
    with pytest.raises(ValueError, match="folds"):
        cv_folds(camp, 1)


def _floor(mean, sd):
    return Floor(np.asarray(mean, float), np.asarray(sd, float), 6, {})


def test_residual_at_the_floor_is_no_misfit_and_twice_it_is():
    rng = np.random.default_rng(0)
    n = 60
    f = 0.01 * (1 + rng.uniform(0, 1, n))
    kinds = ["ground_motion"] * n
    same = f * (1 + 0.2 * rng.standard_normal(n))  # chaos scatters a correct model's error by ~20 %
    r = residual_test(same, _floor(f, 0.2 * f), kinds)
    assert not r.misfit and abs(r.ratio - 1) < 0.1
    twice = 2 * same
    r2 = residual_test(twice, _floor(f, 0.2 * f), kinds)
    assert r2.misfit and r2.ratio == pytest.approx(2, rel=0.1) and r2.z > 3
    # significant but small (1.1x over 10 000 records) is not called a misfit: below RATIO_MISFIT
    big = np.tile(f, 200)
    r3 = residual_test(1.1 * big, _floor(big, 0.01 * big), ["ground_motion"] * big.size)
    assert r3.z > 3 and not r3.misfit and RATIO_MISFIT > 1.1
    # four records whose errors scatter like chaotic ones (80 %) cannot see a 2x misfit: the detectable
    # ratio says so, and how many records would
    wild = f[:4] * (1 + 0.8 * rng.standard_normal(4))
    r4 = residual_test(wild, _floor(f[:4], 0.8 * f[:4]), kinds[:4])
    assert r4.detectable_ratio > 2 and r4.records_needed > 0


def test_the_floors_parameter_draws_stay_within_the_fold_fits():
    # a sliding block's mu fitted at 0.139 with a jackknife spread of 0.02: Gaussian draws would cross
    # tan(alpha) = 0.15 (where the block rocks) 29 % of the time; the folds chose 0.132-0.141
    spec = Specimen.bachmann2017()
    rng = np.random.default_rng(0)
    draws = [
        _perturbed("sliding", {"mu": 0.139}, {"sliding.mu": 0.02}, rng, spec, {"sliding.mu": (0.132, 0.141)})["mu"]
        for _ in range(2000)
    ]
    assert min(draws) >= 0.132 and max(draws) <= 0.141
    assert len(set(np.round(draws, 12))) > 100  # still a spread inside, not the end points alone


def test_one_record_carried_off_by_chaos_does_not_hide_the_power_of_sixty():
    # measured on a restitution campaign: 59 ground motions at their floor, one at 0.66 alpha against a
    # floor of 0.38 +- 0.35 (a correct model's error on it is anywhere in 0-1)
    rng = np.random.default_rng(1)
    n = 60
    f = 0.006 * (1 + rng.uniform(0, 1, n))
    f[7] = 0.38
    e = f * (1 + 0.2 * rng.standard_normal(n))
    e[7] = 0.66
    fl = _floor(f, 0.2 * f)
    r = residual_test(e, fl, ["ground_motion"] * n)
    # the plain mean's standard error alone (0.0047 on a floor of 0.0154) would promise only 2.17x
    assert not r.misfit and r.detectable_ratio <= 2.0 and r.records_needed == 0
    # a broad misfit (every record 2x) still shows, with or without the outlier
    r2 = residual_test(2 * e, fl, ["ground_motion"] * n)
    assert r2.misfit and r2.groups["ground_motion"].ratio_trimmed == pytest.approx(2, rel=0.15)


def _five_records():
    """The residual of five records at their floor, and the verdict decided on it."""
    r = residual_test(np.full(5, 0.01), _floor(np.full(5, 0.01), np.full(5, 1e-3)), ["ground_motion"] * 5)
    v = decide(
        n_records=5,
        baseline=r,
        final=r,
        selected=[],
        params={},
        baseline_cmp=None,
        final_cmp=None,
        library=["restitution"],
    )
    return r, v


def test_too_few_records_is_inconclusive():
    _, v = _five_records()
    assert v.status == "inconclusive" and "too few" in verdict_text(v.facts, v.status)


def test_the_status_is_the_truth_table_and_the_text_is_drawn_from_it():
    r, v = _five_records()
    facts = VerdictFacts(
        n_records=5,
        baseline=r,
        final=r,
        selected=[],
        added=[],
        model=[],
        params={},
        library=["restitution"],
        drift=None,
        family="",
        classes=[],
        final_classes=[],
        local_plain=[],
        local_final=[],
        dist_plain=[],
        dist_final=[],
        plain_misfit=False,
        final_misfit=False,
        powered=True,
        probed=False,
    )
    status = status_rule(False, False, False, False, True)
    assert v.status == status == "inconclusive"
    assert verdict_text(v.facts, status) == verdict_text(facts, status)
    assert verdict_text(v.facts, status).startswith("Inconclusive: 5 usable records are too few")
    # with enough records and the plain model at its floor, the same residual reads "no misfit"
    enough = dataclasses.replace(facts, n_records=60)
    assert verdict_text(enough, status_rule(True, False, False, False, True)).startswith("No misfit: ")


def test_a_small_campaign_with_a_wrong_p_is_not_called_fine(base):
    # 3 free vibrations + 8 ground motions with p mis-stated by 8 %: too little data is no evidence of fit
    info = cg.write_campaign(base / "small-p", "p_misstated", n_ground=8, seed=3)
    diag = diagnose(load_campaign(info["root"]), compare_steps=False)
    assert diag.status != "no_misfit", diagnosis_summary(diag)
    assert diag.verdict.baseline.misfit  # the free vibrations alone show it


def test_an_effect_outside_the_library_is_not_called_explained(base):
    info, diag = _diag(base, "random_restitution")
    v = diag.verdict
    assert v.status in ("partly_explained", "unexplained"), diagnosis_summary(diag)
    # the library claimed where the search tried it, by name (issue 40: exactly what ran)
    assert "the search tried (" in verdict_paragraph(diag) and "explains it" not in verdict_paragraph(diag)
    # what remains shows in the errors (above the floor) or in the localisation (beyond Z_LOCAL)
    assert (v.residual.misfit and v.residual.ratio > RATIO_MISFIT) or "still points to a misfit" in verdict_paragraph(
        diag
    )
    assert v.next and v.next[0].name == info["expected"], v.next
    assert "explains it" not in diagnosis_summary(diag)


def test_json_carries_the_verdict_and_the_localisation(base, tmp_path):
    _info, diag = _diag(base, "random_restitution")
    write_diagnosis_json(diag, tmp_path / "d.json")
    d = json.loads((tmp_path / "d.json").read_text())
    v = d["verdict"]
    assert v["status"] in STATUSES and v["text"] == verdict_paragraph(diag)
    assert set(v["residual"]) == {"error", "floor", "ratio", "z"}
    assert all(math.isfinite(v["residual"][k]) for k in ("error", "floor", "ratio"))
    assert v["next"][0]["evidence"]  # each class with its figures
    assert d["localisation"]["baseline"]["localisation"] and d["localisation"]["final"]["localisation"]
    assert d["selection_frequency"] and len(d["folds"]) == 5


# ----------------------------------------------------------------------------
# the matrix (slow): every case at two split seeds
LIBRARY = [h for h in cg.HIDDEN if h != "none"]


@pytest.mark.slow
@pytest.mark.parametrize("hidden", LIBRARY)
def test_library_effects_are_explained_at_both_split_seeds(base, hidden):
    out = []
    for s in (0, 1):
        info, diag = _diag(base, hidden, s)
        assert diag.status == "explained", diagnosis_summary(diag)
        assert tuple(diag.selected) == info["expected"], diagnosis_summary(diag)
        out.append(tuple(diag.selected))
    assert out[0] == out[1]


@pytest.mark.slow
@pytest.mark.parametrize("hidden", list(cg.OUTSIDE))
def test_effects_outside_the_library_at_both_split_seeds(base, hidden):
    got = []
    for s in (0, 1):
        info, diag = _diag(base, hidden, s)
        assert diag.status in ("partly_explained", "unexplained"), diagnosis_summary(diag)
        assert diag.verdict.next[0].name == info["expected"], diag.verdict.next
        got.append(diag.status)
    assert got[0] == got[1]


@pytest.mark.slow
@pytest.mark.parametrize("campaign_seed", [0, 1])
def test_controls_are_no_misfit_at_both_split_seeds(base, campaign_seed):
    for s in (0, 1):
        _info, diag = _diag(base, "none", s, campaign_seed)
        assert diag.status == "no_misfit", diagnosis_summary(diag)
        assert diag.selected == []


@pytest.mark.slow
def test_verdict_matrix_table(base, capsys):
    """Every case at both split seeds, as one table (after the matrix above: its diagnoses are cached)."""
    cases = [(h, 0) for h in LIBRARY] + [(h, 0) for h in cg.OUTSIDE] + [("none", 0), ("none", 1)]
    lines = [
        f"{'hidden effect (truth)':32s} {'camp':>4s}  {'split 0: status, named':54s} "
        f"{'split 1: status, named':54s} {'ratio 0':>7s} {'ratio 1':>7s}"
    ]
    stable = []
    for hidden, cs in cases:
        cells, ratios = [], []
        for s in (0, 1):
            _info, diag = _diag(base, hidden, s, cs)
            cells.append(f"{diag.status}, {' + '.join(diag.selected) or '-'}")
            ratios.append(diag.verdict.residual.ratio)
        stable.append(cells[0] == cells[1])
        lines.append(f"{hidden:32s} {cs:4d}  {cells[0]:54s} {cells[1]:54s} {ratios[0]:7.2f} {ratios[1]:7.2f}")
    with capsys.disabled():
        print("\n" + "\n".join(lines))
    assert all(stable)


def test_a_probes_figure_is_a_value_and_its_words_are_the_reports():
    # The pointer carries the probe's figures (its fitted parameters, the held-out errors with and without it);
    # reports.diagnosis.words says them, with the probe's own summary.
    from housner.reports.diagnosis.words import evidence_text, probe_words
    from housner.scenarios.diagnosis.selection.probes import ProbeFinding
    from housner.scenarios.diagnosis.verdict.decision import pointer_classes

    found = ProbeFinding(
        "vertical_coupling", "vertical_input", {"k": 0.31, "delay": 0.004}, 0.08, 0.05, 0.03, 0.007, 4.2, 1e-5
    )
    (cls,) = pointer_classes([], [], [found], None)
    (ev,) = cls.evidence
    assert cls.name == "vertical_input" and ev.metric == "probe:vertical_coupling" and ev.label == ""
    assert ev.params == {"k": 0.31, "delay": 0.004} and (ev.measured, ev.model, ev.z) == (0.05, 0.08, 4.2)
    text = evidence_text(ev)
    said = probe_words("vertical_coupling")
    assert said != "vertical_coupling"  # the probe declares its summary
    assert text.startswith(f"a trial of physics outside the library (the probe vertical_coupling: {said}; k = 0.31, ")
    assert "held-out error 0.05 alpha against 0.08 without it (z = +4.2: the fall in standard errors" in text
