"""Recorded ground motions shipped with the suite, and the intensity measures read from them.

The records are byte copies of public files (see ``scenarios/catalogue/data/README.md``
for sources, checksums and how to cite them); they are found through
:mod:`importlib.resources`, so they load from an installed package too.

    >>> from housner.scenarios.motions.records import elcentro, load_record
    >>> rec = elcentro()                    # PEER 1999 I-ELC180, 4000 x 0.01 s
    >>> rec = load_record("elcentro-chopra")
    >>> rec = read_record_file("records/kobe.AT2")   # a user's file, by its suffix

Intensity measures (SI): Arias intensity Ia = pi / (2 g) int ug''^2 dt [m/s];
the Husid curve Ia(t) / Ia [-]; significant duration D5-95 [s]; and t_mid, the
time at 45 % of Ia [s]. Times count from the first sample, t = 0. The integral
is the trapezoidal rule on the samples, consistent with the acceleration being
linear between samples to within O(dt^2).
"""

from __future__ import annotations

import hashlib
from collections.abc import Callable
from importlib import resources
from pathlib import Path

import numpy as np

from housner.errors import DataFileError, unknown_choice
from housner.motion import GroundMotion
from housner.units import G

__all__ = [
    "ELCENTRO_VARIANTS",
    "RECORDS",
    "RECORD_SUFFIXES",
    "arias_intensity",
    "elcentro",
    "husid",
    "husid_time",
    "file_sha256",
    "load_record",
    "read_record_file",
    "pmnm_count",
    "significant_duration",
    "t_mid",
    "upcrossing_count",
]

_PEER_CITATION = "PEER Strong Motion Database (1999/2000), Pacific Earthquake Engineering Research Center"
_NGA_CITATION = (
    "PEER NGA-West2 database, RSN 6; Ancheta, T. D. et al. (2014), NGA-West2 database, "
    "Earthquake Spectra 30(3), 989-1005"
)
_CHOPRA_CITATION = "Chopra, A. K., Dynamics of Structures, Appendix 6 (El Centro 1940 N-S, 'Peknold' version)"
_EVENT = "1940 Imperial Valley earthquake (Mw 6.95), El Centro Array #9 (USGS station 117), N-S component (180)"

#: El Centro 1940 N-S variants: name -> (file in scenarios/catalogue/data, citation, processing note).
ELCENTRO_VARIANTS: dict[str, tuple[str, str, str]] = {
    "peer1999": (
        "elcentro_1940_ns_I-ELC180_peer1999.AT2",
        _PEER_CITATION,
        "PEER 1999 processing I-ELC180, band-pass 0.2-15 Hz, 4000 samples at 0.01 s",
    ),
    "ngawest2": (
        "elcentro_1940_ns_RSN6_ngawest2.AT2",
        _NGA_CITATION,
        "NGA-West2 re-processing RSN6 I-ELC180 (hor1), 5372 samples at 0.01 s",
    ),
    "chopra": (
        "elcentro_1940_ns_chopra_dt002.txt",
        _CHOPRA_CITATION,
        "digitisation used in Chopra's textbook, 1559 samples at 0.02 s",
    ),
}


def elcentro(variant: str = "peer1999") -> GroundMotion:
    """The 1940 El Centro N-S record (Imperial Valley, El Centro Array #9, component 180).

    Parameters
    ----------
    variant : {"peer1999", "ngawest2", "chopra"}
        ``"peer1999"`` (default): PEER 1999 file I-ELC180, 4000 points at 0.01 s,
        PGA 0.313 g (3.07 m/s^2). ``"ngawest2"``: the NGA-West2 re-processing
        (RSN 6), 5372 points at 0.01 s, PGA 0.281 g. ``"chopra"``: Chopra's
        textbook version, 1559 points at 0.02 s, PGA 0.319 g.

    Returns
    -------
    GroundMotion
        Acceleration in m/s^2 (converted once from g with g = 9.80665 m/s^2),
        named ``"elcentro-<variant>"``, with the source file and citation in
        ``provenance``.

    References
    ----------
    PEER Strong Motion Database (1999/2000). Ancheta, T. D. et al. (2014).
    NGA-West2 database. Earthquake Spectra 30(3), 989-1005. Chopra, A. K.
    Dynamics of Structures, App. 6.
    """
    try:
        filename, citation, note = ELCENTRO_VARIANTS[variant]
    except (KeyError, TypeError):
        raise unknown_choice("El Centro variant", variant, ELCENTRO_VARIANTS) from None
    resource = resources.files("housner.scenarios.catalogue").joinpath("data", filename)
    with resources.as_file(resource) as path:
        rec = GroundMotion.from_at2(path)
    return GroundMotion(
        acc=rec.acc,
        dt=rec.dt,
        name=f"elcentro-{variant}",
        provenance=f"{_EVENT}; {note}; file {filename}; cite: {citation}; reader: {rec.provenance}",
    )


def _loader(variant: str) -> Callable[[], GroundMotion]:
    def load() -> GroundMotion:
        return elcentro(variant)

    load.__name__ = f"elcentro_{variant}"
    load.__doc__ = f"El Centro 1940 N-S, variant {variant!r} (see :func:`elcentro`)."
    return load


#: Registry of shipped records: name -> loader taking no argument.
RECORDS: dict[str, Callable[[], GroundMotion]] = {"elcentro": _loader("peer1999")}
RECORDS.update({f"elcentro-{v}": _loader(v) for v in ELCENTRO_VARIANTS})


def load_record(name: str) -> GroundMotion:
    """Load a shipped record by its name in :data:`RECORDS`; unknown names list the choices."""
    try:
        loader = RECORDS[name]
    except (KeyError, TypeError):
        raise unknown_choice("record", name, RECORDS) from None
    return loader()


#: Suffixes of the record files :func:`read_record_file` reads (compared in lower case): reader.
RECORD_SUFFIXES: dict[str, str] = {".at2": "PEER AT2", ".csv": "CSV with `time` and `ground_acc` columns"}


def read_record_file(path: str | Path, name: str | None = None, units: str | None = None) -> GroundMotion:
    """Read a user's record file, a PEER AT2 or a CSV, chosen by its suffix.

    Parameters
    ----------
    path : path
        ``*.AT2`` (any case): :meth:`GroundMotion.from_at2`, the unit from the
        header; ``*.csv``: :meth:`GroundMotion.from_csv`, columns ``time`` [s]
        and ``ground_acc`` [m/s^2] unless the header names their units
        (``ground_acc [g]``). Converted once, in the reader, to m/s^2.
    name : str, optional
        Name of the motion (default: the file's stem).
    units : str, optional
        Acceleration unit of a file whose header names none (a scenario's ``[motions] units``);
        a unit the header names must agree with it.

    Returns
    -------
    GroundMotion
        Acceleration [m/s^2]; the provenance names the file and the conversion.

    Raises
    ------
    DataFileError
        The file is missing, unreadable, of another suffix, or malformed; the
        message names the file and, where known, the line.
    """
    path = Path(path)
    kind = RECORD_SUFFIXES.get(path.suffix.lower())
    if kind is None:
        got = f"suffix {path.suffix!r}" if path.suffix else "no suffix"
        raise DataFileError(path, f"{got}: a record file is an .AT2 (PEER) or a .csv (time, ground_acc) file")
    if path.is_dir():
        raise DataFileError(path, "is a directory, not a record file")
    if not path.exists():
        raise DataFileError(path, "no such file")
    if path.suffix.lower() == ".at2":
        return GroundMotion.from_at2(path, name=name, units=units)
    return GroundMotion.from_csv(path, name=name, units=units)


def file_sha256(path: str | Path) -> str:
    """SHA-256 of a file's bytes (hex), to tell later whether a record file has changed."""
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


# ----------------------------------------------------------------------
# Intensity measures
# ----------------------------------------------------------------------
def _acc_dt(motion: GroundMotion) -> tuple[np.ndarray, float]:
    if not isinstance(motion, GroundMotion):
        raise TypeError(f"`motion` must be a housner.GroundMotion, got {type(motion).__name__}")
    return motion.acc, motion.dt


def _cumulative_arias(acc: np.ndarray, dt: float) -> np.ndarray:
    """Ia(t_k) [m/s] by the trapezoidal rule, Ia(0) = 0."""
    sq = acc * acc
    out = np.empty(acc.size)
    out[0] = 0.0
    np.cumsum(0.5 * (sq[1:] + sq[:-1]) * dt, out=out[1:])
    return out * (np.pi / (2.0 * G))


def arias_intensity(motion: GroundMotion) -> float:
    """Arias intensity Ia = pi / (2 g) int ug''(t)^2 dt [m/s].

    References
    ----------
    Arias, A. (1970). A measure of earthquake intensity. In Seismic Design for
    Nuclear Power Plants, MIT Press, 438-483.
    """
    acc, dt = _acc_dt(motion)
    return float(_cumulative_arias(acc, dt)[-1])


def husid(motion: GroundMotion) -> tuple[np.ndarray, np.ndarray]:
    """Husid curve: sample times [s] and the normalised cumulative Arias intensity Ia(t) / Ia [-]."""
    acc, dt = _acc_dt(motion)
    c = _cumulative_arias(acc, dt)
    if c[-1] <= 0.0:
        raise ValueError(f"motion {motion.name!r} has zero Arias intensity; its Husid curve is undefined")
    return motion.t, c / c[-1]


def husid_time(motion: GroundMotion, fraction) -> float | np.ndarray:
    """Time [s] at which the Husid curve first reaches ``fraction`` (in [0, 1]), linear between samples."""
    f = np.asarray(fraction, dtype=float)
    if not np.all((f >= 0.0) & (f <= 1.0)):
        raise ValueError(f"`fraction` must lie in [0, 1], got {fraction!r}")
    t, h = husid(motion)
    # The Husid curve is non-decreasing; interp on it returns the first crossing
    # except on flat stretches, where any time on the stretch is as good.
    out = np.interp(f, h, t)
    return float(out) if out.ndim == 0 else out


def significant_duration(motion: GroundMotion, start: float = 0.05, end: float = 0.95) -> float:
    """Significant duration D_start-end, the time to go from ``start`` to ``end`` of Ia [s]; D5-95 by default."""
    if not (0.0 <= start < end <= 1.0):
        raise ValueError(f"need 0 <= `start` < `end` <= 1, got start={start!r}, end={end!r}")
    t0, t1 = husid_time(motion, [start, end])
    return float(t1 - t0)


def t_mid(motion: GroundMotion) -> float:
    """Time at 45 % of the Arias intensity, the middle of the strong-motion phase [s] (Rezaeian & Der Kiureghian)."""
    return float(husid_time(motion, 0.45))


def upcrossing_count(acc) -> np.ndarray:
    """Cumulative count of zero-level up-crossings at each sample [-], along axis 0.

    A crossing between samples k and k + 1 (acc[k] < 0 <= acc[k + 1]) is counted at k + 1.
    """
    a = np.asarray(acc, dtype=float)
    ind = np.zeros(a.shape)
    ind[1:] = (a[:-1] < 0.0) & (a[1:] >= 0.0)
    return np.cumsum(ind, axis=0)


def pmnm_count(acc) -> np.ndarray:
    """Cumulative count of positive minima and negative maxima at each sample [-], along axis 0.

    Local extrema on the 'wrong' side of zero measure the bandwidth of a process:
    a narrow-band process has almost none, a broad-band one many.
    """
    a = np.asarray(acc, dtype=float)
    ind = np.zeros(a.shape)
    prev, mid, nxt = a[:-2], a[1:-1], a[2:]
    pos_min = (mid > 0.0) & (mid < prev) & (mid <= nxt)
    neg_max = (mid < 0.0) & (mid > prev) & (mid >= nxt)
    ind[1:-1] = pos_min | neg_max
    return np.cumsum(ind, axis=0)
