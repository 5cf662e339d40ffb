"""The chaos floor: how well the analytic model agrees with itself, record by record, when nudged.

Rocking under a long random record is sensitive to small perturbations, so an engine's record-by-record
agreement with the analytic model cannot be judged against 100 %. The chaos floor is the agreement to expect
from chaos alone: the analytic model run on the same motions with its r and p perturbed, each in both
directions, by the engine's errors measured on free rocking (:func:`measure_engine_errors`, releases at
:data:`RELEASE_AMPLITUDES`), and compared with itself by the same rule
(:func:`housner.statistics.ensemble_stats.per_record_agreement`, :data:`RECORD_RTOL`). Why, how the errors are measured
and what
reaching the floor means are in ``docs/explanation/verdict.md`` ("Record by record, against the chaos floor").
"""

from __future__ import annotations

import json
import math
import threading
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from housner._values import JsonValue
from housner.engines.base import RECORD_ERRORS, Engine, get_engine
from housner.engines.measures import first_impact_ratio, free_rocking_quarter_period
from housner.motion import GroundMotion
from housner.scenarios.execution.cache import code_version, content_key, store_text
from housner.specimen import Specimen
from housner.statistics.ensemble_stats import per_record_agreement
from housner.statistics.proportions import wilson_interval

#: Record-by-record agreement: both overturned, or both rocked with theta_max/alpha within this relative
#: tolerance of the reference's [-] (the run report's rule, and housner explain's).
RECORD_RTOL = 0.03

__all__ = [
    "RELEASE_AMPLITUDES",
    "AgreementShares",
    "ChaosFloor",
    "EngineErrors",
    "RECORD_RTOL",
    "chaos_floor",
    "errors_from_dict",
    "floor_check",
    "floor_verdict",
    "measure_engine_errors",
    "rms",
    "run_engine_errors",
    "run_engine_errors_meanwhile",
]

#: Release amplitudes theta0 / alpha [-] of the free-rocking measurement: the range where the
#: tuner checks r (0.2-0.9 alpha), five points so that a step-phase scatter averages out.
RELEASE_AMPLITUDES = (0.2, 0.35, 0.5, 0.65, 0.8)


@dataclass(frozen=True, eq=False)
class EngineErrors(JsonValue):
    """An engine's measured free-rocking errors against the analytic model (run.json's ``engine_errors``).

    Attributes
    ----------
    engine : str
    amplitudes : tuple of float
        Release amplitudes theta0 / alpha [-].
    r_rel_errors : tuple of float
        r_engine / r_reference - 1 at each amplitude [-] (NaN where not measurable).
    p_rel_errors : tuple of float
        p_engine / p - 1 at each amplitude [-], from the time to the first impact.
    dt : float
        Sample step of the measurement [s] (the ensemble's).
    r_reference : float or None
        The r the engine was measured against [-] (None: not stated).
    error : str or None
        Why the measurement failed (then there are no errors), None when it did not.
    """

    engine: str = ""
    amplitudes: tuple[float, ...] = ()
    r_rel_errors: tuple[float, ...] = ()
    p_rel_errors: tuple[float, ...] = ()
    dt: float = math.nan
    r_reference: float | None = None
    error: str | None = None

    @property
    def eps_r(self) -> float:
        """Root mean square of the r errors [-]: the size of the engine's error per impact."""
        return rms(self.r_rel_errors)

    @property
    def eps_p(self) -> float:
        """Root mean square of the p errors [-]."""
        return rms(self.p_rel_errors)

    def to_json(self) -> dict:
        """run.json's entry: the errors with their RMS and the reference r, or ``{"error": why}``."""
        if self.error is not None:
            return {"error": self.error}
        return {
            "engine": self.engine,
            "amplitudes": list(self.amplitudes),
            "r_rel_errors": list(self.r_rel_errors),
            "p_rel_errors": list(self.p_rel_errors),
            "dt": self.dt,
            "eps_r": self.eps_r,
            "eps_p": self.eps_p,
            **({} if self.r_reference is None else {"r_reference": self.r_reference}),
        }

    @classmethod
    def from_json(cls, data: Any) -> EngineErrors:
        """The errors of run.json's entry (``eps_r`` and ``eps_p`` follow from the errors; read, not kept)."""
        if isinstance(data, EngineErrors):
            return data
        data = data if isinstance(data, dict) else {}
        if "error" in data:
            return cls(engine=str(data.get("engine", "")), error=str(data["error"]))
        return super().from_json({k: v for k, v in data.items() if k not in ("eps_r", "eps_p")})


def rms(x) -> float:
    """Root mean square of the finite values of ``x`` [same unit]; NaN when none is finite."""
    v = np.asarray(x, dtype=float)
    v = v[np.isfinite(v)]
    return float(np.sqrt(np.mean(v**2))) if v.size else math.nan


def measure_engine_errors(
    engine: Engine,
    specimen: Specimen,
    *,
    r_reference: float | None = None,
    dt: float = 1e-3,
    amplitudes: Sequence[float] = RELEASE_AMPLITUDES,
) -> EngineErrors:
    """Measure an engine's r and p errors on free rocking.

    Parameters
    ----------
    engine : Engine
        The engine, with the settings it runs the ensemble with.
    specimen : Specimen
    r_reference : float, optional
        The r the engine should reproduce [-] (default: Housner's, ``specimen.r_housner``).
    dt : float
        Sample step [s] of the releases (use the ensemble's: the engines cut it into their steps).
    amplitudes : sequence of float
        Release amplitudes theta0 / alpha [-], each in (0, 1).

    Returns
    -------
    EngineErrors
    """
    r_ref = specimen.r_housner if r_reference is None else float(r_reference)
    reference = get_engine("housner", r=r_ref)
    r_err, p_err = [], []
    for a in amplitudes:
        th0 = float(a) * specimen.alpha
        quarter = free_rocking_quarter_period(specimen, th0)
        # two quarter periods of this amplitude and the next half-cycle's rise, plus margin
        duration = 5.0 * quarter + 0.05
        release = GroundMotion.free_vibration(th0, duration, dt=dt, name=f"release {a:g}")
        res = engine.simulate(specimen, release)
        # against the analytic model measured the same way: the peaks read from samples carry an error
        # of their own at small amplitudes (1.5 % at 0.01 alpha with 1 ms samples), the same for both
        r_meas = first_impact_ratio(reference.simulate(specimen, release), specimen.alpha)
        r_err.append(first_impact_ratio(res, specimen.alpha) / r_meas - 1.0)
        t1 = res.impact_times[0] if len(res.impact_times) else math.nan
        p_err.append(quarter / t1 - 1.0 if t1 > 0 else math.nan)
    return EngineErrors(engine.name, tuple(float(a) for a in amplitudes), tuple(r_err), tuple(p_err), float(dt))


def run_engine_errors(
    specimen: Specimen,
    engines: dict[str, dict],
    motions: Sequence[GroundMotion],
    reference: str = "housner",
    *,
    cache_dir: str | Path | None = None,
) -> dict[str, EngineErrors]:
    """Every engine's measured free-rocking errors for a run (run.json's ``engine_errors``).

    Parameters
    ----------
    specimen : Specimen
    engines : dict
        Engine name -> its settings, as the run used them. Only when the
        reference is the analytic model (``"housner"``) is there a floor to
        compute: otherwise the result is empty.
    motions : sequence of GroundMotion
        The ensemble; its median sample step is the measurement's.
    reference : str
        The run's reference engine.
    cache_dir : str or Path, optional
        The result cache's folder: an engine's errors measured before with the same specimen,
        settings, engine version, code, reference r and step are read back from
        ``cache_dir/engine-errors/`` (and new ones written there) instead of measured again.
        None: always measured.

    Returns
    -------
    dict
        Engine name -> its :class:`EngineErrors` with ``r_reference``, or one with only ``error`` (the message)
        for an engine that failed the measurement.
    """
    if reference != "housner" or reference not in engines or not motions:
        return {}
    r_ref = engines[reference].get("r") or specimen.r_housner
    dt = float(np.median([m.dt for m in motions]))
    out: dict[str, EngineErrors] = {}
    for name, settings in engines.items():
        if name == reference:
            continue
        try:
            engine = get_engine(name, **settings)
            path = None if cache_dir is None else _errors_path(cache_dir, specimen, engine, float(r_ref), dt)
            if path is not None and (cached := _read_errors(path)) is not None:
                out[name] = cached
                continue
            err = measure_engine_errors(engine, specimen, r_reference=r_ref, dt=dt)
        except RECORD_ERRORS as e:
            out[name] = EngineErrors(engine=name, error=f"{type(e).__name__}: {e}")
            continue
        # through its JSON (lists of floats), the same whether measured now or read back from the cache
        text = json.dumps(replace(err, r_reference=float(r_ref)).to_json(), default=float, allow_nan=True)
        out[name] = EngineErrors.from_json(json.loads(text))
        if path is not None:
            store_text(path, text)
    return out


def run_engine_errors_meanwhile(*args, **kwargs) -> Callable[[], dict[str, EngineErrors]]:
    """:func:`run_engine_errors` started in a thread of this process; call the result to wait for it.

    ``housner run`` measures the engines' errors while its worker processes run the records: the
    calling process only waits on them then, so the measurement (about 6 s of CPU for five engines)
    takes the time the pool leaves over instead of adding to the run. An exception of the
    measurement is raised by the call that waits.
    """
    box: dict[str, Any] = {}

    def work() -> None:
        try:
            box["value"] = run_engine_errors(*args, **kwargs)
        except BaseException as e:  # handed to the caller, who raises it where it waits
            box["error"] = e

    thread = threading.Thread(target=work, name="housner-engine-errors", daemon=True)
    thread.start()

    def wait() -> dict[str, EngineErrors]:
        thread.join()
        if "error" in box:
            raise box["error"]
        return box["value"]

    return wait


def _errors_path(cache_dir: str | Path, specimen: Specimen, engine: Engine, r_ref: float, dt: float) -> Path:
    """The cache file of an engine's free-rocking errors: a hash of everything that determines them."""
    content = {
        "what": "engine errors",
        "specimen": specimen.describe(),
        "engine": engine.name,
        "settings": engine.settings(),
        "engine_version": engine.version(),
        "code": code_version(),
        "r_reference": r_ref,
        "dt": dt,
        "amplitudes": list(RELEASE_AMPLITUDES),
    }
    return Path(cache_dir) / "engine-errors" / f"{content_key(content)[:32]}.json"


def _read_errors(path: Path) -> EngineErrors | None:
    """A cached measurement, or None when there is none or it cannot be read (then it is measured again)."""
    try:
        d = json.loads(path.read_text())
    except (OSError, ValueError):
        return None
    keys = ("engine", "amplitudes", "r_rel_errors", "p_rel_errors", "dt", "eps_r", "eps_p", "r_reference")
    return EngineErrors.from_json(d) if isinstance(d, dict) and all(k in d for k in keys) else None


def errors_from_dict(d: dict) -> EngineErrors:
    """The :class:`EngineErrors` of run.json's entry (:meth:`EngineErrors.from_json`)."""
    return EngineErrors.from_json(d)


@dataclass(frozen=True, eq=False)
class AgreementShares(JsonValue):
    """Self-agreement of the analytic model under perturbations: the share of records that still agree.

    Attributes
    ----------
    shares : dict
        Per perturbation: the share of records on which the perturbed analytic model agrees with the
        unperturbed one [-].
    verdict_shares : dict
        The same for the overturn verdict alone [-].
    share : float
        The floor: the mean of ``shares`` [-].
    share_min, share_max : float
        The lowest and highest of ``shares`` [-].
    n : int
        Records compared.
    """

    shares: dict
    verdict_shares: dict
    share: float
    share_min: float
    share_max: float
    n: int

    @staticmethod
    def summarised(shares: dict, verdict_shares: dict, n: int) -> dict:
        """The fields of the class from the per-perturbation shares (no perturbation: agreement 1)."""
        vals = list(shares.values()) or [1.0]
        return {
            "shares": shares,
            "verdict_shares": verdict_shares,
            "share": float(np.mean(vals)),
            "share_min": float(min(vals)),
            "share_max": float(max(vals)),
            "n": int(n),
        }

    def to_dict(self) -> dict:
        """The fields as JSON data (:meth:`to_json`)."""
        return self.to_json()


@dataclass(frozen=True, eq=False)
class ChaosFloor(AgreementShares):
    """:class:`AgreementShares` under an engine's measured errors: r and p perturbed ("r+", "r-", "p+", "p-")."""

    #: The engine whose errors set the perturbation.
    engine: str = ""
    #: The relative perturbation of r [-] (the engine's RMS error of r).
    eps_r: float = 0.0
    #: The relative perturbation of p [-] (the engine's RMS error of p).
    eps_p: float = 0.0


def chaos_floor(
    specimen: Specimen,
    motions: Sequence[GroundMotion],
    errors: EngineErrors,
    *,
    r: float | None = None,
    rtol: float = 0.1,
    atol: float = 0.05,
) -> ChaosFloor:
    """The analytic model's record-by-record agreement with itself under an engine's errors.

    Parameters
    ----------
    specimen : Specimen
    motions : sequence of GroundMotion
        The ensemble (the same motions the engines ran).
    errors : EngineErrors
        The engine's measured errors (:func:`measure_engine_errors`).
    r : float, optional
        The analytic model's r [-] (default: Housner's).
    rtol, atol : float
        Agreement tolerances of :func:`housner.statistics.ensemble_stats.per_record_agreement`
        (use the same as for the engine's own agreement).

    Returns
    -------
    ChaosFloor
    """
    r0 = specimen.r_housner if r is None else float(r)

    def theta(spec: Specimen, rr: float) -> np.ndarray:
        out = get_engine("housner", r=rr).simulate_many(spec, motions)
        return np.array([resp.theta_max_over_alpha for resp in out], dtype=float)

    base = theta(specimen, r0)
    shares, verdicts = {}, {}
    for label, eps in (("r", errors.eps_r), ("p", errors.eps_p)):
        if not (math.isfinite(eps) and eps > 0):
            continue
        for sign, tag in ((1.0, "+"), (-1.0, "-")):
            if label == "r":
                rr = min(r0 * (1.0 + sign * eps), 1.0)
                got = theta(specimen, rr)
            else:
                got = theta(specimen.with_p(specimen.p * (1.0 + sign * eps)), r0)
            ag = per_record_agreement(got, base, rtol=rtol, atol=atol)
            shares[label + tag] = ag.share
            verdicts[label + tag] = ag.verdict_share
    return ChaosFloor(
        engine=errors.engine,
        eps_r=errors.eps_r,
        eps_p=errors.eps_p,
        **AgreementShares.summarised(shares, verdicts, base.size),
    )


def floor_check(n_agree: int, n: int, floor: ChaosFloor, *, ci: float = 0.95) -> tuple[float, float, bool]:
    """The Wilson interval of an engine's record-by-record agreement share [-], and whether it lies below the
    chaos floor: its upper end under the lowest perturbed share (``n`` > 0)."""
    low, high = (float(x) for x in wilson_interval(n_agree, n, ci))
    return low, high, high < floor.share_min


def floor_verdict(n_agree: int, n: int, floor: ChaosFloor, *, ci: float = 0.95) -> str:
    """One sentence: is an engine's record-by-record agreement at the chaos floor or below it?

    The engine's share gets a Wilson interval; it is "at the chaos floor" when
    that interval reaches the floor, the lowest perturbed share (``floor.share_min``),
    "below the chaos floor" otherwise (a difference its measured r and p errors do not explain).

    Parameters
    ----------
    n_agree, n : int
        Records on which the engine agrees with the analytic model, and records compared.
    floor : ChaosFloor
    ci : float
        Confidence level of the interval [-].
    """
    if n <= 0:
        return "no paired records"
    low, high, below = floor_check(n_agree, n, floor, ci=ci)
    head = (
        f"{n_agree / n:.0%} [{low:.0%}, {high:.0%}] of records agree against a chaos floor of {floor.share_min:.0%} "
        f"(the analytic model against itself with r off by {floor.eps_r:.2%} and p by {floor.eps_p:.2%}, this "
        f"engine's measured errors: {floor.share_min:.0%}-{floor.share_max:.0%} of records over the four runs)"
    )
    if not below:
        return head + ": at the floor, record-by-record differences no larger than its measured r and p errors give"
    return head + ": below the floor, a difference beyond its measured r and p errors"
