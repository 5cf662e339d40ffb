"""The spectral band check: an ensemble's mean response spectrum against a record's, per third-octave band.

Periods are grouped in third-octave bands (centres 2^(k/3) s); in each band
the ratio of the ensemble's arithmetic mean 5 %-damped spectrum to the
record's is averaged geometrically over a few log-spaced periods, given with a
95 % sampling interval from the motions' scatter, and accepted within
:data:`BAND_BOUNDS`. The check is the acceptance test of the matched ground-
motion model (:mod:`housner.scenarios.motions.rdk_match`) and is shown on every report of an
RDK scenario, for whatever record and model it names.

Periods in s, spectra in m/s^2 (PSa) and m (Sd).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from housner.motion import GroundMotion
from housner.scenarios.motions.elastic import ensemble_spectra, response_spectrum

__all__ = [
    "BAND_BOUNDS",
    "CHECK_PER_BAND",
    "DEFAULT_PSA_RANGE",
    "DEFAULT_SD_RANGE",
    "BandCheck",
    "BandTable",
    "band_centres",
    "band_check",
    "band_periods",
]

#: Accepted range of a band's ratio ensemble-mean / record [-] (+25 % / -20 %, symmetric in log).
BAND_BOUNDS = (0.8, 1.25)

#: Period range of the PSa band check [s].
DEFAULT_PSA_RANGE = (0.05, 3.0)

#: Period range of the Sd band check [s].
DEFAULT_SD_RANGE = (0.5, 3.0)

#: Periods per band of the acceptance check [-].
CHECK_PER_BAND = 5


def check_range(value, name: str) -> tuple[float, float]:
    try:
        lo, hi = (float(v) for v in value)
    except (TypeError, ValueError):
        raise ValueError(f"`{name}` must be a pair (T_min, T_max) of periods [s], got {value!r}") from None
    if not (math.isfinite(lo) and math.isfinite(hi) and 0.0 < lo < hi):
        raise ValueError(f"`{name}` must satisfy 0 < T_min < T_max (finite) [s], got {value!r}")
    return lo, hi


def band_centres(t_min: float, t_max: float) -> np.ndarray:
    """Centres T_k = 2^(k/3) [s] of every third-octave period band that overlaps [t_min, t_max].

    Band k spans T_k 2^(-1/6) .. T_k 2^(1/6), so the bands tile the period axis
    and every period in [t_min, t_max] lies in one of them (the first and last
    band may reach up to a sixth of an octave beyond the range). For 0.05-3 s:
    19 bands, centres 0.0496 .. 3.17 s, spanning 0.0442 .. 3.56 s.
    """
    lo, hi = check_range((t_min, t_max), "period range")
    k0 = math.ceil(3.0 * math.log2(lo) - 0.5 - 1e-9)
    k1 = math.floor(3.0 * math.log2(hi) + 0.5 + 1e-9)
    return 2.0 ** (np.arange(k0, k1 + 1) / 3.0)


def band_periods(centres, per_band: int) -> np.ndarray:
    """``per_band`` periods per band [s], at the middles of equal log-width slices of each band.

    Returns an array of shape (len(centres) * per_band,), band by band.
    """
    if isinstance(per_band, (bool, np.bool_)) or not isinstance(per_band, (int, np.integer)) or per_band < 1:
        raise ValueError(f"`per_band` must be a positive int, got {per_band!r}")
    offsets = 2.0 ** (((np.arange(per_band) + 0.5) / per_band - 0.5) / 3.0)
    return (np.asarray(centres, dtype=float)[:, None] * offsets[None, :]).ravel()


@dataclass(frozen=True)
class BandTable:
    """Per-band ratio of an ensemble's mean spectrum to a record's, with its verdict.

    Parameters
    ----------
    quantity : str
        ``"PSa"`` or ``"Sd"``.
    centre, lo, hi : tuple of float
        Band centre and edges [s].
    ratio : tuple of float
        Geometric mean over the band's periods of (ensemble mean / record) [-].
    ci95 : tuple of (float, float)
        Approximate 95 % sampling interval of each ratio [-]: exp(log ratio +- 1.96 se),
        se the standard error of log(ensemble mean) from the motions' scatter
        (delta method), averaged over the band's periods. It measures the
        doubt from the finite ensemble only, not from the record.
    bounds : (float, float)
        Accepted range of a ratio [-].
    n_motions : int
        Size of the ensemble.
    """

    quantity: str
    centre: tuple
    lo: tuple
    hi: tuple
    ratio: tuple
    ci95: tuple
    bounds: tuple = BAND_BOUNDS
    n_motions: int = 0

    @property
    def band_passed(self) -> tuple:
        """PASS (True) or FAIL per band."""
        return tuple(bool(self.bounds[0] <= r <= self.bounds[1]) for r in self.ratio)

    @property
    def passed(self) -> bool:
        """True if every band passes."""
        return all(self.band_passed)

    @property
    def worst(self) -> float:
        """The ratio farthest from 1 in log [-]."""
        return max(self.ratio, key=lambda r: abs(math.log(r)))

    def rows(self) -> list[dict]:
        """One plain dict per band (units in the keys), for reports."""
        return [
            {
                "quantity": self.quantity,
                "centre_s": c,
                "lo_s": lo,
                "hi_s": hi,
                "ratio": r,
                "ci95_lo": ci[0],
                "ci95_hi": ci[1],
                "lower_bound": self.bounds[0],
                "upper_bound": self.bounds[1],
                "verdict": "PASS" if ok else "FAIL",
            }
            for c, lo, hi, r, ci, ok in zip(
                self.centre, self.lo, self.hi, self.ratio, self.ci95, self.band_passed, strict=True
            )
        ]

    def __str__(self) -> str:
        head = (
            f"{self.quantity}: ensemble mean / record per third-octave band ({self.n_motions} motions), "
            f"accepted [{self.bounds[0]:g}, {self.bounds[1]:g}]"
        )
        lines = [head, f"{'centre [s]':>10} {'band [s]':>15} {'ratio':>6} {'95 % interval':>15}  verdict"]
        for row in self.rows():
            lines.append(
                f"{row['centre_s']:10.3f} {row['lo_s']:7.3f}-{row['hi_s']:<7.3f} {row['ratio']:6.3f} "
                f"{row['ci95_lo']:7.3f}-{row['ci95_hi']:<7.3f}  {row['verdict']}"
            )
        n_ok = sum(self.band_passed)
        lines.append(
            f"{n_ok}/{len(self.ratio)} bands pass; worst {self.worst:.3f}: {'PASS' if self.passed else 'FAIL'}"
        )
        return "\n".join(lines)


@dataclass(frozen=True)
class BandCheck:
    """The PSa and Sd band tables of one ensemble against one record."""

    psa: BandTable
    sd: BandTable
    record: str = ""
    damping: float = 0.05

    @property
    def passed(self) -> bool:
        """True if every PSa and every Sd band passes."""
        return self.psa.passed and self.sd.passed

    def rows(self) -> list[dict]:
        """The rows of both tables, PSa first."""
        return self.psa.rows() + self.sd.rows()

    def __str__(self) -> str:
        return (
            f"record {self.record!r}, {100 * self.damping:g} % damping\n{self.psa}\n{self.sd}\n"
            f"overall: {'PASS' if self.passed else 'FAIL'}"
        )


def band_table(
    quantity: str, centres: np.ndarray, per_band: int, ens: np.ndarray, rec: np.ndarray, bounds
) -> BandTable:
    """Band table from spectra ``ens`` (motions x periods) and ``rec`` (periods) at band_periods(centres, per_band)."""
    mean = ens.mean(axis=0)
    log_ratio = np.log(mean / rec).reshape(centres.size, per_band).mean(axis=1)
    n = ens.shape[0]
    # delta method: d log(mean) = (s_i - mean) / (n mean) per motion; averaged over the band's periods
    z = (ens / mean - 1.0).reshape(n, centres.size, per_band).mean(axis=2)
    se = z.std(axis=0, ddof=1) / math.sqrt(n) if n > 1 else np.full(centres.size, np.nan)
    ratio = np.exp(log_ratio)
    half = 2.0 ** (1.0 / 6.0)
    return BandTable(
        quantity=quantity,
        centre=tuple(float(c) for c in centres),
        lo=tuple(float(c / half) for c in centres),
        hi=tuple(float(c * half) for c in centres),
        ratio=tuple(float(r) for r in ratio),
        ci95=tuple(
            (float(r * math.exp(-1.96 * s)), float(r * math.exp(1.96 * s))) for r, s in zip(ratio, se, strict=True)
        ),
        bounds=tuple(float(b) for b in bounds),
        n_motions=n,
    )


def check_bounds(bounds, name: str) -> tuple[float, float]:
    try:
        lo, hi = (float(b) for b in bounds)
    except (TypeError, ValueError):
        raise ValueError(f"`{name}` must be a pair (lower, upper) of ratios, got {bounds!r}") from None
    if not (math.isfinite(lo) and math.isfinite(hi) and 0.0 < lo < hi):
        raise ValueError(f"`{name}` must satisfy 0 < lower < upper (finite), got {bounds!r}")
    return lo, hi


def band_check(
    motions: Sequence[GroundMotion],
    record: GroundMotion,
    *,
    psa_range=DEFAULT_PSA_RANGE,
    sd_range=DEFAULT_SD_RANGE,
    damping: float = 0.05,
    per_band: int = CHECK_PER_BAND,
    bounds=BAND_BOUNDS,
) -> BandCheck:
    """Compare an ensemble's mean response spectrum with a record's, band by band.

    Parameters
    ----------
    motions : sequence of GroundMotion
        The ensemble [m/s^2]; any number of motions, any steps and lengths.
    record : GroundMotion
        The target record [m/s^2].
    psa_range, sd_range : (float, float)
        Period ranges [s] of the PSa and Sd checks: every third-octave band
        (centres 2^(k/3) s, see :func:`band_centres`) overlapping the range is checked.
    damping : float
        Damping ratio of the spectra [-].
    per_band : int
        Periods per band, evenly spread in log T (see :func:`band_periods`).
    bounds : (float, float)
        Accepted range of each band's ratio [-].

    Returns
    -------
    BandCheck
        ``.psa`` and ``.sd`` tables (centre, edges, ratio, 95 % sampling
        interval, PASS/FAIL) and ``.passed``; ``str()`` prints both.

    Notes
    -----
    A band's ratio is the geometric mean over its periods of
    (arithmetic ensemble mean / record). Sd = PSa / omega^2 for every motion
    and for the record, so a band's Sd ratio equals its PSa ratio wherever
    both are checked; it is computed from the Sd spectra all the same.
    """
    motions = list(motions)
    if not motions:
        raise ValueError("`motions` is empty")
    if not isinstance(record, GroundMotion):
        raise TypeError(f"`record` must be a housner.GroundMotion, got {type(record).__name__}")
    bounds = check_bounds(bounds, "bounds")
    c_psa = band_centres(*check_range(psa_range, "psa_range"))
    c_sd = band_centres(*check_range(sd_range, "sd_range"))
    c_all = np.unique(np.concatenate([c_psa, c_sd]))
    periods = band_periods(c_all, per_band)
    psa, sd = ensemble_spectra(motions, periods, damping)
    rec_psa, rec_sd = response_spectrum(record, periods, damping)

    def pick(centres: np.ndarray) -> np.ndarray:
        rows = np.searchsorted(c_all, centres)
        return (rows[:, None] * per_band + np.arange(per_band)[None, :]).ravel()

    i_psa, i_sd = pick(c_psa), pick(c_sd)
    return BandCheck(
        psa=band_table("PSa", c_psa, per_band, psa[:, i_psa], rec_psa[i_psa], bounds),
        sd=band_table("Sd", c_sd, per_band, sd[:, i_sd], rec_sd[i_sd], bounds),
        record=record.name,
        damping=float(damping),
    )
