"""Contact tuning: find engine settings that reproduce a target energy ratio r at impact.

An engine's contact model decides how much kinetic energy the block keeps at
each impact. The tuner releases the block from rest at theta0 = a alpha for a
set of amplitudes a, measures the first impact's energy ratio with the seed's
eq. 8 from the peaks before and after it,

    c = (cos(alpha - |theta_1|) - cos alpha) / (cos(alpha - |theta_0|) - cos alpha),

and compares it with the target (Housner's r by default). It tries the
engine's candidate settings (its classmethod
``tuning_candidates(specimen, target_r)``, ordered cheap to expensive), and
picks the cheapest candidate whose ratio is within ``rtol`` (0.5 %) of the
target at every amplitude, or else the one with the smallest worst error, and
says which.

The energy ratio alone does not pin a contact down: a soft frictional contact
can match r and still rock too far under a pulse (MuJoCo's pyramidal cone with
a large mu^2 / impratio rocks 1.7 % too far on the pulses below while its r is
within 0.4 %). So by default a candidate must also reproduce, within ``rtol``,
the analytic model's first peak (before any impact) under two one-sine pulses,
ug'' = a_p sin(omega_p t) for one period, with (omega_p / p, a_p / (g tan alpha))
= (8, 5) and (6, 3): first peaks of about 0.29 and 0.21 alpha for the seed
specimen, no impact involved.

Run it from the shell with ``python -m engines.tuning ENGINE [--target-r R]``.

References
----------
Housner, G. W. (1963). The behavior of inverted pendulum structures during
earthquakes. BSSA 53(2), 403-417.
Bachmann, J. A. et al. (2017). Probabilistic validation of the Housner rocking
model. COMPDYN 2017, eqs. 7-8 and Table 1.
"""

from __future__ import annotations

import datetime
import math
import time
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from engines.base import engine_class
from housner.errors import EngineError
from housner.motion import GroundMotion
from housner.response import Response
from housner.specimen import Specimen

__all__ = [
    "DEFAULT_AMPLITUDES",
    "TuningResult",
    "first_impact_ratio",
    "first_peak",
    "free_vibration_motions",
    "free_rocking_quarter_period",
    "pulse_motions",
    "tune",
    "tuning_report_figure",
]

#: Release amplitudes theta0 / alpha [-] at which r is measured: 0.2 to 0.9 in
#: steps of 0.05. A compliant contact integrated with a fixed step gives each
#: impact's r a scatter that depends on where the impact falls within the step
#: (about +-1 % at MuJoCo's 0.25 ms step), so neighbouring amplitudes differ by
#: more than the tolerance; the 0.1 grid let such a candidate pass by luck.
DEFAULT_AMPLITUDES = tuple(round(0.2 + 0.05 * i, 2) for i in range(15))

#: Accepted relative error of the energy ratio at every amplitude [-]: half the
#: 0.7 % gap between the seed's calibrated and Housner's r (Table 1), so a
#: tuned engine can tell the two apart.
RTOL = 0.005

#: The one-sine pulses of the compliance check: (omega_p / p, a_p / (g tan alpha)) [-].
PULSES = ((8.0, 5.0), (6.0, 3.0))

#: Sample step of the free-vibration records [s]. The peak of a half-cycle is
#: found with a parabola through the three samples around it; its error is
#: O(p^2 alpha dt^3), negligible at 1 ms.
_DT = 0.001


def free_rocking_quarter_period(specimen: Specimen, theta0: float) -> float:
    """Time [s] from a release at rest at ``theta0`` [rad] to the first impact, exact for Housner's equation.

    With no ground motion, rocking on the +x pivot obeys
    theta'' = -p^2 sin(alpha - theta), whose energy integral from a release at
    rest at theta0 is theta'^2 / 2 = p^2 (cos(alpha - theta0) - cos(alpha - theta)).
    The time to fall to theta = 0 is

        T/4 = int_0^theta0 dtheta / sqrt(2 p^2 (cos(alpha - theta0) - cos(alpha - theta))).

    The substitution theta = theta0 - s^2 removes the inverse-square-root end
    singularity, and Gauss-Legendre quadrature (64 nodes) evaluates the smooth
    rest to machine precision. For small alpha it tends to Housner's
    T/4 = acosh(1 / (1 - theta0/alpha)) / p (seed eq. 7).

    Parameters
    ----------
    specimen : Specimen
        Provides p [1/s] and alpha [rad].
    theta0 : float
        Release angle [rad], 0 < |theta0| < alpha.

    References
    ----------
    Housner (1963), eq. for the free-rocking period; Bachmann et al. (2017), eq. 7.
    """
    th0 = abs(float(theta0))
    alpha, p = specimen.alpha, specimen.p
    if not 0.0 < th0 < alpha:
        raise ValueError(f"`theta0` must satisfy 0 < |theta0| < alpha = {alpha:.6g} rad, got {theta0!r}")
    x, wq = np.polynomial.legendre.leggauss(64)
    smax = math.sqrt(th0)
    s = 0.5 * smax * (x + 1.0)
    theta = th0 - s * s
    # cos(a - th0) - cos(a - th) = 2 sin((2a - th0 - th)/2) sin((th0 - th)/2), stable near th = th0
    diff = 2.0 * np.sin(alpha - 0.5 * (th0 + theta)) * np.sin(0.5 * s * s)
    integrand = 2.0 * s / np.sqrt(2.0 * p * p * diff)
    return float(0.5 * smax * np.sum(wq * integrand))


def _parabolic_peak(y: np.ndarray, i: int) -> float:
    """Vertex of the parabola through y[i-1], y[i], y[i+1] (y[i] at the ends)."""
    if i <= 0 or i >= y.size - 1:
        return float(y[i])
    a, b, c = y[i - 1], y[i], y[i + 1]
    den = a - 2.0 * b + c
    if den >= 0.0:
        return float(b)
    return float(b - 0.125 * (a - c) ** 2 / den)


def first_impact_ratio(response: Response, alpha: float | None = None) -> float:
    """Kinetic-energy ratio of the first impact of a free-vibration response (seed eq. 8) [-].

    The peaks are |theta| at release (the largest |theta| before the first
    sign change) and the largest |theta| of the next half-cycle, refined by a
    parabola through the samples around it. NaN when the record ends before
    that half-cycle's peak, when the block never crossed zero, or when a peak
    reached alpha.

    Parameters
    ----------
    response : Response
        A free-vibration response (noise-free engine output).
    alpha : float, optional
        Slenderness [rad]; defaults to ``response.alpha``.

    References
    ----------
    Bachmann et al. (2017), eq. 8.
    """
    alpha = response.alpha if alpha is None else float(alpha)
    th = np.asarray(response.theta, dtype=float)
    s0 = np.sign(th[0]) if th[0] != 0 else np.sign(th[np.argmax(np.abs(th))])
    crossed = np.flatnonzero(th * s0 < 0)
    if crossed.size == 0:
        return math.nan
    k1 = int(crossed[0])
    i0 = int(np.argmax(np.abs(th[:k1])))
    peak0 = _parabolic_peak(np.abs(th), i0)
    back = np.flatnonzero(th[k1:] * s0 > 0)
    k2 = k1 + int(back[0]) if back.size else th.size
    seg = np.abs(th[k1:k2])
    i1 = int(np.argmax(seg))
    if i1 >= seg.size - 1:  # still rising when the record (or half-cycle) ends
        return math.nan
    peak1 = _parabolic_peak(np.abs(th), k1 + i1)
    if not (peak0 < alpha and peak1 < alpha):  # rocked past alpha: no free-vibration half-cycle to compare
        return math.nan
    from housner.calibration import energy_ratios

    return float(energy_ratios([peak0, peak1], alpha)[0])


def first_peak(response: Response) -> float:
    """Largest |theta| [rad] before the first impact of a response that starts at rest.

    The peak is refined by a parabola through the samples around it. NaN if
    the block never left rest, or if |theta| is still growing when the record
    ends before any impact.
    """
    th = np.asarray(response.theta, dtype=float)
    moving = np.flatnonzero(th != 0.0)
    if moving.size == 0:
        return math.nan
    k0 = int(moving[0])
    s0 = np.sign(th[k0])
    back = np.flatnonzero(th[k0:] * s0 < 0)
    end = k0 + int(back[0]) if back.size else th.size
    seg = np.abs(th[:end])
    i = int(np.argmax(seg))
    if i >= seg.size - 1 and not back.size:
        return math.nan
    return _parabolic_peak(np.abs(th), i)


def pulse_motions(specimen: Specimen, pulses=PULSES, dt: float = _DT) -> list[GroundMotion]:
    """The one-sine pulses of the compliance check, scaled to ``specimen``.

    ug''(t) = a_p sin(omega_p t) for one period 2 pi / omega_p, then zero, with
    omega_p = (omega_p / p) p and a_p = (a_p / (g tan alpha)) g tan(alpha); each
    record lasts the pulse plus 2 / p [s] so that the first peak is inside it.
    """
    out = []
    for w_ratio, a_ratio in pulses:
        omega = w_ratio * specimen.p
        a_p = a_ratio * specimen.uplift_acceleration
        tp = 2.0 * math.pi / omega
        n = int(math.ceil((tp + 2.0 / specimen.p) / dt)) + 1
        t = np.arange(n) * dt
        acc = np.where(t <= tp, a_p * np.sin(omega * t), 0.0)
        out.append(
            GroundMotion(
                acc,
                dt,
                name=f"one-sine omega_p={w_ratio:g}p a_p={a_ratio:g}g tan(alpha)",
                provenance="engines.tuning.pulse_motions",
            )
        )
    return out


def _settings_text(settings: dict) -> str:
    def fmt(v):
        if isinstance(v, (list, tuple)):
            return "(" + ", ".join(fmt(x) for x in v) + ")"
        if isinstance(v, float):
            return f"{v:.4g}"
        return str(v)

    return ", ".join(f"{k}={fmt(v)}" for k, v in settings.items())


@dataclass
class TuningResult:
    """What :func:`tune` found.

    Attributes
    ----------
    engine : str
        Engine name.
    specimen : str
        Specimen name.
    target_r : float
        Target kinetic-energy ratio [-].
    settings : dict
        The chosen candidate's settings.
    table : pandas.DataFrame
        For the chosen settings: ``amplitude`` (theta0/alpha [-]), ``r_engine``,
        ``r_target`` and ``rel_error`` (r_engine / r_target - 1 [-]).
    cost_per_sim_second : float
        CPU seconds per simulated second of the chosen settings [s/s].
    met : bool
        True if the chosen settings meet ``rtol`` at every amplitude (and on
        the pulses, when they were checked).
    candidates : pandas.DataFrame
        Every candidate tried: ``settings`` (text), ``worst_rel_error`` and
        ``mean_rel_error`` (signed) of r, ``pulse_rel_error`` (worst
        |first peak / analytic - 1| on the pulses, NaN if not checked),
        ``cost_per_sim_second``, ``wall_per_sim_second``, ``met``, ``error``
        (engine failure, if any).
    pulse_table : pandas.DataFrame
        For the chosen settings: ``pulse`` (name), ``peak_engine`` and
        ``peak_analytic`` (first peak / alpha [-]), ``rel_error``; empty when
        the pulses were not checked.
    rtol : float
        Accepted relative error [-].
    date : str
        ISO date of the run.
    version : str
        Engine package version.
    """

    engine: str
    specimen: str
    target_r: float
    settings: dict
    table: pd.DataFrame
    cost_per_sim_second: float
    met: bool
    candidates: pd.DataFrame
    pulse_table: pd.DataFrame = field(default_factory=pd.DataFrame)
    rtol: float = RTOL
    date: str = field(default_factory=lambda: datetime.date.today().isoformat())
    version: str = ""

    @property
    def worst_rel_error(self) -> float:
        """Largest |r_engine / r_target - 1| of the chosen settings [-]."""
        return float(np.max(np.abs(self.table["rel_error"])))

    def to_dict(self) -> dict:
        """Plain data (JSON-serialisable) for reports and caches."""
        return {
            "engine": self.engine,
            "specimen": self.specimen,
            "target_r": self.target_r,
            "rtol": self.rtol,
            "settings": {k: list(v) if isinstance(v, tuple) else v for k, v in self.settings.items()},
            "met": bool(self.met),
            "worst_rel_error": self.worst_rel_error,
            "cost_per_sim_second": self.cost_per_sim_second,
            "table": self.table.to_dict(orient="list"),
            "pulse_table": self.pulse_table.to_dict(orient="list"),
            "candidates": self.candidates.to_dict(orient="records"),
            "date": self.date,
            "version": self.version,
        }

    def summary(self) -> str:
        """A few lines for the terminal: verdict, settings, errors per amplitude and pulse, cost."""
        verdict = "MET" if self.met else "NOT MET"
        n_ok = int(self.candidates["met"].sum())
        lines = [
            f"{self.engine} tuned to r = {self.target_r:.5g} for {self.specimen} "
            f"({self.date}, version {self.version}): "
            f"{verdict} (tolerance {self.rtol:.2%}; {n_ok} of {len(self.candidates)} candidates met it)",
            f"settings: {_settings_text(self.settings)}",
            "amplitude  r_engine  rel_error",
        ]
        for row in self.table.itertuples():
            lines.append(f"  {row.amplitude:6.3f}   {row.r_engine:.5f}  {row.rel_error:+.3%}")
        lines.append(
            f"worst error {self.worst_rel_error:.3%}, mean {float(self.table['rel_error'].mean()):+.3%}; "
            f"cost {self.cost_per_sim_second:.4g} CPU s per simulated s"
        )
        for row in self.pulse_table.itertuples():
            lines.append(
                f"pulse {row.pulse}: first peak {row.peak_engine:.5f} alpha vs analytic {row.peak_analytic:.5f} "
                f"({row.rel_error:+.3%})"
            )
        return "\n".join(lines)


def free_vibration_motions(specimen: Specimen, amplitudes: Sequence[float], dt: float = _DT) -> list[GroundMotion]:
    """Releases from rest at theta0 = a alpha, each long enough for the first impact and the next peak.

    The duration is 2.2 quarter periods of the release amplitude plus 0.05 s:
    the next half-cycle is shorter than two quarter periods of the release
    because its amplitude is smaller.
    """
    out = []
    for a in amplitudes:
        th0 = a * specimen.alpha
        duration = 2.2 * free_rocking_quarter_period(specimen, th0) + 0.05
        out.append(GroundMotion.free_vibration(th0, duration, dt=dt, name=f"free vibration {a:g} alpha"))
    return out


def _measure(engine, specimen: Specimen, motions: list[GroundMotion], pulses: list[GroundMotion]):
    """Energy ratio per release, first peak per pulse, CPU and wall seconds per simulated second."""
    engine.simulate(specimen, motions[0])  # warm-up: model compile / JIT outside the timing
    r = np.empty(len(motions))
    peaks = np.empty(len(pulses))
    cpu = wall = sim = 0.0
    for i, m in enumerate(motions + pulses):
        c0, w0 = time.process_time(), time.perf_counter()
        resp = engine.simulate(specimen, m)
        cpu += time.process_time() - c0
        wall += time.perf_counter() - w0
        sim += m.duration
        if i < len(motions):
            r[i] = first_impact_ratio(resp)
        else:
            peaks[i - len(motions)] = first_peak(resp)
    return r, peaks, cpu / sim, wall / sim


def tune(
    engine_name: str,
    specimen: Specimen,
    target_r: float | None = None,
    amplitudes: Sequence[float] = DEFAULT_AMPLITUDES,
    candidates: Sequence[dict] | None = None,
    progress: bool = True,
    *,
    rtol: float = RTOL,
    check_pulses: bool = True,
) -> TuningResult:
    """Find the cheapest settings of an engine that reproduce a target energy ratio at impact.

    Parameters
    ----------
    engine_name : str
        A name in :data:`engines.ENGINES`.
    specimen : Specimen
        The block to tune for.
    target_r : float, optional
        Target kinetic-energy ratio at impact [-]; Housner's
        ``specimen.r_housner`` when omitted.
    amplitudes : sequence of float
        Release amplitudes theta0 / alpha [-], each in (0, 1).
    candidates : sequence of dict, optional
        Settings to try; the engine class's ``tuning_candidates(specimen, target_r)`` when omitted.
    progress : bool
        Show a progress bar (tqdm).
    rtol : float
        Accepted |r_engine / r_target - 1| at every amplitude, and accepted
        |first peak / analytic first peak - 1| on each pulse [-].
    check_pulses : bool
        Also require the pulses' first peaks (see the module docstring).

    Returns
    -------
    TuningResult
        The cheapest candidate (by CPU time per simulated second) that meets
        ``rtol`` everywhere, else the candidate with the smallest worst error
        (the larger of the r and pulse errors); ``met`` says which.

    Notes
    -----
    The cost is CPU time of this process, which equals wall time for a
    single-threaded engine on an idle machine and is less disturbed by other
    load; wall time is recorded too. Both are noisy at the 10-20 % level, so
    candidates of nearly equal cost may swap places between runs.
    """
    if not isinstance(specimen, Specimen):
        raise TypeError(f"`specimen` must be a housner.Specimen, got {type(specimen).__name__}")
    cls = engine_class(engine_name)
    target = specimen.r_housner if target_r is None else float(target_r)
    if not (math.isfinite(target) and 0.0 < target < 1.0):
        raise ValueError(f"`target_r` must lie in (0, 1), got {target_r!r}")
    amps = tuple(float(a) for a in amplitudes)
    if not amps or not all(0.0 < a < 1.0 for a in amps):
        raise ValueError(f"`amplitudes` must be non-empty, each in (0, 1) (theta0/alpha), got {amplitudes!r}")
    if not (math.isfinite(rtol) and rtol > 0):
        raise ValueError(f"`rtol` must be positive, got {rtol!r}")
    if candidates is None:
        if not hasattr(cls, "tuning_candidates"):
            raise ValueError(f"engine {engine_name!r} has no tuning_candidates(); pass `candidates`")
        candidates = cls.tuning_candidates(specimen, target)
    candidates = [dict(c) for c in candidates]
    if not candidates:
        raise ValueError("`candidates` is empty")

    releases = free_vibration_motions(specimen, amps)
    pulses = pulse_motions(specimen) if check_pulses else []
    if pulses:
        from housner.model import simulate

        ref_peaks = np.array([first_peak(simulate(specimen, m)) for m in pulses])

    rows, ratios, peaks_all = [], [], []
    it = candidates
    if progress:
        from tqdm.auto import tqdm

        it = tqdm(candidates, desc=f"tuning {engine_name}", unit="candidate")
    version = ""
    for settings in it:
        err = ""
        try:
            engine = cls(**settings)
            version = engine.version()
            r, peaks, cpu, wall = _measure(engine, specimen, releases, pulses)
        except EngineError as e:
            r, peaks, cpu, wall, err = (
                np.full(len(amps), np.nan),
                np.full(len(pulses), np.nan),
                math.inf,
                math.inf,
                str(e),
            )
        rel = r / target - 1.0
        worst = float(np.max(np.abs(rel))) if np.all(np.isfinite(rel)) else math.inf
        if pulses:
            prel = peaks / ref_peaks - 1.0
            pworst = float(np.max(np.abs(prel))) if np.all(np.isfinite(prel)) else math.inf
        else:
            pworst = math.nan
        rows.append(
            {
                "settings": _settings_text(settings),
                "worst_rel_error": worst,
                "mean_rel_error": float(np.mean(rel)) if np.all(np.isfinite(rel)) else math.nan,
                "pulse_rel_error": pworst,
                "cost_per_sim_second": cpu,
                "wall_per_sim_second": wall,
                "met": bool(worst <= rtol and (not pulses or pworst <= rtol)),
                "error": err,
            }
        )
        ratios.append(r)
        peaks_all.append(peaks)
    table = pd.DataFrame(rows)
    ok = np.flatnonzero(table["met"].to_numpy())
    if ok.size:
        best = int(ok[np.argmin(table["cost_per_sim_second"].to_numpy()[ok])])
    else:
        overall = table["worst_rel_error"].to_numpy()
        if pulses:
            overall = np.maximum(overall, table["pulse_rel_error"].to_numpy())
        best = int(np.argmin(overall))
    r = ratios[best]
    chosen = pd.DataFrame(
        {"amplitude": amps, "r_engine": r, "r_target": np.full(len(amps), target), "rel_error": r / target - 1.0}
    )
    if pulses:
        pk = peaks_all[best]
        pulse_table = pd.DataFrame(
            {
                "pulse": [m.name for m in pulses],
                "peak_engine": pk / specimen.alpha,
                "peak_analytic": ref_peaks / specimen.alpha,
                "rel_error": pk / ref_peaks - 1.0,
            }
        )
    else:
        pulse_table = pd.DataFrame(columns=["pulse", "peak_engine", "peak_analytic", "rel_error"])
    return TuningResult(
        engine=engine_name,
        specimen=specimen.name,
        target_r=target,
        settings=cls(**candidates[best]).settings() if hasattr(cls, "settings") else candidates[best],
        table=chosen,
        cost_per_sim_second=float(table["cost_per_sim_second"].iloc[best]),
        met=bool(table["met"].iloc[best]),
        candidates=table,
        pulse_table=pulse_table,
        rtol=rtol,
        version=version,
    )


def tuning_report_figure(result: TuningResult):
    """Energy ratio against release amplitude for the chosen settings, with the target and its band.

    Parameters
    ----------
    result : TuningResult

    Returns
    -------
    matplotlib.figure.Figure
        r_engine [-] against theta0/alpha [-], the target r as a line and the
        +-rtol band shaded.
    """
    from matplotlib.figure import Figure

    fig = Figure(figsize=(6.0, 4.0), layout="constrained")
    ax = fig.add_subplot()
    t = result.table
    lo, hi = result.target_r * (1 - result.rtol), result.target_r * (1 + result.rtol)
    ax.axhspan(lo, hi, color="tab:green", alpha=0.15, label=f"target +- {result.rtol:.1%}")
    ax.axhline(result.target_r, color="tab:green", lw=1.5, label=f"target r = {result.target_r:.4f}")
    ax.plot(t["amplitude"], t["r_engine"], "o-", color="tab:blue", label=f"{result.engine} (chosen settings)")
    ax.set_xlabel(r"release amplitude $\theta_0/\alpha$ [-]")
    ax.set_ylabel("energy ratio at first impact r [-]")
    verdict = "met" if result.met else "NOT met"
    ax.set_title(f"{result.engine} contact tuning: target {verdict}, worst error {result.worst_rel_error:.2%}")
    ax.legend(loc="best", fontsize="small")
    return fig


def main(argv: Sequence[str] | None = None) -> int:
    """Command line: ``python -m engines.tuning ENGINE [--target-r R] [--json FILE] [--figure FILE]``."""
    import argparse
    import json

    ap = argparse.ArgumentParser(prog="python -m engines.tuning", description=main.__doc__)
    ap.add_argument("engine")
    ap.add_argument("--target-r", type=float, default=None, help="target energy ratio (default: Housner's r)")
    ap.add_argument("--json", default=None, help="write the full result as JSON here")
    ap.add_argument("--figure", default=None, help="write the r-against-amplitude figure here")
    ap.add_argument("--quiet", action="store_true", help="no progress bar")
    args = ap.parse_args(argv)
    result = tune(args.engine, Specimen.bachmann2017(), target_r=args.target_r, progress=not args.quiet)
    print(result.summary())
    cand = result.candidates.assign(
        overall=np.fmax(result.candidates["worst_rel_error"], result.candidates["pulse_rel_error"])
    )
    best = cand.sort_values("overall").head(10)
    print("\nbest 10 candidates by worst error:")
    cols = ["settings", "worst_rel_error", "mean_rel_error", "pulse_rel_error", "cost_per_sim_second", "met"]
    print(best[cols].to_string())
    if args.json:
        with open(args.json, "w", encoding="utf-8") as fh:
            json.dump(result.to_dict(), fh, indent=1, default=float)
    if args.figure:
        tuning_report_figure(result).savefig(args.figure)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
