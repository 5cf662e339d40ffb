"""The diagnosis' verdict says exactly what ran (issue 40), on the tutorial's campaign and through the command line.

Four runs of ``housner diagnose examples/campaigns/pivot-friction``, none with the library search (about 50 s
together on 2 cores): the plain model alone (``--effects none``), pivot friction added by hand (the tutorial's
fix), a user's quadratic air drag added by hand (an effect that fails: the campaign's loss is Coulomb friction),
and two library effects added by hand (a joint refit moves the first one's parameter).
"""

from __future__ import annotations

import contextlib
import io
import json
import re
from pathlib import Path

import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg

from housner.cli import main
from housner.reports.diagnosis import render_diagnosis
from housner.reports.diagnosis.figures import histories_figure
from housner.reports.diagnosis.words import Z_LEGEND, Z_LOCAL_LEGEND, params_text
from housner.scenarios.diagnosis.diagnose import diagnose

ROOT = Path(__file__).resolve().parents[1]
CAMPAIGN = ROOT / "examples" / "campaigns" / "pivot-friction"
FRICTION = ROOT / "examples" / "effects" / "pivot_friction.py"

#: A user's effect that cannot explain the campaign: a moment quadratic in the rotation speed (air drag).
AIR_DRAG = """
from dataclasses import dataclass

from numba import njit

from housner.effects import Effect, MomentTerm, param, register_effect


@njit(cache=True)
def drag(phi, w, t, a, v, s, alpha, p2, q):
    return -q[0] * w * abs(w)  # [rad/s^2]


@register_effect
@dataclass(frozen=True)
class StillAirDrag(Effect):
    name = "still_air_drag"
    coefficient: float = param("1/rad", (0.0, 0.5), neutral=0.0, default=0.0, doc="c in phi'' = -c w|w|")

    def terms(self, params, specimen):
        return (MomentTerm(drag, (self.coefficient,), at_rest=False),) if self.coefficient else ()
"""


def _cli(tmp: Path, name: str, *args: str) -> tuple[str, dict]:
    """The command's standard output and its JSON."""
    out = tmp / f"{name}.json"
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        assert main(["diagnose", str(CAMPAIGN), *args, "-q", "--json", str(out)]) == 0
    return buf.getvalue(), json.loads(out.read_text())


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("verdict_texts")
    (tmp / "air_drag.py").write_text(AIR_DRAG)
    return {
        "plain": _cli(tmp, "plain", "--effects", "none"),
        "friction": _cli(tmp, "friction", "--plugin", str(FRICTION), "--add", "pivot_friction", "--effects", "none"),
        "drag": _cli(tmp, "drag", "--plugin", str(tmp / "air_drag.py"), "--add", "still_air_drag", "--effects", "none"),
        "two": _cli(tmp, "two", "--add", "restitution", "--add", "rotational_damping", "--effects", "none"),
    }


def test_no_library_claim_when_no_search_ran(runs):
    for name, (out, d) in runs.items():
        text = d["verdict"]["text"]
        # a misfit that remains says what was tried; an explained one needs no search to say so
        assert ("no library search ran" in text) == (d["verdict"]["status"] != "explained"), name
        for claim in ("in the library explains", "no effect in the library", "the search tried"):
            assert claim not in text and claim not in out, (name, claim)
        assert d["settings"]["search"] == "off"


def test_the_status_is_printed_once(runs):
    for name, (out, d) in runs.items():
        lines = out.splitlines()
        assert [ln for ln in lines if ln.startswith("verdict")] == [f"verdict: {d['verdict']['status']}"], name
        # the paragraph under it does not open with the status again ("Explained: ...")
        assert not lines[1].lower().startswith(d["verdict"]["status"].replace("_", " ") + ":"), name
    # what CI greps: exactly one such line for the tutorial's fix
    assert len(re.findall(r"(?m)^verdict: explained$", runs["friction"][0])) == 1


def test_the_plain_model_keeps_its_floor_whatever_is_added(runs):
    plain = runs["plain"][1]["verdict"]["baseline_residual"]
    for name in ("friction", "drag", "two"):
        d = runs[name][1]
        base = d["verdict"]["baseline_residual"]
        # the same model, the same seeded bootstrap: the same numbers, not merely close
        assert base["floor"] == plain["floor"] and base["ratio"] == plain["ratio"], name
        assert d["settings"]["floor_family_plain"] == runs["plain"][1]["settings"]["floor_family"]
        floor = f"a correct-model floor of {plain['floor']:.4f} alpha"
        assert floor in d["verdict"]["text"] and floor in runs["plain"][1]["verdict"]["text"]
    # where the final model's floor is over another family, the text says so and why
    f = runs["friction"][1]
    assert f["settings"]["floor_family"] != f["settings"]["floor_family_plain"]
    assert "each model is judged against its own floor, measured over the narrowest family" in f["verdict"]["text"]


def test_every_statistic_is_explained_where_it_appears(runs):
    for name, (out, d) in runs.items():
        text = d["verdict"]["text"]
        assert text.count(Z_LEGEND) == 1, name  # once, in the plain model's figures, the first to give a z
        assert text.index("z = ") < text.index(Z_LEGEND) < text.index("z = ") + 400, name
        assert not re.search(r"z = [+-]?\d{3,}", text + out), name  # a z of thousands says no more than "> 100"
        assert "residual ratio" in text and "the worse group's error over its floor" in text
        if "Where to look first" in text:
            assert Z_LOCAL_LEGEND in text
        assert "error/floor" not in out and " z +" not in out  # the last line: words, no bare statistic


def test_a_failed_addition_points_from_the_model_with_it(runs):
    d = runs["drag"][1]
    v = d["verdict"]
    assert v["status"] == "partly_explained"  # air drag is not the campaign's loss
    assert v["next"] and all(c["from"] == "final" for c in v["next"])
    assert "Where to look first, from what the model with still_air_drag still gets wrong" in v["text"]
    # the evidence is the model with air drag's, not the plain model's: the energy ratio per impact it cites
    # differs from the plain model's figure for it
    plain = {e["metric"]: e for c in runs["plain"][1]["verdict"]["next"] for e in c["evidence"]}
    cited = {e["metric"]: e for e in v["next"][0]["evidence"]}
    shared = set(plain) & set(cited) - {"flight_share"}
    assert shared and all(cited[m]["model"] != plain[m]["model"] for m in shared)


def test_one_value_per_fitted_parameter(runs):
    out, d = runs["two"]
    text = d["verdict"]["text"]
    assert "all parameters fitted together in the final model" in text
    # the ladder's value of the first effect, where the joint refit moved it, is labelled as the step's
    ladder = out[out.index("Ladder:") :]
    first = re.search(r"\+ restitution \(by hand\) \(([^)]*)\)", ladder).group(1)
    r_final = re.search(r"with restitution \((r = [0-9.]+ \[-\])\)", text).group(1)
    assert first == r_final or ("as fitted at this step" in first and f"{r_final} in the final model" in ladder)


def test_the_histories_legend_fits_the_figure(tmp_path):
    d = diagnose(CAMPAIGN, add=["restitution", "rotational_damping"], effects=[], compare_steps=True, n_replicas=2)
    fig = histories_figure(d)
    renderer = FigureCanvasAgg(fig).get_renderer()
    fig.draw(renderer)
    box, legend = fig.bbox, fig.legends[0].get_window_extent(renderer)
    assert box.x0 <= legend.x0 and legend.x1 <= box.x1 and box.y0 <= legend.y0 and legend.y1 <= box.y1
    # and no axes' title runs under it
    assert all(ax.title.get_window_extent(renderer).y1 <= legend.y0 + 1 for ax in fig.axes)
    assert render_diagnosis(d).count("Where to look first") == 0  # the page lists the pointers instead
    assert params_text("restitution", dict(d.final.effects)["restitution"]) in render_diagnosis(d)


def test_a_parameter_fitted_at_an_end_of_its_range_is_said_to_be():
    """A fit stopped at the top of its range (not at its neutral value) does not rule the effect out: said so."""
    from housner.reports.diagnosis.words import params_text

    top = params_text("rotational_damping", {"c": 5.0})  # bounds (0, 5) 1/s
    assert "at the top of its search range 0 to 5" in top and "does not rule the effect out" in top
    assert params_text("rotational_damping", {"c": 0.0}) == "c = 0 1/s"  # the neutral end: no damping found
    assert params_text("rotational_damping", {"c": 2.0}) == "c = 2.000 1/s"
