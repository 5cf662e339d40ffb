"""The tuner's checks: their records, tolerances and analytic references, and how a candidate scores on them.

Each check compares an engine with the analytic model at r = target (Housner's r by default): the first
impact's energy ratio at 0.2-0.9 alpha (:data:`DEFAULT_AMPLITUDES`, within :data:`RTOL`) and at small
amplitudes (:data:`SMALL_AMPLITUDES`), the free decay (:data:`DECAY_START`, :data:`DECAY_IMPACTS`,
:data:`DECAY_RTOL`) and the pulses (:data:`PULSES`, :data:`THRESHOLD_PULSES`), each at every one of the
:data:`SAMPLE_STEPS`, the worse counted. The constants' notes say why each tolerance is what it is; the
checks' formulas, and why checks 2-4 were added, are in ``docs/explanation/engines.md`` ("The tuner's
checks").
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from housner.engines.measures import decay_peaks, first_peak, free_rocking_quarter_period
from housner.model import simulate
from housner.motion import GroundMotion
from housner.pulse_response.pulses import one_sine
from housner.specimen import Specimen

#: Release amplitudes theta0 / alpha [-] at which r is measured (check 1): 0.20
#: to 0.90 in steps of 0.01. A compliant contact integrated with a fixed step
#: gives each impact's r a scatter that depends on where the impact falls
#: within the step (standard deviation 0.13-0.26 % at MuJoCo's 0.2-0.33 ms
#: steps), so neighbouring amplitudes differ by more than the tolerance: on the
#: earlier 0.05 grid a 1/3 ms candidate passed whose worst error on this grid
#: is 1.03 %.
DEFAULT_AMPLITUDES = tuple(round(0.2 + 0.01 * i, 2) for i in range(71))

#: Small release amplitudes theta0 / alpha [-] (check 2): 0.02 to 0.19 in steps of 0.01.
SMALL_AMPLITUDES = tuple(round(0.02 + 0.01 * i, 2) for i in range(18))

#: Accepted relative error of the energy ratio at every amplitude [-]: half the
#: 0.7 % gap between the seed's calibrated and Housner's r (Table 1), so a
#: tuned engine can tell the two apart.
RTOL = 0.005

#: Worst small-amplitude error accepted, in units of ``rtol`` (check 2). Below 0.2 alpha the
#: impacts are slow and each one's ratio scatters more with where it falls within the engine
#: step (measured standard deviation 0.36-0.52 % at 0.02-0.05 alpha for steps of 0.125-0.25 ms,
#: against 0.13-0.26 % above 0.2 alpha), so the single worst impact gets three times the
#: tolerance; a bias would add up over the many small impacts of a record, so the mean keeps
#: the tight one.
SMALL_WORST_FACTOR = 3.0

#: The strong one-sine pulses of check 4: (omega_p / p, a_p / (g tan alpha)) [-].
#: They rock the seed specimen to first peaks of 0.29, 0.21 and 0.13 alpha and,
#: after one impact, to theta_max = 0.53, 0.64 and 0.21 alpha (within 1.7 / p
#: of the pulse's end). First peak and theta_max are accepted within ``rtol``.
PULSES = ((8.0, 5.0), (6.0, 3.0), (12.0, 5.0))

#: The near-threshold one-sine pulses of check 4: first peaks of 0.023 and
#: 0.018 alpha, then, after an impact at that small amplitude, theta_max = 0.18
#: and 0.16 alpha. theta_max inherits that impact's scatter (check 2), so it
#: is accepted within 3 ``rtol``; the first peak, before any impact, within ``rtol``.
THRESHOLD_PULSES = ((6.0, 1.5), (3.0, 1.2))

#: Free decay (check 3): release amplitude theta0 / alpha [-], the impacts after which the peak
#: is compared (for Housner's r the peaks are then 0.056, 0.032, 0.018 and 0.011 alpha), and the
#: accepted relative error [-]. The seed compares its free-vibration test over more than 20
#: cycles (40 impacts). Independent scatter of 0.3 % per impact adds up to about 2 % (one
#: standard deviation) after 40 impacts; 5 % of the 40th peak is 0.08 mrad, a tenth of what
#: the seed's markers resolve.
DECAY_START = 0.1
DECAY_IMPACTS = (10, 20, 30, 40)
DECAY_RTOL = 0.05

#: Free decay (check 3): a peak is compared only if its analytic value is at least this [alpha],
#: the resolution at which impacts are counted (``benchmarks/bench_engines.py``). For a target
#: below Housner's r the decay reaches it sooner: for r = 0.9 the peaks after 30 and 40 impacts
#: are 0.004 and 0.0014 alpha, below what any engine's contact was tuned or measured for.
DECAY_FLOOR = 0.01

#: Sample step of the free-vibration records [s]. The peak of a half-cycle is
#: found with a parabola through the three samples around it; its error is
#: O(p^2 alpha dt^3), negligible at 1 ms.
_DT = 0.001

#: Sample steps [s] at which every check is run: 1 ms, and 0.01 / sqrt(10) s,
#: the step of the seed's El Centro records at model scale. The engine's step
#: (the sample step over a whole number) then falls differently relative to
#: the impacts; a candidate that passes at one sample step only passed by
#: luck (the only 0.25 ms candidate that passed at 1 ms had its 40th decay
#: peak 3 % off there and 11 % off at 3.16 ms).
SAMPLE_STEPS = (0.001, 0.01 / math.sqrt(10.0))


def decay_motion(
    specimen: Specimen, start: float = DECAY_START, n_impacts: int = max(DECAY_IMPACTS), dt: float = _DT
) -> GroundMotion:
    """Free vibration from rest at ``start`` alpha, long enough for ``n_impacts`` impacts and the next peak.

    The duration is that of Housner's decay (:func:`decay_peaks`): a quarter
    period from the release, two per half-cycle after it, 1.1 times over, plus
    0.05 s.
    """
    peaks = decay_peaks(specimen, start * specimen.alpha, n_impacts)
    tq = [free_rocking_quarter_period(specimen, th) for th in peaks]
    duration = 1.1 * (tq[0] + 2.0 * sum(tq[1:]) + tq[-1]) + 0.05
    return GroundMotion.free_vibration(
        start * specimen.alpha, duration, dt=dt, name=f"free decay from {start:g} alpha, {n_impacts} impacts"
    )


def pulse_motions(specimen: Specimen, pulses=PULSES, dt: float = _DT) -> list[GroundMotion]:
    """The one-sine pulses of the pulse check, scaled to ``specimen``.

    ug''(t) = a_p sin(omega_p t) for one period 2 pi / omega_p, then zero, with
    omega_p = (omega_p / p) p and a_p = (a_p / (g tan alpha)) g tan(alpha); each
    record lasts the pulse plus 3 / p [s] so that the first peak and theta_max
    are inside it.
    """
    out = []
    for w_ratio, a_ratio in pulses:
        omega = w_ratio * specimen.p
        a_p = a_ratio * specimen.uplift_acceleration
        tp = 2.0 * math.pi / omega
        n = int(math.ceil((tp + 3.0 / specimen.p) / dt)) + 1  # samples
        g = one_sine(a_p, omega, dt=dt, duration=(n - 0.5) * dt)
        out.append(
            GroundMotion(
                g.acc,
                dt,
                name=f"one-sine omega_p={w_ratio:g}p a_p={a_ratio:g}g tan(alpha)",
                provenance="housner.engines.tuning.pulse_motions",
            )
        )
    return out


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


@dataclass
class CheckSuite:
    """The records of the checks at one sample step, and the analytic references."""

    dt: float
    releases: list[GroundMotion]
    small: list[GroundMotion]
    decay: list[GroundMotion]
    decay_ref: np.ndarray  # peaks / alpha after decay_impacts impacts
    pulses: list[GroundMotion]
    pulse_ref: np.ndarray  # (first peak, theta_max) [rad] per pulse
    pulse_tol: np.ndarray  # (first peak, theta_max) tolerance in units of rtol, per pulse
    decay_impacts: tuple = DECAY_IMPACTS  # the impacts after which the decay's peak is compared


def check_suite(specimen: Specimen, target: float, amps, small_amps, check_decay: bool, check_pulses: bool, dt: float):
    """The checks' records at sample step ``dt`` [s] and their analytic references at r = ``target``.

    Decay peaks whose analytic value lies below :data:`DECAY_FLOOR` are left out (none: no decay record).
    """
    decay, decay_ref, decay_impacts = [], np.empty(0), ()
    if check_decay:
        peaks = decay_peaks(specimen, DECAY_START * specimen.alpha, max(DECAY_IMPACTS), r=target) / specimen.alpha
        decay_impacts = tuple(k for k in DECAY_IMPACTS if peaks[k] >= DECAY_FLOOR)
        decay_ref = peaks[list(decay_impacts)]
        decay = [decay_motion(specimen, dt=dt)] if decay_impacts else []
    pulses, tol = [], []
    if check_pulses:
        pulses = pulse_motions(specimen, PULSES, dt) + pulse_motions(specimen, THRESHOLD_PULSES, dt)
        tol = [(1.0, 1.0)] * len(PULSES) + [(1.0, SMALL_WORST_FACTOR)] * len(THRESHOLD_PULSES)
    refs = [simulate(specimen, m, r=target) for m in pulses]
    return CheckSuite(
        dt,
        free_vibration_motions(specimen, amps, dt),
        free_vibration_motions(specimen, small_amps, dt),
        decay,
        decay_ref,
        pulses,
        np.array([(first_peak(x), x.theta_max) for x in refs]).reshape(-1, 2),
        np.array(tol, dtype=float).reshape(-1, 2),
        decay_impacts,
    )


def _worst(rel) -> float:
    """Largest |rel| [-]; inf if any is NaN (a check that could not be measured fails)."""
    rel = np.asarray(rel, dtype=float)
    if rel.size == 0:
        return math.nan
    return float(np.max(np.abs(rel))) if np.all(np.isfinite(rel)) else math.inf


def candidate_errors(meas: list[dict], suites: list[CheckSuite], target: float, rtol: float) -> dict:
    """Relative errors of one candidate per suite, each check's worst over the suites, and the score.

    The score is the largest error over its tolerance (check 2's mean is the
    worst of the per-suite means); the candidate passes when it is at most 1.
    """
    rel = [m["r"] / target - 1.0 for m in meas]
    small = [m["small"] / target - 1.0 for m in meas]
    decay = [m["decay"] / s.decay_ref - 1.0 if s.decay else np.empty(0) for m, s in zip(meas, suites, strict=True)]
    pulse = [m["pulse"] / s.pulse_ref - 1.0 for m, s in zip(meas, suites, strict=True)]
    pulse_scaled = np.concatenate([np.ravel(p / s.pulse_tol) for p, s in zip(pulse, suites, strict=True)])
    all_rel, all_small, all_decay = np.concatenate(rel), np.concatenate(small), np.concatenate(decay)
    means = [float(np.mean(x)) if x.size and np.all(np.isfinite(x)) else math.nan for x in small]
    small_mean = max(means, key=abs) if all_small.size else math.nan
    e = {
        "worst_rel_error": _worst(all_rel),
        "mean_rel_error": float(np.mean(all_rel)) if np.all(np.isfinite(all_rel)) else math.nan,
        "small_worst_rel_error": _worst(all_small),
        "small_mean_rel_error": small_mean,
        "pulse_rel_error": _worst(np.concatenate([np.ravel(p) for p in pulse])),
        "decay_rel_error": _worst(all_decay),
    }
    ratios = {"r": e["worst_rel_error"] / rtol}
    if all_small.size:
        ratios["small-amplitude r"] = e["small_worst_rel_error"] / (SMALL_WORST_FACTOR * rtol)
        ratios["small-amplitude mean r"] = abs(small_mean) / rtol if math.isfinite(small_mean) else math.inf
    if pulse_scaled.size:
        ratios["pulses"] = _worst(pulse_scaled) / rtol
    if all_decay.size:
        ratios["decay"] = e["decay_rel_error"] / DECAY_RTOL
    finite = all(math.isfinite(x) for x in ratios.values())
    e["score"] = float(max(ratios.values())) if finite else math.inf
    e["met"] = bool(e["score"] <= 1.0)
    # the checks not met, by name (a ratio that could not be measured fails its check)
    e["failed"] = ", ".join(k for k, x in ratios.items() if not (math.isfinite(x) and x <= 1.0))
    e["_rel"], e["_small"], e["_decay"], e["_pulse"] = rel, small, decay, pulse
    return e
