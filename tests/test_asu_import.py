"""``housner campaign from-asu``: the ASU granite shake-table tests written as a campaign.

The original-format path is checked on the small synthetic data set in tests/data/asu_small (its
script says what the signals are) against an independent reading and decimation, and against the
signals' closed forms; the npz path on the shared derived data set, when it is there.
"""

from __future__ import annotations

import importlib.util
import math
import shutil
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from scipy import signal

from housner.cli import main
from housner.errors import DataFileError
from housner.scenarios.campaigns.asu import ImportResult, import_asu
from housner.scenarios.campaigns.campaign import load_campaign

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

SMALL = Path(__file__).parent / "data" / "asu_small"
SHARED = Path(__file__).resolve().parents[2] / "shared/data/asu-granite"
G = 9.80665  # [m/s^2]
M_PER_VOLT = 5.9797e-4 * 0.0254
#: The README's decimation filter: 161 taps, 85 Hz, Kaiser window with beta 8.
README_FILTER = signal.firwin(161, 85.0, window=("kaiser", 8.0), fs=800)
#: One float32 unit in the last place, relative [-]: the records store float32, written to read back exactly.
F32 = 2.0**-23


def _generator():
    spec = importlib.util.spec_from_file_location("make_asu_small", SMALL / "make_asu_small.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


GEN = _generator()


def _raw(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """Columns 2 [g] and 6 [V] of an original file, read independently of the importer."""
    x = np.loadtxt(path, delimiter="\t", skiprows=1, usecols=(1, 5))
    return x[:, 0], x[:, 1]


def _record(out: Path, test: str) -> pd.DataFrame:
    """A record file, its header checked (units declared: the table's spikes reach 5.9 g, test 183)."""
    rec = pd.read_csv(out / "records" / f"{test}.csv")
    assert list(rec.columns) == ["time [s]", "ground_acc [m/s^2]"]
    return rec.set_axis(["time", "ground_acc"], axis=1)


def _toml(out: Path) -> dict:
    return tomllib.loads((out / "campaign.toml").read_text(encoding="utf-8"))


@pytest.fixture
def data(tmp_path) -> Path:
    """A copy of the small data set, free to be spoiled."""
    return shutil.copytree(SMALL, tmp_path / "data")


@pytest.fixture(scope="module")
def small(tmp_path_factory) -> tuple[ImportResult, Path, list[str]]:
    """The small data set imported once: the result, OUT, and the progress lines."""
    out = tmp_path_factory.mktemp("asu") / "campaign"
    lines: list[str] = []
    return import_asu(SMALL, out, progress=lines.append), out, lines


def test_small_data_set_matches_its_script(tmp_path):
    for path in GEN.write(tmp_path):
        assert path.read_bytes() == (SMALL / path.relative_to(tmp_path)).read_bytes(), path.name


def test_records_in_test_order_with_their_outcomes(small):
    result, out, _ = small
    doc = _toml(out)
    assert [r["id"] for r in doc["record"]] == ["Test011", "Test012", "Test017"]  # index.csv lists 12 first
    assert [r["overturned"] for r in doc["record"]] == [False, True, False]
    assert all(r["kind"] == "ground_motion" and r["file"] == f"records/{r['id']}.csv" for r in doc["record"])
    assert (result.n_records, result.n_overturned, result.n_absent) == (3, 1, 1)  # Test013: present = 0
    assert sorted(p.name for p in (out / "records").iterdir()) == ["Test011.csv", "Test012.csv", "Test017.csv"]
    assert doc["name"] == "ASU granite shake-table tests (2021), specimen SP1"
    assert doc["description"].startswith(f"imported by housner campaign from-asu from {SMALL.resolve()};")
    assert doc["description"].endswith("outcomes from column overturn_SP1")
    assert doc["specimen"] == {"mesh": "SP1.obj", "azimuth": 0.0, "contact": "hull", "density": 2700.0}
    assert (out / "SP1.obj").read_bytes() == (SMALL / "SP1.obj").read_bytes()
    assert "imported 3 records (1 overturned)" in result.summary
    assert "left out: 3" in result.summary and "1 test listed without a file" in result.summary


def test_tests_that_cannot_be_imported_are_reported_in_one_line_each(small):
    result, _, lines = small
    reasons = dict(result.left_out)
    assert list(reasons) == ["Test014", "Test015", "Test016"]
    assert reasons["Test014"] == "no outcome in column overturn_SP1 (index.csv line 5)"
    assert reasons["Test015"].startswith("Test015.txt not found in ") and reasons["Test015"].endswith(
        "(index.csv line 6)"
    )
    assert reasons["Test016"].endswith("Test016.txt line 7, column 2: 'n/a' is not a number")
    assert sorted(lines) == sorted(f"{t}: {r}: left out" for t, r in result.left_out)
    assert all("\n" not in line for line in lines)


@pytest.mark.parametrize("test", ["Test011", "Test012", "Test017"])
def test_acceleration_is_the_readme_processing_of_column_2(small, test):
    """Bias (whole-record mean) removed, g -> m/s^2, then resample_poly(1, 4) with the README's filter."""
    _, out, _ = small
    raw = next(SMALL.rglob(f"{test}.txt"))
    acc_g, _ = _raw(raw)
    want = signal.resample_poly((acc_g - acc_g.mean()) * G, 1, 4, window=README_FILTER)
    rec = _record(out, test)
    assert len(rec) == acc_g.size // 4
    np.testing.assert_array_equal(rec["time"].to_numpy(), np.arange(len(rec)) / 200.0)
    # float32 storage: within one unit in the last place of float32
    np.testing.assert_allclose(rec["ground_acc"].to_numpy(), want, rtol=F32, atol=1e-30)


@pytest.mark.parametrize("test", [11, 12, 17])
def test_decimation_keeps_the_band_and_removes_the_bias_and_above_100_hz(small, test):
    """Against the closed form: the 2, 7 and 60 Hz terms kept with gain 1, the bias and 110 Hz gone.

    The README's filter passes 2 to 60 Hz within 4.4e-5 and stops 110 Hz to 3.4e-5 (under 8e-5 from
    100 Hz): together under 6e-6 g here, with the 6-digit text of the file; 2e-5 g is the bound. A
    Hamming window (firwin's default) would miss it: it leaks 1.1e-3 at 110 Hz and passes 7 Hz at 0.9988.
    """
    _, out, _ = small
    k, _, _ = GEN.SIGNALS[test]
    rec = _record(out, f"Test{test:03d}")
    t = rec["time"].to_numpy()
    inner = (t > 0.15) & (t < t[-1] - 0.15)  # the filter spans +-0.1 s: edge transients left out
    s = lambda f: np.sin(2 * np.pi * f * t)  # noqa: E731
    want = G * (k * (0.1 * s(2) + 0.05 * s(7)) + 0.02 * s(60))
    err = np.abs(rec["ground_acc"].to_numpy() - want)[inner]
    assert err.max() < 2e-5 * G, f"{err.max() / G:.2e} g"


@pytest.mark.parametrize("test", [11, 12, 17])
def test_pgv_is_from_the_displacement_channel(small, test):
    """pgv: column 6 [V] -> m, decimated, 20 Hz 4th-order Butterworth both ways, central differences."""
    _, out, _ = small
    rec = next(r for r in _toml(out)["record"] if r["id"] == f"Test{test:03d}")
    _, volts = _raw(next(SMALL.rglob(f"Test{test:03d}.txt")))
    disp = signal.resample_poly(volts * M_PER_VOLT, 1, 4, window=README_FILTER)
    sos = signal.butter(4, 20.0, fs=200.0, output="sos")
    want = np.abs(np.gradient(signal.sosfiltfilt(sos, disp), 1 / 200.0)).max()
    assert rec["pgv"] == pytest.approx(want, rel=1e-5)  # written with 6 significant digits
    # closed form k 0.01 pi: central differences at 200 Hz err by (2 pi 1 Hz dt)^2 / 6 = 1.6e-4
    assert rec["pgv"] == pytest.approx(GEN.SIGNALS[test][0] * 0.01 * math.pi, rel=1e-3)


def test_a_file_with_a_wrong_column_count_is_left_out_with_its_line(data, tmp_path):
    path = data / "Test011.txt"
    lines = path.read_bytes().split(b"\r\n")
    lines[9] = b"\t".join(lines[9].split(b"\t")[:7])  # line 10: 7 columns, no trailing tab
    path.write_bytes(b"\r\n".join(lines))
    result = import_asu(data, tmp_path / "out")
    reasons = dict(result.left_out)
    assert reasons["Test011"] == f"{path} line 10: 7 columns, expected 8 (tab-separated)"
    assert [r["id"] for r in _toml(tmp_path / "out")["record"]] == ["Test012", "Test017"]


def test_a_file_that_index_csv_does_not_list_is_reported(data, tmp_path):
    shutil.copyfile(data / "Test012.txt", data / "Test099.txt")
    result = import_asu(data, tmp_path / "out")
    assert dict(result.left_out)["Test099"] == f"in {data / 'Test099.txt'} but not listed in index.csv (no outcome)"
    assert result.n_records == 3


def test_a_previous_import_is_replaced_and_anything_else_refused(data, tmp_path):
    out = tmp_path / "out"
    import_asu(data, out)
    (data / "Test012.txt").unlink()
    result = import_asu(data, out)  # replaced whole: Test012's record goes
    assert result.n_records == 2 and not (out / "records" / "Test012.csv").exists()
    (out / "notes.txt").write_text("mine")
    with pytest.raises(DataFileError, match="notes.txt"):
        import_asu(data, out)
    assert (out / "notes.txt").read_text() == "mine" and (out / "campaign.toml").is_file()
    other = tmp_path / "other"
    other.mkdir()
    (other / "a.csv").write_text("x")
    with pytest.raises(DataFileError, match="not empty and not a campaign written by"):
        import_asu(data, other)
    assert [p.name for p in other.iterdir()] == ["a.csv"]


def test_a_failed_import_leaves_no_campaign_and_keeps_the_previous_one(data, tmp_path):
    out = tmp_path / "out"
    import_asu(data, out)
    before = (out / "campaign.toml").read_text()
    with pytest.raises(DataFileError, match="no test could be imported"):
        import_asu(data, out, flags="date")  # 20210621 is no outcome: every test left out
    assert (out / "campaign.toml").read_text() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["data", "out"]  # no hidden half campaign
    with pytest.raises(DataFileError, match="no test could be imported"):
        import_asu(data, tmp_path / "new", flags="date")
    assert not (tmp_path / "new").exists()


def _drop_column(data: Path, name: str) -> None:
    ix = pd.read_csv(data / "index.csv", dtype=str, keep_default_na=False)
    ix.drop(columns=[name]).to_csv(data / "index.csv", index=False)


def test_each_record_carries_the_ground_motion_it_played_as_its_group(data, tmp_path):
    ix = pd.read_csv(data / "index.csv", dtype=str, keep_default_na=False)
    names = {"11": "RSN1_A.AT2", "12": 'RSN2 "B"', "17": "RSN1_A.AT2"}  # a quote: written as a TOML escape
    ix["record"] = [names.get(t, "RSN9_OTHER") for t in ix["test"]]
    ix.to_csv(data / "index.csv", index=False)
    out = tmp_path / "out"
    import_asu(data, out)
    assert [(r["id"], r["group"]) for r in _toml(out)["record"]] == [
        ("Test011", "RSN1_A.AT2"),
        ("Test012", 'RSN2 "B"'),
        ("Test017", "RSN1_A.AT2"),
    ]
    assert load_campaign(out).outcome_groups == ["RSN1_A.AT2", 'RSN2 "B"', "RSN1_A.AT2"]
    # without the record column nothing else changes: the same campaign.toml less its group lines
    _drop_column(data, "record")
    import_asu(data, tmp_path / "without")
    with_groups = (out / "campaign.toml").read_text().splitlines()
    assert (tmp_path / "without" / "campaign.toml").read_text().splitlines() == [
        ln for ln in with_groups if not ln.startswith("group = ")
    ]
    assert load_campaign(tmp_path / "without").outcome_groups == ["Test011", "Test012", "Test017"]


@pytest.mark.parametrize(
    ("spoil", "kwargs", "message"),
    [
        (lambda d: shutil.rmtree(d), {}, "no such folder"),
        (lambda d: [p.unlink() for p in d.rglob("Test*.txt")], {}, "holds neither asu_granite_200hz.npz nor"),
        (lambda d: (d / "index.csv").unlink(), {}, "index.csv: no such file"),
        (lambda d: _drop_column(d, "present"), {}, "index.csv line 1: no column `present`"),
        (lambda d: None, {"flags": "overturn_sp1"}, "no outcome column `overturn_sp1`; did you mean `overturn_SP1`?"),
        (lambda d: None, {"specimen": "SP2"}, "(outcome columns: overturn_SP1; choose one with --flags COLUMN)"),
        (lambda d: (d / "SP1.obj").unlink(), {}, "no mesh of specimen SP1; give one with --mesh FILE"),
        (lambda d: (d / "SP1.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"), {}, "watertight"),
        # the mesh's, azimuth's and contact's messages are housner.scan's: only the name they give is checked
        (lambda d: None, {"azimuth": 360.0}, "`azimuth`"),
        (lambda d: None, {"contact": "flat"}, "`contact`"),
    ],
    ids=["no-data", "no-files", "no-index", "no-column", "flags", "specimen", "no-mesh", "mesh", "azimuth", "contact"],
)
def test_bad_input_is_refused_in_one_line_before_writing(data, tmp_path, spoil, kwargs, message):
    spoil(data)
    with pytest.raises(ValueError) as e:
        import_asu(data, tmp_path / "out", **kwargs)
    assert message in str(e.value) and "\n" not in str(e.value)
    assert not (tmp_path / "out").exists()


def test_mesh_in_millimetres_is_refused(data, tmp_path):
    text = (data / "SP1.obj").read_text().splitlines()
    scaled = [
        " ".join(["v", *(f"{1000 * float(c):g}" for c in ln.split()[1:])]) if ln.startswith("v ") else ln for ln in text
    ]
    (tmp_path / "mm.obj").write_text("\n".join(scaled) + "\n")
    with pytest.raises(DataFileError, match="metres"):
        import_asu(data, tmp_path / "out", mesh=tmp_path / "mm.obj")
    assert not (tmp_path / "out").exists()


def test_cli_writes_the_campaign(data, tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["campaign", "from-asu", str(data), str(out), "--azimuth", "90", "--contact", "flat:0.005"]) == 0
    assert _toml(out)["specimen"] == {"mesh": "SP1.obj", "azimuth": 90.0, "contact": "flat:0.005", "density": 2700.0}
    std = capsys.readouterr()
    assert std.out.startswith("imported 3 records (1 overturned)") and std.out.count("\n") == 1
    assert std.err.count("\n") == 3 and all(line.endswith(": left out") for line in std.err.splitlines())


def test_cli_bad_flag_column_is_one_line_and_status_2(data, tmp_path, capsys):
    assert main(["campaign", "from-asu", str(data), str(tmp_path / "out"), "--flags", "overturn_SP9"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("housner: error: ") and "did you mean `overturn_SP1`?" in err
    assert not (tmp_path / "out").exists()


@pytest.mark.skipif(not (SHARED / "asu_granite_200hz.npz").is_file(), reason=f"{SHARED} not here")
def test_shared_data_set(tmp_path):
    """The whole derived data set: 490 records (92 listed without a file), 187 of them overturned, of 56 motions."""
    out = tmp_path / "asu"
    result = import_asu(SHARED, out)
    assert (result.n_records, result.n_overturned, result.n_absent, result.left_out) == (490, 187, 92, ())
    doc = _toml(out)
    ix = pd.read_csv(SHARED / "index.csv").query("present == 1").sort_values("test")
    assert [r["id"] for r in doc["record"]] == [f"Test{t:03d}" for t in ix["test"]]
    assert [r["overturned"] for r in doc["record"]] == ix["overturn_SP1"].astype(bool).tolist()
    with np.load(SHARED / "asu_granite_200hz.npz") as z:
        o, n = int(z["offset"][0]), int(z["n_samples"][0])
        first = z["acc_mps2"][o : o + n]
        assert int(z["test"][0]) == 11
    rec = _record(out, "Test011")
    np.testing.assert_array_equal(rec["ground_acc"].to_numpy().astype(np.float32), first)  # read back exactly
    # The same recipe as the README's pgv_meas_disp_mps (a 20 Hz, 4th-order Butterworth both ways, central
    # differences) on the same float32 samples agrees to 4e-6 (6 digits written); the README does not state
    # the filter's order, and a 2nd-order one would differ by up to 6 %: 1e-3 tells the two apart.
    np.testing.assert_allclose([r["pgv"] for r in doc["record"]], ix["pgv_meas_disp_mps"], rtol=1e-3)
    # each test's group is the ground motion it played, index.csv's record: 490 tests of 56 motions at 2-14
    # scalings each (counted from index.csv's rows with present == 1)
    groups = [r["group"] for r in doc["record"]]
    assert groups == ix["record"].tolist()
    sizes = pd.Series(groups).value_counts()
    assert (len(groups), len(sizes), sizes.min(), sizes.max()) == (490, 56, 2, 14)
