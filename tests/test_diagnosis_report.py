"""The diagnosis page (housner.reports.diagnosis) and text (campaigns.results) as a researcher reads them.

One small campaign (3 free vibrations, 12 ground motions, hidden rotational damping) is
diagnosed once for the module with two candidates and a short floor bootstrap (~5 s);
the cases the search does not produce by itself (an error that rises, an overturned
median) are made by editing copies of that diagnosis.
"""

from __future__ import annotations

import copy
import math
import re
from dataclasses import replace
from pathlib import Path

import campaign_generators as cg
import numpy as np
import pytest
from shared import page_section, page_text

import housner.scenarios.diagnosis.verdict.decision as verdict_mod
import housner.scenarios.diagnosis.verdict.residual_test as residual_mod
from housner.reports.diagnosis import history_records, render_diagnosis
from housner.reports.diagnosis.figures import histories_figure
from housner.reports.diagnosis.reason_text import reason_text, reason_words
from housner.reports.diagnosis.verdict_text import diagnosis_summary, verdict_paragraph
from housner.reports.diagnosis.words import change_text, fmt_pm, params_text
from housner.scenarios.campaigns.campaign import load_campaign
from housner.scenarios.diagnosis.diagnose import diagnose
from housner.scenarios.diagnosis.selection.reasons import Reason

#: The documentation page that explains the verdict (it was the README's "Measurements" section).
DIAGNOSIS_DOC = Path(__file__).resolve().parents[1] / "docs" / "explanation" / "diagnosis.md"


@pytest.fixture(scope="module")
def diag(tmp_path_factory):
    root = tmp_path_factory.mktemp("diag_report") / "rd"
    cg.write_campaign(root, "rotational_damping", n_ground=12, fv_duration=6.0)
    d = diagnose(
        load_campaign(root),
        effects=["rotational_damping", "sensor_offset"],
        compare_steps=True,
        n_replicas=2,
        max_effects=1,
    )
    assert d.selected == ["rotational_damping"], diagnosis_summary(d)
    return d


@pytest.fixture(scope="module")
def page(diag):
    return render_diagnosis(diag)


# ----------------------------------------------------------------------------
# the helper: a value with its standard error
@pytest.mark.parametrize(
    ("value", "se", "text"),
    [
        (0.0031234, 0.000423, "0.00312 +- 0.00042"),
        (0.0917, 0.0331, "0.092 +- 0.033"),
        (0.005414, 2.41e-5, "0.005414 +- 0.000024"),
        (123.4, 15.6, "123 +- 16"),
        (0.5, 0.000996, "0.5000 +- 0.0010"),  # rounds up to a new digit: still 2 significant
        (-1e-7, 3e-4, "0.00000 +- 0.00030"),  # no "-0.00000"
        (math.inf, math.inf, "overturned"),  # an overturned theta_max: no uncertainty
        (math.inf, 0.1, "overturned"),
        (0.3, math.nan, "0.3000"),
        (math.nan, 0.1, "n/a"),
    ],
)
def test_fmt_pm_gives_the_error_two_significant_digits_and_the_value_its_decimal_place(value, se, text):
    assert fmt_pm(value, se) == text


def test_changes_are_said_with_a_positive_figure():
    assert change_text(-0.05, 0.011) == "rises by 0.050 +- 0.011"
    assert change_text(0.0863, 0.0331) == "falls by 0.086 +- 0.033"
    # a reason keeps its signed figure in the JSON, and is said in words on the page
    small = Reason("training_fall_small", {"fall": -0.0012, "margin": 0.005})
    assert reason_text(small).startswith("training error falls by -0.0012 < 0.0050 alpha")
    assert reason_words(small).startswith("training error rises by 0.0012 < 0.0050 alpha")
    assert reason_words(replace(small, figures={"fall": 0.0012, "margin": 0.005})).startswith(
        "training error falls by 0.0012 <"
    )
    subset = Reason("subset_fall_small", {"records": 0, "fall": -0.002, "margin": 0.005})
    assert reason_text(subset).startswith("the subset's best point lowers the error on all records by -0.0020 <")
    assert reason_words(subset).startswith("the subset's best point raises the error on all records by 0.0020 <")
    assert params_text("rotational_damping", {"c": 0.59991}) == "c = 0.5999 1/s"
    assert params_text("restitution", {"r": 0.88}) == "r = 0.8800 [-]"


# ----------------------------------------------------------------------------
# 1. the top: measured against modelled theta(t)
def test_histories_come_first_after_the_headline(diag, page):
    top = page_section(page, "summary")
    first_fig = top.index("<figure>")
    assert 'alt="measured and modelled theta(t)"' in top[first_fig : top.index("</figure>", first_fig)]
    # nothing but the headline before it: the verdict table and the rest of the page follow
    assert top.index('<p class="lead">') < first_fig < top.index("<table")
    assert page.index('alt="measured and modelled theta(t)"') < page.index('alt="error ladder"')


def test_histories_show_worst_and_median_ground_motion_and_a_free_vibration(diag):
    err = dict(zip(diag.heldout_ids, diag.final.heldout_errors, strict=True))
    gm = sorted((err[r.id], r.id) for r in diag.campaign.ground_motion)
    picks = history_records(diag)
    assert [role for _rid, role in picks] == ["worst ground motion", "median ground motion", "free vibration"]
    assert picks[0][0] == gm[-1][1] and picks[1][0] == gm[(len(gm) - 1) // 2][1]
    assert diag.campaign.record(picks[2][0]).kind == "free_vibration"
    fig = histories_figure(diag)
    axes = fig.get_axes()
    assert len(axes) == 3
    for ax, (rid, _role) in zip(axes, picks, strict=True):
        labels = [ln.get_label() for ln in ax.get_lines()]
        assert {"measured", "before: Housner (plain)", "after: Housner + rotational_damping"} <= set(labels)
        assert ax.get_title(loc="left").startswith(rid)
        # the measured trace is the record's theta/alpha
        meas = next(ln for ln in ax.get_lines() if ln.get_label() == "measured")
        rec = diag.campaign.record(rid)
        np.testing.assert_allclose(meas.get_ydata(), rec.theta / diag.campaign.specimen.alpha)


def test_without_an_effect_the_histories_show_the_plain_model_only(diag):
    plain = copy.copy(diag)
    plain.steps = diag.steps[:1]
    labels = {ln.get_label() for ax in histories_figure(plain).get_axes() for ln in ax.get_lines()}
    assert "measured" in labels and "before: Housner (plain)" in labels
    assert not any(lab.startswith("after") for lab in labels)
    assert "No effect was added" in page_text(render_diagnosis(plain))


# ----------------------------------------------------------------------------
# 2. the fall of the held-out error, before and after, with standard errors
def test_headline_states_the_fall_with_standard_errors(diag, page):
    b, f = diag.baseline, diag.final
    lead = page_text(page_section(page, "summary").split("<figure>")[0])
    before = fmt_pm(b.heldout_error, b.heldout_se, sep=" ± ")
    after = fmt_pm(f.heldout_error, f.heldout_se, sep=" ± ")
    pct = f"{100 * diag.reduction:.0f}"
    assert f"Held-out error falls by {pct} %: from {before} α (plain Housner model) to {after} α" in lead
    # and the summary text says the same
    assert f"from {fmt_pm(b.heldout_error, b.heldout_se)} to {fmt_pm(f.heldout_error, f.heldout_se)} alpha" in (
        diagnosis_summary(diag)
    )


# ----------------------------------------------------------------------------
# 3. the verdict once; parameters with units
def test_verdict_is_stated_once(diag, page):
    text = page_text(page)
    body = verdict_paragraph(diag).split(":", 1)[1].strip()  # after "Explained:"
    assert text.count(body[1:]) == 1
    assert len(re.findall(r"(?i)\bexplained\b", text)) == 1  # the status, in the headline only
    assert "Ladder:" not in text  # the summary paragraph (which opens with the verdict) is not on the page


def test_effect_parameters_carry_their_units(diag, page):
    c = dict(diag.final.effects)["rotational_damping"]["c"]
    want = params_text("rotational_damping", {"c": c})
    assert want.endswith(" 1/s")
    assert want in page_text(page_section(page, "summary"))  # the headline
    assert want in page_text(page_section(page, "ladder"))
    assert want in diagnosis_summary(diag)
    assert re.search(r"offset = [-0-9.e]+ rad", page_text(page_section(page, "candidates")))


# ----------------------------------------------------------------------------
# 4. an error that rises
def _risen(diag):
    """``diag`` with its final step made worse than the baseline, and a candidate whose error rose."""
    d = copy.copy(diag)
    b = diag.baseline
    worse = b.heldout_errors + 0.05
    d.steps = [
        b,
        replace(
            diag.final,
            heldout_error=float(worse.mean()),
            heldout_se=b.heldout_se,
            improvement=-0.05,
            improvement_se=0.011,
            heldout_errors=worse,
            significant=False,
        ),
    ]
    d.rounds = [
        [replace(c, reason=Reason("training_fall_small", {"fall": -0.0012, "margin": 0.0054})) for c in diag.rounds[0]]
    ]
    return d


def test_a_rising_error_rises_and_never_falls_by_a_negative_amount(diag):
    d = _risen(diag)
    text, summary = page_text(render_diagnosis(d)), diagnosis_summary(d)
    for t in (text, summary):
        assert not re.search(r"(falls|fell|lowers?[\w ]*) by [-−]", t), t
    assert "Held-out error rises by" in text and "rises by 0.050 ± 0.011" in text
    assert "training error rises by 0.0012" in text
    assert "In all the held-out error rises by" in summary and "rises by 0.050 +- 0.011" in summary


# ----------------------------------------------------------------------------
# 5. standard errors to their significant digits
def test_no_standard_error_is_rounded_to_zero(diag, page):
    assert not re.search(r"&plusmn; 0\.0*(?![0-9])", page)
    assert not re.search(r"\+- 0\.0*(?![0-9])", diagnosis_summary(diag))
    f = diag.final
    assert fmt_pm(f.heldout_error, f.heldout_se, sep=" &plusmn; ") in page_section(page, "ladder")


# ----------------------------------------------------------------------------
# 6. an overturned theta_max is "overturned", without an uncertainty
def test_overturned_is_written_without_an_uncertainty(diag):
    d = copy.copy(diag)
    steps = []
    for s in diag.steps:
        cmp = copy.copy(s.comparison)
        loc = dict(s.comparison.localisation())
        m, x = loc["theta_max_median"]
        loc["theta_max_median"] = (m._replace(value=math.inf, se=math.inf), x._replace(value=math.inf, se=math.inf))
        cmp.localisation = lambda loc=loc: loc
        steps.append(replace(s, comparison=cmp))
    d.steps = steps
    page = render_diagnosis(d)
    assert not re.search(r"overturn\w* &plusmn;|&plusmn; overturn", page)
    row = re.search(r"median theta_max/alpha of the ground-motion records</td>(.*?)</tr>", page).group(1)
    assert row.count("overturned") == 1 + len(d.steps)
    # the records table too: a measured overturn reads "overturned"
    assert any(r.overturned for r in diag.campaign.ground_motion)
    assert "overturned" in page_section(page, "records")


# ----------------------------------------------------------------------------
# 7. one threshold for a localisation quantity, on the page and in the documentation
def test_page_and_docs_state_the_same_localisation_threshold(diag, page, monkeypatch):
    z_local, z_misfit = verdict_mod.Z_LOCAL, residual_mod.Z_MISFIT
    text = page_text(page)
    assert f"more than {z_local:g} combined standard errors" in text
    assert f"z > {z_misfit:g}" in text and f"more than {z_local:g} standard errors" in text
    doc = DIAGNOSIS_DOC.read_text(encoding="utf-8")
    section = doc[doc.index("## The floor") :]
    section = " ".join(section[: section.index("\n## ", 10)].split())
    assert f"more than {z_local:g} standard errors from the measured one" in section
    assert f"z > {z_misfit:g}" in section and f"`Z_LOCAL` = {z_local:g}" in section
    # the page reads the constants, it does not repeat a number
    monkeypatch.setattr(verdict_mod, "Z_LOCAL", 7.5)
    monkeypatch.setattr(residual_mod, "Z_MISFIT", 6.5)
    text = page_text(render_diagnosis(diag))
    assert "more than 7.5 combined standard errors" in text and "z > 6.5" in text
    assert f"more than {z_local:g} combined" not in text
