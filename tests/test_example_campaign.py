"""The shipped example campaign (the tutorial's data) still loads and is still explained by the example effect.

examples/campaigns/pivot-friction/ is written by scripts/make_example_campaign.py from the independent
generator's ``pivot_friction`` case (M_f = 0.09 N m). The plain model must miss it, dissipation named
first; adding examples/effects/pivot_friction.py by hand must turn it "explained", as test_plugins
checks on the generator's own 60-record campaign: the shipped data, rounded and cut to 30 ground
motions, cannot rot without this test failing.
"""

from __future__ import annotations

from pathlib import Path

import pytest
from shared import assert_strict_json_fixed_point

from housner.effects import load_plugin
from housner.reports.diagnosis.verdict_text import verdict_paragraph
from housner.scenarios import diagnose, load_campaign

ROOT = Path(__file__).resolve().parents[1]
CAMPAIGN = ROOT / "examples" / "campaigns" / "pivot-friction"
PLUGIN = ROOT / "examples" / "effects" / "pivot_friction.py"
#: The truth of the campaign [N m] (its README.md) and the tolerance of test_plugins (the fit's sensitivity).
MOMENT, TOL = 0.09, 0.002


@pytest.fixture(scope="module")
def campaign():
    return load_campaign(CAMPAIGN)


def test_the_example_campaign_loads_whole_and_stays_small(campaign):
    assert not campaign.skipped
    assert len(campaign.free_vibration) == 3 and len(campaign.ground_motion) == 30
    assert [r.id for r in campaign.records][:2] == ["fv01", "gm001"] and campaign.records[-1].id == "fv03"
    assert campaign.specimen.p == pytest.approx(4.8883)
    size = sum(p.stat().st_size for p in CAMPAIGN.rglob("*") if p.is_file())
    assert size < 2.6e6  # shipped in the repository and the sdist: keep it small
    assert "0.09 N m" in (CAMPAIGN / "README.md").read_text()  # the README states the truth


def test_the_plain_model_misses_it_and_points_to_dissipation(campaign):
    d = diagnose(campaign, effects=[], compare_steps=False)
    v = d.verdict
    assert v.status != "no_misfit", verdict_paragraph(d)
    assert v.baseline.ratio > 5  # far beyond the 1.25 band of a correct model
    assert v.next and v.next[0].name == "dissipation", verdict_paragraph(d)


def test_the_example_effect_added_by_hand_explains_it(campaign):
    (name,) = load_plugin(PLUGIN)
    d = diagnose(campaign, add=[name], effects=[], compare_steps=False)
    v = d.verdict
    assert v.status == "explained", verdict_paragraph(d)
    assert v.residual.ratio <= 1.25  # at the correct-model floor, like the controls
    assert dict(d.final.effects)[name]["moment"] == pytest.approx(MOMENT, abs=TOL)
    assert d.final.heldout_error < 0.2 * d.baseline.heldout_error  # the error falls by 80 % or more
    assert "added by hand" in verdict_paragraph(d) and "falls from" in verdict_paragraph(d)


def test_the_diagnosis_json_is_written_from_a_typed_value_and_read_back_whole(campaign):
    d = diagnose(campaign, effects=["restitution"], max_effects=1, n_replicas=4)
    fresh = d.result()

    read = assert_strict_json_fixed_point(d, fresh, indent=2)
    assert read.verdict.status == d.status and read.verdict.next == d.verdict.next
    assert read.ladder[-1].names == d.final.names and read.settings == d.settings
