"""Units in data files: AT2 headers, CSV header brackets, campaigns through the CLI (SI inside).

Every conversion is checked numerically against the same samples written in SI,
with factors written out here, independently of the reader's table:
1 g = 9.80665 m/s^2 (standard gravity), 1 gal = 1 cm/s^2 = 0.01 m/s^2,
1 in = 0.0254 m, 1 ft = 0.3048 m, 1 deg = pi/180 rad.
"""

from __future__ import annotations

import json
import math
import shutil
from pathlib import Path

import campaign_generators as cg
import numpy as np
import pytest

from housner import DataFileError, GroundMotion
from housner.cli import main
from housner.scenarios.campaigns.campaign import load_campaign

G0 = 9.80665  # standard gravity [m/s^2], by definition
PER_UNIT = {  # value of one unit in SI
    "g": G0,
    "cm/s^2": 0.01,
    "m/s^2": 1.0,
    "mm/s^2": 0.001,
    "in/s^2": 0.0254,
    "ft/s^2": 0.3048,
    "ms": 1e-3,
    "s": 1.0,
    "deg": math.pi / 180.0,
    "mrad": 1e-3,
    "urad": 1e-6,
    "rad": 1.0,
}

# A small acceleration record in SI [m/s^2] (a decaying sine, peak ~2.9 m/s^2).
N = 40
DT = 0.01
ACC_SI = 3.0 * np.sin(np.arange(N) * 0.7) * np.exp(-np.arange(N) / 30.0)


# ----------------------------------------------------------------------------
# AT2
def _at2(path: Path, header_lines: list[str], values, dt: float = DT) -> Path:
    rows = ["".join(f"{v:15.7E}" for v in values[i : i + 5]) for i in range(0, len(values), 5)]
    path.write_text("\n".join([*header_lines, f"NPTS= {len(values):5d}, DT= {dt:.5f} SEC", *rows]) + "\n")
    return path


@pytest.mark.parametrize(
    ("units_line", "unit"),
    [
        ("ACCELERATION TIME HISTORY IN UNITS OF G", "g"),  # PEER 1999
        ("ACCELERATION TIME SERIES IN UNITS OF G", "g"),  # NGA-West2
        ("The units are (g)", "g"),  # Chopra's free text
        ("ACCELERATION TIME HISTORY IN UNITS OF CM/S/S", "cm/s^2"),  # the file that was read 980x too strong
        ("ACCELERATION IN UNITS OF CM/SEC/SEC", "cm/s^2"),
        ("ACCELERATION IN CM/SEC/SEC, FILTERED 0.1-25 HZ", "cm/s^2"),  # written out, no 'UNITS' phrase
        ("UNITS: GAL", "cm/s^2"),
        ("UNITS OF cm/s^2", "cm/s^2"),
        ("ACCELERATION TIME HISTORY IN UNITS OF M/S/S", "m/s^2"),
        ("UNITS = m/s2", "m/s^2"),
        ("ACCELERATION IN UNITS OF IN/SEC/SEC", "in/s^2"),
        ("UNITS OF FT/S^2", "ft/s^2"),
    ],
)
def test_at2_units_from_the_header_match_si(tmp_path, units_line, unit):
    # the same record written in `unit` reads back as the SI samples; E15.7 keeps 8 significant digits
    p = _at2(
        tmp_path / "rec.AT2",
        ["PEER STRONG MOTION DATABASE RECORD", "TEST 1/1/00, STATION", units_line],
        ACC_SI / PER_UNIT[unit],
    )
    m = GroundMotion.from_at2(p)
    np.testing.assert_allclose(m.acc, ACC_SI, rtol=1e-7, atol=0)
    assert m.dt == DT
    assert f"{unit} -> m/s^2" in m.provenance


def test_at2_in_gal_is_not_read_as_g(tmp_path):
    # the reported bug: a peak of 300 gal (0.31 g) was read as 300 g
    p = _at2(tmp_path / "gal.AT2", ["X", "Y", "ACCELERATION TIME HISTORY IN UNITS OF CM/S/S"], [0.0, 300.0, -120.0])
    assert GroundMotion.from_at2(p).pga == pytest.approx(3.0, rel=1e-12)


def test_shipped_chopra_file_finds_g_in_its_free_text():
    data = Path(__file__).resolve().parents[1] / "scenarios/catalogue/data"
    m = GroundMotion.from_at2(data / "elcentro_1940_ns_chopra_dt002.txt")
    assert "g -> m/s^2" in m.provenance and "header line 5" in m.provenance  # "The units are (g)"
    assert m.pga / G0 == pytest.approx(0.31882, abs=5e-6)  # the file's largest |value| is 0.31882


@pytest.mark.parametrize(
    ("header", "units", "needles"),
    [
        (
            ["X", "Y", "ACCELERATION TIME HISTORY"],
            None,
            ["nounits.AT2 line 4:", "names no acceleration units", "units="],
        ),
        (
            ["X", "Y", "VELOCITY TIME HISTORY IN UNITS OF CM/SEC"],
            None,
            ["nounits.AT2 line 3:", "cannot read the acceleration units 'CM/SEC'"],
        ),
        (
            ["X", "UNITS OF FURLONGS/FORTNIGHT/FORTNIGHT", "Z"],
            None,
            ["nounits.AT2 line 2:", "'FURLONGS/FORTNIGHT/FORTNIGHT'"],
        ),
        (
            ["X", "ACCELERATION IN UNITS OF G", "PEAK 300 CM/S/S"],
            None,
            ["nounits.AT2 line 3:", "two acceleration units, g (line 2) and cm/s^2 (line 3)"],
        ),
        (
            ["X", "Y", "ACCELERATION IN UNITS OF CM/S/S"],
            "g",
            ["nounits.AT2 line 3:", "header says cm/s^2 but units='g' was given"],
        ),
    ],
)
def test_at2_unreadable_units_are_refused_on_one_line(tmp_path, header, units, needles):
    p = _at2(tmp_path / "nounits.AT2", header, [0.1, 0.2, 0.3])
    with pytest.raises(DataFileError) as e:
        GroundMotion.from_at2(p, units=units)
    msg = str(e.value)
    assert "\n" not in msg
    for n in needles:
        assert n in msg


def test_at2_units_argument_reads_a_header_without_units(tmp_path):
    p = _at2(tmp_path / "bare.AT2", ["X", "Y", "Z"], ACC_SI / 0.01)
    np.testing.assert_allclose(GroundMotion.from_at2(p, units="cm/s^2").acc, ACC_SI, rtol=1e-7)
    with pytest.raises(ValueError, match="`units` must be an acceleration unit"):
        GroundMotion.from_at2(p, units="cm/s")


# ----------------------------------------------------------------------------
# CSV ground motions
def _csv(path: Path, header: str, cols, *, bom: bool = False) -> Path:
    body = "".join(",".join(repr(float(x)) for x in row) + "\n" for row in zip(*cols, strict=True))
    path.write_text(("\ufeff" if bom else "") + header + "\n" + body, encoding="utf-8")
    return path


@pytest.mark.parametrize(
    ("t_unit", "a_unit"),
    [("s", "m/s^2"), ("ms", "m/s^2"), ("s", "g"), ("ms", "cm/s^2"), ("s", "mm/s^2"), ("s", "in/s^2"), ("ms", "ft/s^2")],
)
def test_csv_units_in_brackets_match_the_si_file(tmp_path, t_unit, a_unit):
    t = np.arange(N) * DT
    si = GroundMotion.from_csv(_csv(tmp_path / "si.csv", "time,ground_acc", [t, ACC_SI]))
    p = _csv(
        tmp_path / "u.csv", f"time [{t_unit}],ground_acc [{a_unit}]", [t / PER_UNIT[t_unit], ACC_SI / PER_UNIT[a_unit]]
    )
    m = GroundMotion.from_csv(p)
    # written with repr (17 digits): the round trip value / f * f is exact to a few ulp
    assert m.dt == pytest.approx(si.dt, rel=1e-12)
    np.testing.assert_allclose(m.acc, si.acc, rtol=1e-14, atol=1e-15)
    assert f"{a_unit} -> m/s^2" in m.provenance


def test_csv_spellings_of_units(tmp_path):
    t = np.arange(N) * DT
    for header, f_t, f_a in (
        ("time (ms), ground_acc (gal)", 1e-3, 0.01),
        ("time[msec],ground_acc[CM/S/S]", 1e-3, 0.01),
        ("time [sec],ground_acc [m/s²]", 1.0, 1.0),
        ("time [s], ground_acc [G]", 1.0, G0),
    ):
        m = GroundMotion.from_csv(_csv(tmp_path / "s.csv", header, [t / f_t, ACC_SI / f_a]))
        assert m.dt == pytest.approx(DT, rel=1e-12), header
        np.testing.assert_allclose(m.acc, ACC_SI, rtol=1e-14, atol=1e-15, err_msg=header)


def test_csv_with_a_byte_order_mark_reads(tmp_path):
    t = np.arange(N) * DT
    m = GroundMotion.from_csv(_csv(tmp_path / "bom.csv", "time,ground_acc", [t, ACC_SI], bom=True))
    np.testing.assert_array_equal(m.acc, ACC_SI)
    m = GroundMotion.from_csv(_csv(tmp_path / "bom2.csv", "time [ms],ground_acc [g]", [t * 1e3, ACC_SI], bom=True))
    np.testing.assert_allclose(m.acc, ACC_SI * G0, rtol=1e-15)


def test_csv_milliseconds_without_a_unit_are_refused(tmp_path):
    t = np.arange(N) * 2.0  # a 500 Hz record with its time in ms: taken as seconds the step would be 2 s
    p = _csv(tmp_path / "ms.csv", "time,ground_acc", [t, ACC_SI])
    with pytest.raises(DataFileError) as e:
        GroundMotion.from_csv(p)
    msg = str(e.value)
    assert "ms.csv line 3, column `time`: time step 2 read in seconds" in msg
    assert "implausible" in msg and "`time [ms]`" in msg and "\n" not in msg
    # the same column with its unit reads; a step of 2 s written as [s] is the user's word and is kept
    assert GroundMotion.from_csv(_csv(tmp_path / "ms2.csv", "time [ms],ground_acc", [t, ACC_SI])).dt == pytest.approx(
        0.002, rel=1e-12
    )
    assert GroundMotion.from_csv(_csv(tmp_path / "s2.csv", "time [s],ground_acc", [t, ACC_SI])).dt == 2.0
    # and a step below 1e-5 s without a unit (microseconds? a typo?) is refused too
    with pytest.raises(DataFileError, match=r"time step 2e-06 read in seconds .* implausible"):
        GroundMotion.from_csv(_csv(tmp_path / "us.csv", "time,ground_acc", [t * 1e-6, ACC_SI]))
    # the edges of the plausible range are accepted: 0.1 s and 1e-5 s
    for step in (0.1, 1e-5):
        assert GroundMotion.from_csv(_csv(tmp_path / "e.csv", "time,ground_acc", [np.arange(N) * step, ACC_SI])).dt == (
            pytest.approx(step, rel=1e-9)
        )


@pytest.mark.parametrize(
    ("header", "units", "needles"),
    [
        ("time,ground_acc [furlongs]", None, ["line 1, column `ground_acc`: unknown unit [furlongs] for acceleration"]),
        ("time [m/s^2],ground_acc", None, ["line 1, column `time`: acceleration unit [m/s^2] for time"]),
        ("time,ground_acc [cm/s^2]", "g", ["column `ground_acc`: the header says [cm/s^2] but units='g' was given"]),
        ("Time,ground_acc", None, ["line 1: missing column `time`; did you mean `Time`?"]),
    ],
)
def test_csv_unit_errors_name_file_line_and_column(tmp_path, header, units, needles):
    p = _csv(tmp_path / "bad.csv", header, [np.arange(N) * DT, ACC_SI])
    with pytest.raises(DataFileError) as e:
        GroundMotion.from_csv(p, units=units)
    msg = str(e.value)
    assert msg.startswith(str(p)) and "\n" not in msg
    for n in needles:
        assert n in msg


def test_csv_not_utf8_names_the_line(tmp_path):
    p = tmp_path / "latin1.csv"
    p.write_bytes(b"time,ground_acc\n0,0\n0.01,1\n" + "# 1 \u00b0\n".encode("latin-1"))
    with pytest.raises(DataFileError, match=r"latin1\.csv line 4: not UTF-8 text \(byte 0xb0\)"):
        GroundMotion.from_csv(p)


# ----------------------------------------------------------------------------
# campaigns: from the files to the diagnosis (housner diagnose)
UNIT_PLAN = {  # record id -> (time unit, ground_acc unit, theta unit, BOM)
    "fv01": ("ms", "g", "deg", False),
    "fv02": ("s", "cm/s^2", "mrad", True),
    "fv03": ("ms", "m/s^2", "urad", False),
    "gm001": ("ms", "g", "deg", True),
    "gm002": ("s", "cm/s^2", "mrad", False),
    "gm003": ("s", "in/s^2", "rad", False),
    "gm004": ("ms", "mm/s^2", "deg", False),
}


@pytest.fixture(scope="module")
def si_campaign(tmp_path_factory):
    root = tmp_path_factory.mktemp("si")
    # a hidden restitution (0.88): the plain model misfits, so the diagnosis fits r (a campaign the plain
    # model already fits to its noise is not searched at all)
    cg.write_campaign(root, "restitution", n_ground=4, seed=3, fv_duration=3.0, gm_duration=3.0)
    return root


def _rewrite_in_units(src: Path, dst: Path) -> Path:
    shutil.copytree(src, dst)
    for rid, (tu, au, thu, bom) in UNIT_PLAN.items():
        f = dst / "records" / f"{rid}.csv"
        t, a, th = np.loadtxt(f, delimiter=",", skiprows=1).T
        cols = [t / PER_UNIT[tu], a / PER_UNIT[au], th / PER_UNIT[thu]]
        _csv(f, f"time [{tu}],ground_acc [{au}],theta [{thu}]", cols, bom=bom)
    return dst


def test_campaign_records_in_other_units_load_as_the_si_ones(si_campaign, tmp_path):
    si = load_campaign(si_campaign)
    un = load_campaign(_rewrite_in_units(si_campaign, tmp_path / "units"))
    assert not un.skipped and [r.id for r in un.records] == [r.id for r in si.records]
    for a, b in zip(si.records, un.records, strict=True):
        # value / f written with 17 digits, times f on reading: equal to a few ulp
        assert b.dt == pytest.approx(a.dt, rel=1e-12)
        np.testing.assert_allclose(b.theta, a.theta, rtol=1e-14, atol=1e-18)
        np.testing.assert_allclose(b.motion.acc, a.motion.acc, rtol=1e-14, atol=1e-18)
        # the release fit and the noise estimate see the same numbers to ~1e-15: equal far below 1e-9
        assert b.motion.theta0 == pytest.approx(a.motion.theta0, rel=1e-9, abs=1e-15)
        assert b.noise == pytest.approx(a.noise, rel=1e-9)


def _diagnose_json(campaign: Path, out: Path, capsys) -> tuple[int, dict, str]:
    rc = main(["diagnose", str(campaign), "--effects", "restitution", "-q", "--json", str(out)])
    err = capsys.readouterr().err
    return rc, (json.loads(out.read_text()) if rc == 0 else {}), err


def test_diagnose_cli_gives_the_same_answer_for_a_campaign_in_other_units(si_campaign, tmp_path, capsys):
    rc_si, si, _ = _diagnose_json(si_campaign, tmp_path / "si.json", capsys)
    rc_un, un, err = _diagnose_json(_rewrite_in_units(si_campaign, tmp_path / "units"), tmp_path / "un.json", capsys)
    assert rc_si == rc_un == 0 and "skipped record" not in err
    # inputs equal to ~1e-15; perturbations grow at most like e^(p t) = e^(4.9 * 3) ~ 2e6 over a 3 s record
    # (negative stiffness of the upright block), so 1e-6 is far above what rounding can do and far below
    # what a unit left unconverted does (a factor 9.8, 100 or 1000)
    assert un["baseline"]["heldout_error"] == pytest.approx(si["baseline"]["heldout_error"], rel=1e-6)
    assert un["baseline"]["noise_floor"] == pytest.approx(si["baseline"]["noise_floor"], rel=1e-6)
    assert un["candidates"][0]["params"]["r"] == pytest.approx(si["candidates"][0]["params"]["r"], rel=1e-6)


def test_diagnose_cli_skips_a_record_in_milliseconds_without_a_unit(si_campaign, tmp_path, capsys):
    d = tmp_path / "c"
    shutil.copytree(si_campaign, d)
    f = d / "records" / "fv03.csv"
    t, a, th = np.loadtxt(f, delimiter=",", skiprows=1).T
    _csv(f, "time,ground_acc,theta", [t * 1e3, a, th])
    rc, _, err = _diagnose_json(d, tmp_path / "x.json", capsys)
    assert rc == 0
    line = next(ln for ln in err.splitlines() if ln.startswith("skipped record fv03"))
    assert "fv03.csv line 3, column `time`: time step 2 read in seconds" in line and "`time [ms]`" in line


_HEAD = 'name = "t"\n[specimen]\nheight = 0.5\nwidth = 0.075\ndepth = 0.4\nmass = 3.94\np = 4.8883\n'
_REC = '[[record]]\nid = "gm001"\nkind = "ground_motion"\nfile = "records/gm001.csv"\n'


@pytest.mark.parametrize(
    ("text", "needles"),
    [
        ("record = [1, 2]\n" + _HEAD, ["line 1:", "`record` must be an array of tables", "got int 1"]),
        ('record = "gm001"\n' + _HEAD, ["line 1:", "`record` must be an array of tables", "got str"]),
        ("record = []\n" + _HEAD, ["line 1:", "`record` is empty"]),
        ("specimen = 5\n" + _REC, ["line 1:", "`specimen` must be a table", "got int 5"]),
        ("description = 1\n" + _HEAD + _REC, ["line 1:", "'description' must be a string, got 1"]),
        ('name = ["a"]\n' + _HEAD.replace('name = "t"\n', "") + _REC, ["line 1:", "'name' must be a string"]),
        (_HEAD + _REC.replace('"gm001"\nkind', "5\nkind"), ["line 9:", "'id' must be a non-empty string, got 5"]),
        (_HEAD.replace("0.075", '"0.075"') + _REC, ["line 4:", "'width' must be a positive number"]),
        (_HEAD + _REC + 'overturned = "yes"\n', ["line 12:", "'overturned' must be true or false"]),
        (_HEAD + '[record]\nid = "gm001"\n', ["line 8:", "`record` must be an array of tables", "got dict"]),
        (_HEAD.replace("mass = 3.94", "mass = true") + _REC, ["line 6:", "'mass' must be a positive number"]),
    ],
)
def test_wrong_types_in_campaign_toml_are_one_line_cli_errors(si_campaign, tmp_path, capsys, text, needles):
    d = tmp_path / "c"
    shutil.copytree(si_campaign, d)
    (d / "campaign.toml").write_text(text)
    assert main(["diagnose", str(d), "-q"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("housner: error: ") and "Traceback" not in err
    assert "campaign.toml" in err
    for n in needles:
        assert n in err


def test_campaign_toml_with_a_byte_order_mark_reads(si_campaign, tmp_path):
    d = tmp_path / "c"
    shutil.copytree(si_campaign, d)
    toml = d / "campaign.toml"
    toml.write_bytes(b"\xef\xbb\xbf" + toml.read_bytes())
    assert len(load_campaign(d).records) == 7


# ----------------------------------------------------------------------------
# plausibility: an acceleration read in m/s^2 because nothing said otherwise, with a peak above 5 g
def test_csv_record_in_gal_without_a_unit_is_refused_naming_the_unit(tmp_path):
    t = np.arange(200) * 0.01
    gal = 320.0 * np.sin(2 * np.pi * t)  # 0.33 g written in cm/s^2, read as m/s^2 it would be 33 g
    p = _csv(tmp_path / "rec.csv", "time,ground_acc", [t, gal])
    with pytest.raises(DataFileError) as e:
        GroundMotion.from_csv(p)
    msg = str(e.value)
    assert "\n" not in msg and "rec.csv line" in msg and "column `ground_acc`" in msg
    assert "look like cm/s^2" in msg and "`ground_acc [cm/s^2]`" in msg
    ok = GroundMotion.from_csv(_csv(tmp_path / "ok.csv", "time,ground_acc [cm/s^2]", [t, gal]))
    assert np.max(np.abs(ok.acc)) == pytest.approx(3.2, rel=1e-3)
    # a plausible peak (4 g) in m/s^2 without a unit is read as before
    assert GroundMotion.from_csv(_csv(tmp_path / "g4.csv", "time,ground_acc", [t, gal / 8.0])).n == 200


def test_campaign_ground_acc_a_hundred_times_too_large_is_refused(si_campaign, tmp_path):
    d = tmp_path / "c"
    shutil.copytree(si_campaign, d)
    for f in sorted((d / "records").glob("gm*.csv")):
        t, a, th = np.loadtxt(f, delimiter=",", skiprows=1).T
        _csv(f, "time,ground_acc,theta", [t, a * 100.0 + np.sign(a) * 60.0, th])  # cm/s^2, peak above 5 g
    # 4 of 7 records unreadable: the campaign is refused as a whole, its message naming the likely unit
    with pytest.raises(DataFileError) as e:
        load_campaign(d)
    msg = str(e.value)
    assert "\n" not in msg and "4 of 7 records could not be read" in msg
    assert "the values look like cm/s^2" in msg and "`ground_acc [cm/s^2]`" in msg


def test_a_scenario_declares_the_unit_of_a_bare_at2(tmp_path):
    from housner.scenarios import load_scenario
    from housner.scenarios.catalogue import ScenarioError

    _at2(tmp_path / "bare.AT2", ["X", "Y", "Z"], ACC_SI / 0.01)
    body = '[specimen]\npreset = "bachmann2017"\n[motions]\nsource = "record"\nrecord = "bare.AT2"\n'
    (tmp_path / "a.toml").write_text(body)
    with pytest.raises(ScenarioError, match=r"declare the unit: `units = \"g\"`.*\[motions\] table"):
        load_scenario(tmp_path / "a.toml")
    (tmp_path / "b.toml").write_text(body + 'units = "cm/s^2"\n')
    m, _facts = load_scenario(tmp_path / "b.toml").record_files()["record"][0]
    np.testing.assert_allclose(m.acc, ACC_SI, rtol=1e-7)
    (tmp_path / "c.toml").write_text(body + 'units = "cm/s"\n')
    with pytest.raises(ScenarioError, match=r"line 6: \[motions\] 'units' must be an acceleration unit"):
        load_scenario(tmp_path / "c.toml")
