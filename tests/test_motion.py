"""GroundMotion: readers, validation, scaling."""

import math
from pathlib import Path

import numpy as np
import pytest

from housner import DataFileError, G, GroundMotion

DATA = Path(__file__).resolve().parents[1] / "scenarios" / "catalogue" / "data"


@pytest.mark.parametrize(
    "fname, npts, dt, pga_g",
    [
        # NPTS, DT and PGA from the table in shared/data/README.md (computed independently there).
        ("elcentro_1940_ns_I-ELC180_peer1999.AT2", 4000, 0.01, 0.3129),
        ("elcentro_1940_ns_RSN6_ngawest2.AT2", 5372, 0.01, 0.2808),
        ("elcentro_1940_ns_chopra_dt002.txt", 1559, 0.02, 0.3188),
    ],
)
def test_at2_layouts(fname, npts, dt, pga_g):
    m = GroundMotion.from_at2(DATA / fname)
    assert m.n == npts
    assert m.dt == pytest.approx(dt, rel=1e-12)
    assert m.pga / G == pytest.approx(pga_g, abs=5e-5)  # the table has 4 decimals
    assert "g -> m/s^2" in m.provenance


def test_at2_errors_name_file_and_line(tmp_path):
    good = (DATA / "elcentro_1940_ns_I-ELC180_peer1999.AT2").read_text().splitlines()
    bad = good[:]
    bad[10] = bad[10].replace(bad[10].split()[2], "abc", 1)
    p = tmp_path / "bad.AT2"
    p.write_text("\n".join(bad))
    with pytest.raises(DataFileError, match=r"bad.AT2 line 11: not a number: 'abc'"):
        GroundMotion.from_at2(p)
    p.write_text("\n".join(good[:100]))
    with pytest.raises(DataFileError, match=r"line 4: header says NPTS=4000 but 480 samples follow"):
        GroundMotion.from_at2(p)
    p.write_text("just text\n1 2 3\n")
    with pytest.raises(DataFileError, match="no 'NPTS= n, DT= dt' header"):
        GroundMotion.from_at2(p)
    with pytest.raises(DataFileError, match="cannot read"):
        GroundMotion.from_at2(tmp_path / "missing.AT2")


def test_csv_reader_and_errors(tmp_path):
    t = np.arange(6) * 0.002
    a = np.sin(t * 100)
    p = tmp_path / "m.csv"
    p.write_text("time,ground_acc\n" + "".join(f"{float(x)!r},{float(y)!r}\n" for x, y in zip(t, a, strict=True)))
    m = GroundMotion.from_csv(p)
    assert m.dt == pytest.approx(0.002)
    np.testing.assert_array_equal(m.acc, a)
    mg = GroundMotion.from_csv(p, units="g")
    np.testing.assert_allclose(mg.acc, a * G)

    rows = ["time,ground_acc", "0,0", "0.002,1", "0.0045,2", "0.006,3"]
    p.write_text("\n".join(rows))
    with pytest.raises(DataFileError, match=r"m.csv line 4, column `time`: non-uniform sampling"):
        GroundMotion.from_csv(p)
    rows = ["time,ground_acc", "0,0", "0.002,nan", "0.004,2"]
    p.write_text("\n".join(rows))
    with pytest.raises(DataFileError, match=r"line 3, column `ground_acc`: value is not finite"):
        GroundMotion.from_csv(p)
    p.write_text("time,acc\n0,1\n")
    with pytest.raises(DataFileError, match=r"line 1: missing column `ground_acc`"):
        GroundMotion.from_csv(p)
    p.write_text("")
    with pytest.raises(DataFileError, match="empty"):
        GroundMotion.from_csv(p)


def test_constructor_validation():
    with pytest.raises(ValueError, match="`acc`.*empty"):
        GroundMotion([], 0.01)
    with pytest.raises(ValueError, match="`acc`.*not finite at sample 1"):
        GroundMotion([0.0, np.inf], 0.01)
    with pytest.raises(ValueError, match="`dt`"):
        GroundMotion([0.0, 1.0], 0.0)
    with pytest.raises(ValueError, match="`theta0`"):
        GroundMotion([0.0, 1.0], 0.01, theta0=2.0)


def test_scaling_time_and_amplitude():
    m = GroundMotion(np.array([0.0, 1.0, -2.0]), 0.01, theta_dot0=0.5)
    s = m.to_model_scale(10.0)
    # seed eq. 9: omega_model = omega_prototype sqrt(S) -> dt_model = dt / sqrt(S); accelerations unchanged
    assert s.dt == pytest.approx(0.01 / math.sqrt(10.0))
    np.testing.assert_array_equal(s.acc, m.acc)
    assert s.theta_dot0 == pytest.approx(0.5 * math.sqrt(10.0))  # rates scale with 1/time
    a = m.scaled(amplitude=2.0)
    np.testing.assert_array_equal(a.acc, 2 * m.acc)
    with pytest.raises(ValueError, match="`time`"):
        m.scaled(time=0)
    assert m.with_duration(0.05).n == 6
    assert m.content_hash() == GroundMotion(m.acc.copy(), 0.01, theta_dot0=0.5).content_hash()
