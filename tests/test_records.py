"""The shipped El Centro records, the intensity measures read from them, and the AT2 reader's error paths."""

from __future__ import annotations

import hashlib
import math
from importlib import resources

import numpy as np
import pytest

from housner import DataFileError, GroundMotion
from housner.scenarios.motions.records import (
    ELCENTRO_VARIANTS,
    RECORDS,
    arias_intensity,
    elcentro,
    husid,
    husid_time,
    load_record,
    significant_duration,
    t_mid,
)
from housner.units import G

# Values from shared/data/README.md (computed there independently of this code).
# PGA and Ia are printed to 4 significant digits, so their tolerance is half a
# unit in the last printed digit. Husid times there are sample times (the first
# sample reaching the fraction) while husid_time interpolates between samples,
# so times and durations may differ by up to one step dt (plus the rounding).
TABLE = {
    "peer1999": dict(npts=4000, dt=0.01, pga_g=0.3129, t_pga=2.15, Ia=1.703, t5=1.99, t95=26.09, D=24.10, tmid=4.90),
    "ngawest2": dict(npts=5372, dt=0.01, pga_g=0.2808, t_pga=2.18, Ia=1.556, t5=2.12, t95=26.31, D=24.19, tmid=5.12),
    "chopra": dict(npts=1559, dt=0.02, pga_g=0.3188, t_pga=2.02, Ia=1.801, t5=None, t95=None, D=23.84, tmid=4.58),
}
SHA256 = {
    "peer1999": "edcd5353db8a9305227293142a3b8b8a7622b273f886c5e739dea451f0111063",
    "ngawest2": "8d790c830a2b69b07eb953770316ddc8432f247624f0d1ea027ab2c56bbc166d",
    "chopra": "fcc4417f9eba2083d8573010659d1e8177e1f795f47a8e8faa9382ef6fa753a0",
}


@pytest.mark.parametrize("variant", sorted(TABLE))
def test_record_statistics_match_the_data_table(variant):
    rec = elcentro(variant)
    row = TABLE[variant]
    assert rec.n == row["npts"]
    assert rec.dt == row["dt"]
    assert rec.name == f"elcentro-{variant}"
    k = int(np.argmax(np.abs(rec.acc)))
    assert rec.acc[k] < 0.0  # all three peaks are negative
    assert rec.pga / G == pytest.approx(row["pga_g"], abs=0.5e-4)
    assert rec.t[k] == pytest.approx(row["t_pga"], abs=0.5e-2)
    assert arias_intensity(rec) == pytest.approx(row["Ia"], abs=0.5e-3)
    tol = rec.dt + 0.5e-2
    assert significant_duration(rec) == pytest.approx(row["D"], abs=tol)
    assert t_mid(rec) == pytest.approx(row["tmid"], abs=tol)
    if row["t5"] is not None:
        assert husid_time(rec, [0.05, 0.95]) == pytest.approx([row["t5"], row["t95"]], abs=tol)


@pytest.mark.parametrize("variant", sorted(SHA256))
def test_shipped_files_are_the_documented_bytes(variant):
    data = resources.files("housner.scenarios.catalogue").joinpath("data", ELCENTRO_VARIANTS[variant][0]).read_bytes()
    assert hashlib.sha256(data).hexdigest() == SHA256[variant]


def test_default_is_peer1999_with_provenance_and_citation():
    rec = elcentro()
    assert rec.name == "elcentro-peer1999"
    assert rec.n == 4000 and rec.dt == 0.01
    assert rec.pga / G == pytest.approx(0.313, abs=5e-4)
    for text in ("I-ELC180", "PEER", "Imperial Valley", "g -> m/s^2"):
        assert text in rec.provenance
    assert "Ancheta" in elcentro("ngawest2").provenance
    assert "Chopra" in elcentro("chopra").provenance


def test_registry_loads_every_record_and_names_the_choices():
    assert set(RECORDS) == {"elcentro", "elcentro-peer1999", "elcentro-ngawest2", "elcentro-chopra"}
    np.testing.assert_array_equal(load_record("elcentro").acc, elcentro().acc)
    for name in RECORDS:
        assert isinstance(load_record(name), GroundMotion)
    with pytest.raises(ValueError, match=r"unknown record 'elcentr'; did you mean 'elcentro'\?.*choices"):
        load_record("elcentr")
    with pytest.raises(ValueError, match=r"unknown El Centro variant 'peer'.*chopra, ngawest2, peer1999"):
        elcentro("peer")


def test_arias_intensity_of_a_sine_is_the_closed_form():
    # a = A sin(2 pi t / Tp) over whole periods: int a^2 dt = A^2 L / 2, so
    # Ia = pi A^2 L / (4 g). The trapezoidal rule is exact for whole periods of
    # sin^2 sampled uniformly (aliasing-free below Nyquist), so rtol 1e-12.
    dt, L, A = 0.005, 12.0, 2.0
    t = np.arange(int(round(L / dt)) + 1) * dt
    m = GroundMotion(A * np.sin(2 * np.pi * t / 0.75), dt)
    assert arias_intensity(m) == pytest.approx(math.pi * A**2 * L / (4 * G), rel=1e-12)


def test_husid_of_constant_amplitude_is_linear():
    # |a| constant: Ia(t) grows linearly, so t at fraction p is p L and D5-95 = 0.9 L.
    dt, L = 0.01, 20.0
    n = int(round(L / dt)) + 1
    m = GroundMotion(np.where(np.arange(n) % 2, 1.0, -1.0), dt)
    t, h = husid(m)
    assert h[0] == 0.0 and h[-1] == 1.0 and np.all(np.diff(h) >= 0)
    assert significant_duration(m) == pytest.approx(0.9 * L, abs=1e-9)
    assert t_mid(m) == pytest.approx(0.45 * L, abs=1e-9)
    with pytest.raises(ValueError, match="`fraction`"):
        husid_time(m, 1.5)
    with pytest.raises(ValueError, match="zero Arias intensity"):
        husid(GroundMotion(np.zeros(10), dt))


# ----------------------------------------------------------------------
# Reader error paths: bad files written to tmp_path
# ----------------------------------------------------------------------
HEADER = [
    "PEER STRONG MOTION DATABASE RECORD. PROCESSING BY PACIFIC ENGINEERING.",
    "TEST RECORD",
    "ACCELERATION TIME HISTORY IN UNITS OF G.",
]


def _write(path, lines):
    path.write_text("\n".join(lines) + "\n")
    return path


def _rows(values, per_line=5):
    return ["".join(f"{v:15.7E}" for v in values[i : i + per_line]) for i in range(0, len(values), per_line)]


def test_a_well_formed_file_reads_back(tmp_path):
    vals = [0.01 * k for k in range(12)]
    path = _write(tmp_path / "ok.AT2", HEADER + ["NPTS=   12, DT= .00500 SEC"] + _rows(vals))
    m = GroundMotion.from_at2(path)
    assert m.n == 12 and m.dt == 0.005
    np.testing.assert_allclose(m.acc, np.array(vals) * G, rtol=1e-7)


def test_truncated_file_names_file_and_header_line(tmp_path):
    path = _write(tmp_path / "short.AT2", HEADER + ["NPTS=   12, DT= .01000 SEC"] + _rows([0.1] * 7))
    with pytest.raises(DataFileError, match=r"short\.AT2 line 4: header says NPTS=12 but 7 samples follow") as e:
        GroundMotion.from_at2(path)
    assert e.value.path == path and e.value.line == 4


def test_more_samples_than_npts_is_an_error(tmp_path):
    path = _write(tmp_path / "long.AT2", HEADER + ["NPTS=    5, DT= .01000 SEC"] + _rows([0.1] * 10))
    with pytest.raises(DataFileError, match=r"long\.AT2 line 4: header says NPTS=5 but 10 samples follow"):
        GroundMotion.from_at2(path)


def test_non_numeric_token_names_its_line(tmp_path):
    rows = _rows([0.1] * 10)
    rows[1] = rows[1][:15] + "   0.1x000E-01" + rows[1][30:]
    path = _write(tmp_path / "bad.AT2", HEADER + ["NPTS=   10, DT= .01000 SEC"] + rows)
    with pytest.raises(DataFileError, match=r"bad\.AT2 line 6: not a number: '0\.1x000E-01'") as e:
        GroundMotion.from_at2(path)
    assert e.value.line == 6


def test_missing_header_names_the_file(tmp_path):
    path = _write(tmp_path / "nohdr.AT2", HEADER + _rows([0.1] * 10))
    with pytest.raises(DataFileError, match=r"nohdr\.AT2: no 'NPTS= n, DT= dt' header line") as e:
        GroundMotion.from_at2(path)
    assert e.value.path == path


def test_crlf_and_end_marker_layouts_read(tmp_path):
    vals = [0.02, -0.01, 0.03, 0.0, 0.01, -0.02, 0.0, 0.005]
    crlf = tmp_path / "crlf.AT2"
    crlf.write_bytes(("\r\n".join(HEADER + ["NPTS=    8, DT=   .0100 SEC,"] + _rows(vals)) + "\r\n").encode())
    marker = _write(
        tmp_path / "marker.txt",
        # free-text header (like the Chopra file's): the reader finds the units in it, then the NPTS line
        ["free text"] * 4
        + [
            "The units are (g)",
            "*** Begin data ***",
            "NPTS=     8, DT= .02000 SEC",
            "".join(f"{v:10.5f}" for v in vals),
        ]
        + ["*** End Data ***", "", ""],
    )
    for path, dt in ((crlf, 0.01), (marker, 0.02)):
        m = GroundMotion.from_at2(path)
        assert m.dt == dt
        np.testing.assert_allclose(m.acc, np.array(vals) * G, rtol=1e-7)
