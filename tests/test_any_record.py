"""Any record in a scenario: AT2 / CSV files by path, suites of records, the RDK model choice, the band check.

The record files are written in ``tmp_path`` from the shipped El Centro record
(PEER 1999): the AT2 is a byte copy, the CSV its samples in m/s^2 (repr, so
they read back exactly; the reader's step, the median of the time differences,
differs from 0.01 s in the 14th digit).
"""

from __future__ import annotations

import json
import shutil
from importlib import resources
from pathlib import Path

import numpy as np
import pytest

from housner.cli import main
from housner.scenarios.catalogue import ScenarioError
from housner.scenarios.catalogue.scenario import load_scenario
from housner.scenarios.motions import build as motion_build
from housner.scenarios.motions.build import build_motions
from housner.scenarios.motions.records import ELCENTRO_VARIANTS, elcentro

#: (samples, dt [s], PGA [m/s^2], RMS [m/s^2]) of motions 0-2 of `housner run elcentro` (rdk2010,
#: seed 2017): the default must not move them. They were SHA-256 hashes of the samples until
#: 2026-11-24, when a fresh install (numpy 2.4.6, scipy 1.17.1) moved the last bits and the hashes
#: with them; a relative 1e-9 on these figures still catches any change of the model, its seed or
#: its scaling (each moves them by more than 1e-3), and no floating-point reordering reaches it.
ELCENTRO_FIGURES = [
    (4735, 0.0031622776601683794, 2.315627221382834, 0.46546589199394045),
    (4735, 0.0031622776601683794, 2.242878273640912, 0.4476640699672257),
    (4735, 0.0031622776601683794, 2.592116530718005, 0.48086019582424944),
]


def _figures_match(motions) -> bool:
    assert len(motions) == len(ELCENTRO_FIGURES)
    for m, (n, dt, pga, rms) in zip(motions, ELCENTRO_FIGURES, strict=True):
        assert (m.n, m.dt) == (n, pytest.approx(dt, rel=1e-12))
        assert float(np.abs(m.acc).max()) == pytest.approx(pga, rel=1e-9)
        assert float(np.sqrt(np.mean(m.acc**2))) == pytest.approx(rms, rel=1e-9)
    return True


SCEN = """name = "anyrec"
[specimen]
preset = "bachmann2017"
[motions]
{motions}
prototype_height = 5.0
[engines]
names = ["housner"]
"""

RDK3 = 'source = "rdk"\nn = 3\nseed = 2017\n'


def write_at2(path: Path) -> Path:
    """A byte copy of the shipped PEER 1999 El Centro AT2."""
    path.parent.mkdir(parents=True, exist_ok=True)
    src = resources.files("housner.scenarios.catalogue").joinpath("data", ELCENTRO_VARIANTS["peer1999"][0])
    with resources.as_file(src) as p:
        shutil.copyfile(p, path)
    return path


def write_csv(path: Path, scale: float = 1.0) -> Path:
    """The shipped El Centro record as a CSV in m/s^2 (times ``scale``)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    rec = elcentro()
    rows = "".join(f"{k * rec.dt!r},{a!r}\n" for k, a in enumerate((rec.acc * scale).tolist()))
    path.write_text("time [s],ground_acc [m/s^2]\n" + rows)
    return path


def scenario(tmp_path: Path, motions: str, name: str = "scen.toml") -> Path:
    path = tmp_path / name
    path.write_text(SCEN.format(motions=motions))
    return path


def same(a, b, rtol: float = 0.0) -> None:
    assert len(a) == len(b)
    for x, y in zip(a, b, strict=True):
        assert x.n == y.n
        if rtol == 0.0:
            assert x.content_hash() == y.content_hash()
        else:
            assert x.dt == pytest.approx(y.dt, rel=rtol)
            np.testing.assert_allclose(x.acc, y.acc, rtol=0, atol=rtol * np.abs(y.acc).max())


# ----------------------------------------------------------------------
# record = <path>
# ----------------------------------------------------------------------
def test_at2_path_gives_the_shipped_records_motions(tmp_path):
    write_at2(tmp_path / "recs" / "ec.AT2")
    shipped, meta0 = build_motions(load_scenario(scenario(tmp_path, RDK3 + 'record = "elcentro"', "a.toml")))
    motions, meta = build_motions(load_scenario(scenario(tmp_path, RDK3 + 'record = "recs/ec.AT2"')))
    same(motions, shipped)
    assert _figures_match(motions)
    assert meta["rdk_params"] == meta0["rdk_params"] and meta["model"] == "rdk2010"
    rec = meta["record"]
    assert (rec["name"], rec["dt"], rec["n"], rec["file"]) == ("ec", 0.01, 4000, "recs/ec.AT2")
    assert rec["path"] == str((tmp_path / "recs" / "ec.AT2").resolve()) and len(rec["sha256"]) == 64
    assert "ec.AT2" in rec["provenance"] and "PEER AT2" in rec["provenance"]
    # source = "record", the path absolute: the record itself, time-compressed by sqrt(S)
    one = f'source = "record"\nrecord = "{tmp_path / "recs" / "ec.AT2"}"\namplitude = 1.5'
    (m,), _ = build_motions(load_scenario(scenario(tmp_path, one, "b.toml")))
    (m0,), _ = build_motions(
        load_scenario(scenario(tmp_path, one.split("\n")[0] + '\nrecord = "elcentro"\namplitude = 1.5', "c.toml"))
    )
    same([m], [m0])
    assert m.dt == pytest.approx(0.01 / np.sqrt(10.0), rel=1e-12) and m.pga == pytest.approx(1.5 * elcentro().pga)


def test_csv_path_gives_the_shipped_records_motions(tmp_path):
    write_csv(tmp_path / "ec.csv")
    shipped, _ = build_motions(load_scenario(scenario(tmp_path, RDK3 + 'record = "elcentro"', "a.toml")), 2)
    motions, meta = build_motions(load_scenario(scenario(tmp_path, RDK3 + 'record = "ec.csv"')), 2)
    same(motions, shipped, rtol=1e-12)
    assert meta["record"]["name"] == "ec" and meta["record"]["n"] == 4000
    (m,), _ = build_motions(load_scenario(scenario(tmp_path, 'source = "record"\nrecord = "ec.csv"', "b.toml")))
    (m0,), _ = build_motions(load_scenario(scenario(tmp_path, 'source = "record"', "c.toml")))
    same([m], [m0], rtol=1e-12)


def test_the_fit_follows_the_files_content(tmp_path):
    """The fit cache is keyed by the record's samples: a file rewritten in place is fitted again."""
    path = write_csv(tmp_path / "rec.csv")
    scen = scenario(tmp_path, 'source = "rdk"\nn = 1\nrecord = "rec.csv"')
    _, before = build_motions(load_scenario(scen))
    write_csv(path, scale=2.0)
    _, after = build_motions(load_scenario(scen))
    assert after["record"]["sha256"] != before["record"]["sha256"]
    assert after["rdk_params"]["Ia_m_s"] == pytest.approx(4.0 * before["rdk_params"]["Ia_m_s"], rel=1e-9)


# ----------------------------------------------------------------------
# source = "records"
# ----------------------------------------------------------------------
def test_records_folder_and_list(tmp_path):
    write_csv(tmp_path / "suite" / "b.csv", scale=0.5)
    write_at2(tmp_path / "suite" / "a.AT2")
    (tmp_path / "suite" / "notes.txt").write_text("not a record")
    scen = load_scenario(scenario(tmp_path, 'source = "records"\nrecords = "suite"\namplitude = 2.0'))
    assert scen.n_motions == 2
    motions, meta = build_motions(scen)
    assert [m.name for m in motions] == ["a", "b"]  # sorted by name, the .txt left out
    assert [r["file"] for r in meta["records"]] == ["suite/a.AT2", "suite/b.csv"]
    assert "a.AT2" in motions[0].provenance and "b.csv" in motions[1].provenance
    # each as source = "record" gives it: the same code path (amplitude, then sqrt(S) in time)
    for m, f in zip(motions, ["suite/a.AT2", "suite/b.csv"], strict=True):
        one = scenario(tmp_path, f'source = "record"\nrecord = "{f}"\namplitude = 2.0', "one.toml")
        same([m], build_motions(load_scenario(one))[0])
    assert motions[0].pga == pytest.approx(2.0 * elcentro().pga) and motions[0].dt == pytest.approx(0.01 / 10**0.5)
    # a list keeps its order; an absolute path is allowed
    listed = f'source = "records"\nrecords = ["suite/b.csv", "{tmp_path / "suite" / "a.AT2"}"]\namplitude = 2.0'
    motions2, meta2 = build_motions(load_scenario(scenario(tmp_path, listed, "list.toml")))
    assert [m.name for m in motions2] == ["b", "a"]
    same(motions2, motions[::-1])
    assert "model" not in meta2 and "band_check" not in meta2


# ----------------------------------------------------------------------
# model = "rdk2010" | "matched", and the band check
# ----------------------------------------------------------------------
def test_default_model_is_the_published_one_unchanged(tmp_path):
    scen = load_scenario(scenario(tmp_path, RDK3 + 'record = "elcentro"'))
    assert "model" not in scen.motions
    motions, meta = build_motions(scen)
    assert _figures_match(motions)
    assert meta["model"] == "rdk2010" and "band_check" not in meta and "matched_gain" not in meta
    _, meta = build_motions(scen, 3, band_check=True)
    check = meta["band_check"]
    assert len(check["psa"]["bands"]) == 19 and len(check["sd"]["bands"]) == 9
    assert check["psa"]["range_s"] == [0.05, 3.0] and check["sd"]["range_s"] == [0.5, 3.0]
    assert check["bounds"] == [0.8, 1.25] and check["record"] == "elcentro-peer1999"
    assert not check["passed"]  # the published model misses the record at 0.5-1 s (docs/results.md)


def test_the_seed_scenario_runs_the_matched_model_and_its_bands_pass():
    """`housner run elcentro` (issue 11): 100 matched motions, every third-octave band within [0.8, 1.25]."""
    scen = load_scenario("elcentro")
    assert scen.motions["model"] == "matched" and scen.n_motions == 100
    motions, meta = build_motions(scen, band_check=True)
    assert len(motions) == 100 and meta["model"] == "matched"
    check = meta["band_check"]
    assert check["passed"], [b for b in check["psa"]["bands"] + check["sd"]["bands"] if b["verdict"] != "PASS"]


def test_matched_model_gives_the_matched_ensemble_and_its_band_check(tmp_path):
    from housner.scenarios.motions.rdk_match import fit_matched, simulate_matched

    scen = load_scenario(scenario(tmp_path, RDK3 + 'record = "elcentro"\nmodel = "matched"'))
    motions, meta = build_motions(scen, band_check=True)
    assert meta["model"] == "matched"
    fit = motion_build._fit("matched", elcentro())  # the cached fit: the same as fitting from scratch
    assert fit.gain == fit_matched(elcentro()).gain
    same(motions, [g.to_model_scale(10.0) for g in simulate_matched(fit, 3, 2017)])
    gain = meta["matched_gain"]
    assert len(gain["gain"]) == len(gain["gain_centres_s"]) == 19 and gain["n_fit"] == 100
    assert meta["rdk_params"] == motion_build._fit("rdk2010", elcentro()).describe()
    check = meta["band_check"]
    rows = check["psa"]["bands"] + check["sd"]["bands"]
    assert {r["verdict"] for r in rows} <= {"PASS", "FAIL"} and len(rows) == 28
    for r in rows:
        assert r["lo_s"] < r["centre_s"] < r["hi_s"] and r["ratio"] > 0
        assert (r["verdict"] == "PASS") == (0.8 <= r["ratio"] <= 1.25)
    # 3 motions only, yet the matched mean is near the record where the published one is not (0.54 at 1 s)
    ratios = [r["ratio"] for r in check["psa"]["bands"] if 0.4 < r["centre_s"] < 0.9]
    assert min(ratios) > 0.8


def test_report_shows_the_band_check_of_a_file_record(tmp_path):
    from housner.reports.run import page as html
    from housner.scenarios.runs.run import run_scenario

    path = write_at2(tmp_path / "ec.AT2")
    scen = scenario(tmp_path, 'source = "rdk"\nn = 2\nseed = 5\nrecord = "ec.AT2"')
    run_scenario(scen, out=tmp_path / "run", jobs=1, use_cache=False, progress=False)
    meta = json.loads((tmp_path / "run" / "run.json").read_text())["motions"]
    assert meta["model"] == "rdk2010" and meta["record"]["file"] == "ec.AT2"
    assert len(meta["band_check"]["psa"]["bands"]) == 19
    page = html.render_report(tmp_path / "run")
    section = page[page.find('id="ensemble"') :]
    section = section[: section.find("<section", 10)]
    assert "Spectral match, band by band" in section and "PSa ratio" in section
    assert section.count("badge pass") + section.count("badge fail") == 19 + 9 + 1  # bands, and the verdict
    assert "ec.AT2" in section and "<img" in section and "no spectra" not in section  # the file, read again
    path.write_bytes(path.read_bytes().replace(b"0.", b"1.", 1))
    assert "has changed since the run: no spectra" in html.render_report(tmp_path / "run")


# ----------------------------------------------------------------------
# Errors: one line naming the scenario file, the key and the path, at load; through the CLI exit 2
# ----------------------------------------------------------------------
def _bad_at2(tmp):
    (tmp / "recs").mkdir(exist_ok=True)
    (tmp / "recs" / "bad.AT2").write_text("PEER\nno header here\n0.1 0.2\n")


def _suite(tmp):
    write_at2(tmp / "recs" / "ec.AT2")
    write_csv(tmp / "recs" / "ec.csv")
    (tmp / "recs" / "ec.txt").write_text("1 2 3\n")
    (tmp / "empty").mkdir()
    (tmp / "half").mkdir()
    write_at2(tmp / "half" / "a.AT2")
    (tmp / "half" / "b.AT2").write_text("PEER\nUNITS OF G\nNPTS= 3, DT= 0.01 SEC\n0.1 0.2\n")
    (tmp / "recs" / "nocol.csv").write_text("time,acc\n0,1\n0.01,2\n")


ERRORS = [
    # id, [motions] lines, substrings of the message besides the file name
    ("record-missing", RDK3 + 'record = "recs/none.AT2"', ["'record'", "recs/none.AT2", "no such file"]),
    ("record-not-at2", RDK3 + 'record = "recs/bad.AT2"', ["'record'", "recs/bad.AT2", "NPTS"]),
    ("record-csv-columns", 'source = "record"\nrecord = "recs/nocol.csv"', ["'record'", "nocol.csv", "ground_acc"]),
    ("record-wrong-format", RDK3 + 'record = "recs/ec.txt"', ["'record'", "recs/ec.txt", ".AT2", ".csv"]),
    ("record-is-a-folder", 'source = "record"\nrecord = "recs/"', ["'record'", "recs", "folder", "records"]),
    ("record-unknown-name", RDK3 + 'record = "kobe"', ["record 'kobe'", "elcentro", ".AT2"]),
    ("records-no-folder", 'source = "records"\nrecords = "nowhere"', ["'records'", "nowhere", "no such folder"]),
    ("records-empty-folder", 'source = "records"\nrecords = "empty"', ["'records'", "empty", "no .AT2 or .csv"]),
    ("records-is-a-file", 'source = "records"\nrecords = "recs/ec.AT2"', ["'records'", "recs/ec.AT2", "is a file"]),
    ("records-bad-in-folder", 'source = "records"\nrecords = "half"', ["'records'", "half/b.AT2", "NPTS=3"]),
    (
        "records-missing-file",
        'source = "records"\nrecords = ["recs/ec.AT2", "recs/none.csv"]',
        ["'records'", "recs/none.csv", "no such file"],
    ),
    (
        "records-duplicate-name",
        'source = "records"\nrecords = ["recs/ec.AT2", "recs/ec.csv"]',
        ["'records'", "recs/ec.AT2", "recs/ec.csv", "'ec'"],
    ),
    ("records-empty-list", 'source = "records"\nrecords = []', ["'records'", "empty list"]),
    ("records-not-paths", 'source = "records"\nrecords = [1]', ["'records'", "strings", "1"]),
    ("records-without-key", 'source = "records"', ["'records'", "needs"]),
    ("records-with-rdk", RDK3 + 'records = "recs"', ["'records'", "source 'rdk'"]),
    ("model-unknown", RDK3 + 'model = "matchd"', ["model 'matchd'", "did you mean 'matched'", "rdk2010"]),
    ("model-with-record", 'source = "record"\nmodel = "matched"', ["'model'", "source 'record'"]),
]


@pytest.mark.parametrize(("case", "motions", "expect"), ERRORS, ids=[e[0] for e in ERRORS])
def test_bad_records_give_one_line_at_load(case, motions, expect, tmp_path, capsys):
    _bad_at2(tmp_path)
    _suite(tmp_path)
    path = scenario(tmp_path, motions)
    with pytest.raises(ScenarioError) as err:
        load_scenario(path)
    msg = str(err.value)
    assert "\n" not in msg and msg.startswith(f"{path} line ")
    for word in expect:
        assert word in msg, f"{word!r} not in: {msg}"
    status = main(["run", str(path), "--jobs", "1", "--no-report", "-q", "--out", str(tmp_path / "out")])
    out, errs = capsys.readouterr()
    assert status == 2 and "Traceback" not in out + errs
    lines = [line for line in errs.splitlines() if line.startswith("housner: error:")]
    assert len(lines) == 1 and msg in lines[0], errs
