"""The residual test: the held-out errors against the correct-model floor, record by record.

The real held-out errors are tested against the floor
(:func:`housner.scenarios.diagnosis.verdict.correct_model_floor.measure_floor`) record by record
(:func:`residual_test`), separately for ground motions (paired differences,
their mean over its standard error, and the same on 10 %-trimmed means,
Yuen's test: chaos makes them heavy-tailed and independent from record to
record) and free vibrations (not chaotic; each
record's difference over the replicas' spread, combined by Stouffer's sum).
A misfit is *significant* when z > :data:`Z_MISFIT` and its size *matters*
when the error is more than :data:`RATIO_MISFIT` times the floor.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import asdict, dataclass

import numpy as np

from housner._values import read_fields
from housner.scenarios.diagnosis.verdict.correct_model_floor import Floor

__all__ = ["DETECTABLE_RATIO", "RATIO_MISFIT", "Z_MISFIT", "GroupResidual", "Residual", "residual_test"]

#: One-sided z above which the error is significantly above the floor (p ~ 1.3e-3) [-].
Z_MISFIT = 3.0
#: Error / floor ratio above which a significant misfit is called a misfit [-]. The floor is an
#: estimate (a Gaussian perturbation model of the parameters' uncertainty, 5-8 replicas): a
#: residual within a quarter of it is not distinguished from the floor's own approximation.
RATIO_MISFIT = 1.25
#: The misfit the verdict promises to see: a model that leaves twice the error of a correct one.
#: With less power than that the verdict is "inconclusive" instead of "no misfit" / "explained"
#: [error / floor].
DETECTABLE_RATIO = 2.0
#: One-sided z of 80 % power [-].
Z_POWER = 0.8416
#: Share of the ground motions' paired differences trimmed off each end in the robust test [-]: chaos
#: carries a record or two of 60 far off a correct model's floor (measured: one record at 0.66 alpha
#: against a floor of 0.38 +- 0.35 while the other 59 sit at it, median ratio 1.00).
TRIM = 0.1
#: Relative spread of one free-vibration record's error below which the replicas' spread is not
#: trusted (an RMS over ~1000-5000 noisy samples scatters by ~1-2 %) [-].
FV_MIN_REL_SD = 0.02


@dataclass(frozen=True)
class GroupResidual:
    """One group of records (ground motions, or free vibrations) against its floor.

    Attributes
    ----------
    n : int
        Records in the group.
    error, floor : float
        Mean held-out error and mean floor of the group [alpha].
    ratio, z : float
        Error over floor [-] and the one-sided z of the paired differences [-].
    misfit : bool
        Significant (z > Z_MISFIT) and larger than RATIO_MISFIT x the floor, on the mean or on the trimmed mean.
    ratio_trimmed, z_trimmed : float
        The same on the 10 %-trimmed means (ground motions; the plain ones for free vibrations) [-].
    detectable_ratio : float
        The error / floor ratio the group detects with 80 % power (never below RATIO_MISFIT) [-].
    """

    n: int
    error: float
    floor: float
    ratio: float
    z: float
    misfit: bool
    ratio_trimmed: float
    z_trimmed: float
    detectable_ratio: float

    @property
    def robust_ratio(self) -> float:
        """The ratio the verdict reads: the larger of the plain and the trimmed one [-]."""
        return max(self.ratio, self.ratio_trimmed)


@dataclass(frozen=True)
class Residual:
    """Held-out error against the correct-model floor.

    Attributes
    ----------
    error, floor : float
        Mean held-out error and mean floor over the records [alpha].
    ratio : float
        The residual ratio [-]: error over floor of the typical record of the worse group, the ground
        motions' 10 %-trimmed (chaos carries a record or two of a correct model far off, whose mean
        ratio is then a count of such records more than a measure), the free vibrations' plain.
    z : float
        The larger of the two groups' one-sided z (ground motion, free vibration) [-].
    misfit : bool
        Significant (z > Z_MISFIT) and larger than RATIO_MISFIT x the floor in at least one group.
    groups : dict of str to GroupResidual
        ``ground_motion`` / ``free_vibration`` -> its residual.
    detectable_ratio : float
        The error / floor ratio this campaign detects with 80 % power in its most telling group
        (never below RATIO_MISFIT) [-].
    records_needed : int
        Ground-motion records needed to detect DETECTABLE_RATIO in them alone (0 when already enough).
    """

    error: float
    floor: float
    ratio: float
    z: float
    misfit: bool
    groups: dict[str, GroupResidual]
    detectable_ratio: float
    records_needed: int

    def to_dict(self) -> dict:
        """The fields as plain data, each group's residual as its fields."""
        return asdict(self)

    @classmethod
    def from_dict(cls, data: dict) -> Residual:
        return read_fields(cls, data)


def _trimmed(x: np.ndarray) -> tuple[float, float, float]:
    """Trimmed mean of ``x`` (:data:`TRIM` off each end), its standard error and the winsorised sd (Yuen 1974)."""
    x = np.sort(np.asarray(x, dtype=float))
    n = x.size
    g = int(math.floor(TRIM * n))
    if n < 2:
        return (float(x.mean()) if n else math.nan), math.inf, math.inf
    tm = float(x[g : n - g].mean())
    w = np.clip(x, x[g], x[n - 1 - g])
    sw = float(w.std(ddof=1))
    return tm, sw / ((1 - 2 * g / n) * math.sqrt(n)), sw


def residual_test(errors: np.ndarray, floor: Floor, kinds: Sequence[str]) -> Residual:
    """Test held-out errors (per record, campaign order) against the floor (module docstring)."""
    e = np.asarray(errors, dtype=float)
    f = floor.mean
    kinds = np.asarray(kinds)
    groups = {}
    z_all, misfit = -math.inf, False
    det, need = math.inf, 0
    zz = Z_MISFIT + Z_POWER
    for kind in ("ground_motion", "free_vibration"):
        m = (kinds == kind) & np.isfinite(e)
        n = int(m.sum())
        if n == 0:
            continue
        d = e[m] - f[m]
        fm = float(f[m].mean())
        ratio = float(e[m].mean() / fm) if fm > 0 else math.inf
        if kind == "ground_motion":
            # records are independent draws of chaos: the paired differences' own spread. One record the
            # chaos carries off (near an overturn: a correct model's error anywhere in 0-1) dominates the
            # mean and its standard error, so the test and the power are also taken on trimmed means
            # (Yuen 1974): a misfit of either kind counts, the power is the trimmed test's.
            sd_d = float(d.std(ddof=1)) if n > 1 else math.inf
            se = sd_d / math.sqrt(n)
            z = float(d.mean() / se) if se > 0 else (math.inf if d.mean() > 0 else 0.0)
            dt_, se_t, sw = _trimmed(d)
            ft = _trimmed(f[m])[0]
            z_t = float(dt_ / se_t) if se_t > 0 else (math.inf if dt_ > 0 else 0.0)
            ratio_t = 1.0 + dt_ / ft if ft > 0 else math.inf
            mis_t = bool(z_t > Z_MISFIT and ratio_t > RATIO_MISFIT)
            det_k = 1.0 + zz * se_t / ft if ft > 0 else math.inf
            want = (DETECTABLE_RATIO - 1.0) * ft
            if want > 0 and math.isfinite(sw):
                need = max(int(math.ceil((zz * sw / (1 - 2 * TRIM) / want) ** 2)) - n, 0)
        else:
            # not chaotic: each record against the replicas' spread of its own error (Stouffer)
            s = np.maximum(floor.sd[m], FV_MIN_REL_SD * f[m])
            z = float(np.sum(d / s) / math.sqrt(n))
            det_k = 1.0 + zz * float(np.mean(s)) / math.sqrt(n) / fm if fm > 0 else math.inf
            z_t, ratio_t, mis_t = z, ratio, False
        mis = bool(z > Z_MISFIT and ratio > RATIO_MISFIT) or mis_t
        groups[kind] = GroupResidual(
            n=n,
            error=float(e[m].mean()),
            floor=fm,
            ratio=ratio,
            z=z,
            misfit=mis,
            ratio_trimmed=ratio_t,
            z_trimmed=z_t,
            detectable_ratio=max(det_k, RATIO_MISFIT),
        )
        z_all = max(z_all, z, z_t)
        misfit = misfit or mis
        det = min(det, max(det_k, RATIO_MISFIT))
    ok = np.isfinite(e)
    err, flo = float(e[ok].mean()), float(f[ok].mean())
    robust = [g.ratio_trimmed if k == "ground_motion" else g.ratio for k, g in groups.items()]
    ratio = max(robust) if robust else (err / flo if flo > 0 else math.inf)
    return Residual(err, flo, ratio, z_all, misfit, groups, det, need)
