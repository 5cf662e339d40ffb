"""A user's effect from a file: --plugin, the examples explained, the cache keyed by the effect's code.

The campaigns come from tests/independent_campaigns.py (written apart from the
library), each with the physics of one shipped example in examples/effects/.
Adding the example by hand must turn its campaign "explained", with the
held-out error at the level a correct model leaves (residual ratio <= 1.25).
"""

from __future__ import annotations

from pathlib import Path

import independent_campaigns as ic
import numpy as np
import pytest
from shared import run_housner

from housner import GroundMotion, Specimen
from housner.effects import effect_class, load_plugin
from housner.reports.diagnosis.verdict_text import verdict_paragraph
from housner.scenarios.campaigns.campaign import load_campaign
from housner.scenarios.diagnosis.diagnose import diagnose
from housner.scenarios.execution.cache import cache_key, effect_code_hash

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ROOT / "examples" / "effects"
#: example file -> (generator case, truth of its parameter, tolerance: the sensitivity of the fit, see test_terms)
CASES = {
    "pivot_friction": ("pivot_friction", ("moment", 0.09, 0.002)),
    "accelerometer_gain": ("accelerometer_gain", ("gain", 1.12, 0.005)),
    "vertical_table": ("vertical_table_measured", ("gain", 1.0, 0.05)),
}


@pytest.fixture(scope="module")
def base(tmp_path_factory):
    return tmp_path_factory.getbasetemp() / "plugins"


@pytest.mark.parametrize("example", list(CASES))
def test_each_example_explains_its_campaign(base, example):
    case, (key, truth, tol) = CASES[example]
    (name,) = load_plugin(EXAMPLES / f"{example}.py")
    camp = load_campaign(ic.cached_campaign(base, case)["root"])
    d = diagnose(camp, add=[name], effects=[], compare_steps=False)
    v = d.verdict
    assert v.status == "explained", verdict_paragraph(d)
    assert v.residual.ratio <= 1.25  # at the correct-model floor, like the controls
    assert dict(d.final.effects)[name][key] == pytest.approx(truth, abs=tol)
    assert d.final.heldout_error < 0.2 * d.baseline.heldout_error  # the error falls by 80 % or more
    assert "added by hand" in verdict_paragraph(d) and "falls from" in verdict_paragraph(d)
    assert len((EXAMPLES / f"{example}.py").read_text().splitlines()) <= 40


def test_cli_loads_a_plugin_and_refuses_a_missing_one(base, tmp_path):
    root = ic.cached_campaign(base, "pivot_friction")["root"]
    plugin = ("--plugin", str(EXAMPLES / "pivot_friction.py"), "--add", "pivot_friction")
    res = run_housner("diagnose", str(root), *plugin, "--effects", "none", "-q", timeout=300)
    assert res.returncode == 0, res.stderr
    # the status once, on its own line (the paragraph under it does not open with it again)
    assert res.stdout.startswith("verdict: explained\n") and "pivot_friction" in res.stdout
    assert "Explained:" not in res.stdout
    bad = run_housner("diagnose", str(root), "--plugin", "nope.py", timeout=120)
    assert bad.returncode == 2 and bad.stderr.count("\n") == 1 and "nope.py" in bad.stderr
    assert "Traceback" not in bad.stderr


def test_a_changed_effect_gets_a_new_cache_key(tmp_path):
    spec = Specimen.bachmann2017()
    mo = GroundMotion(np.zeros(10), 0.002, "m")
    src = (EXAMPLES / "pivot_friction.py").read_text().replace('name = "pivot_friction"', 'name = "my_friction"')
    f = tmp_path / "my_friction.py"
    f.write_text(src)
    load_plugin(f)
    e1 = effect_class("my_friction")(moment=0.05)
    k1 = cache_key(spec, mo, "housner", {}, "1", (e1,))
    f.write_text(src + "\n# the physics changed here\n")
    load_plugin(f)
    e2 = effect_class("my_friction")(moment=0.05)
    k2 = cache_key(spec, mo, "housner", {}, "1", (e2,))
    assert effect_code_hash(e1) != effect_code_hash(e2) and k1 != k2
    # the library's own effects are covered by the code version: their keys carry no file hash
    assert effect_code_hash(effect_class("restitution")(r=0.9)) is None
