"""The time-history error of a model on one measured record, and how long it follows the measurement.

The definitions are those of ``docs/explanation/diagnosis.md``, "A record's error": the error window
fixed by the measurement alone (:func:`error_window`), the clipped RMS error over it in units of alpha
(:func:`record_error`), for a free vibration minimised over its release instant and angle
(:func:`release_error`), and the divergence time (:func:`divergence_time`). Impacts are the zero
crossings of the measured theta with a hysteresis of 4 noise sigmas (:func:`measured_impacts`).
"""

from __future__ import annotations

import math

import numpy as np

from housner.free_vibration.impacts import HYSTERESIS_SIGMAS, noise_crossings
from housner.scenarios.campaigns.campaign_records import MeasuredRecord

__all__ = [
    "DIVERGENCE_SUSTAIN",
    "ERROR_CLIP",
    "RELEASE_DTHETA0_SIGMAS",
    "WINDOW_IMPACTS",
    "WINDOW_IMPACTS_FV",
    "divergence_time",
    "error_window",
    "measured_impacts",
    "record_error",
    "release_error",
    "release_shift_samples",
    "scored_error",
]

#: Measured impacts in the error window of a ground-motion record [-]. Six impacts are about
#: three rocking cycles: long enough for every effect of the library to show (uplift thresholds,
#: impact losses, timing), short enough that a model with fitted (not exact) parameters has
#: mostly not yet parted from the measurement by chaos. (The exact model and an independent
#: integrator of the same physics stay within ~0.006 alpha over whole 6 s records.)
WINDOW_IMPACTS = 6
#: Free vibration is not chaotic; its window runs over up to this many impacts [-] (from 0.8 alpha
#: with r = 0.95 that is down to ~0.3 alpha: p and r are pinned long before).
WINDOW_IMPACTS_FV = 20
#: Per-sample error clip [alpha].
ERROR_CLIP = 1.0
#: Divergence: |delta theta| > DIVERGENCE_SIGMAS sigma + DIVERGENCE_ALPHA alpha for DIVERGENCE_SUSTAIN s.
DIVERGENCE_SIGMAS = 5.0
DIVERGENCE_ALPHA = 0.05
DIVERGENCE_SUSTAIN = 0.05
#: Free-vibration analyses stop at this many noise sigmas (the calibration's floor).
FV_FLOOR_SIGMAS = 10.0
#: Largest shift of the release instant of a free vibration tried by the error [s] (release_error):
#: twice the +-20 ms to which the instant is known.
RELEASE_SHIFT = 0.05
#: Largest change of a free vibration's release angle tried by the error [noise sigmas]: about twice
#: the bias an undetected short hold leaves (0.3-0.45 sigma), five times the fit's standard error.
RELEASE_DTHETA0_SIGMAS = 1.0


def measured_impacts(theta, noise: float) -> np.ndarray:
    """Indices of the measured impacts: zero crossings of theta with a hysteresis of 4 noise sigmas.

    :func:`housner.free_vibration.impacts.noise_crossings`, the detector the free-vibration
    calibration uses too.

    Parameters
    ----------
    theta : array_like
        Rotation [rad].
    noise : float
        Noise standard deviation [rad].

    Returns
    -------
    ndarray of int
        For each crossing, the first sample beyond the band on the new side.
    """
    return noise_crossings(theta, noise)


def error_window(record: MeasuredRecord, alpha: float, window_impacts: int | None = None) -> int:
    """Number of samples (from the start) over which the time-history error of ``record`` is taken.

    See ``docs/explanation/diagnosis.md``, "A record's error": up to the ``window_impacts``-th measured
    impact, the measured block passing alpha, or the end (ground motion); up
    to the ``window_impacts``-th impact or the last one above 10 noise sigmas
    (free vibration). The impacts are the record's own (:attr:`MeasuredRecord.impacts
    <housner.scenarios.campaigns.campaign_records.MeasuredRecord.impacts>`, :func:`measured_impacts` derived once).
    """
    th = record.theta
    n = th.size
    imp = record.impacts
    if record.kind == "free_vibration":
        k_imp = WINDOW_IMPACTS_FV if window_impacts is None else window_impacts
        floor = FV_FLOOR_SIGMAS * record.noise
        bounds = np.concatenate(([0], imp, [n]))
        end = n
        for j in range(imp.size):
            nxt = np.max(np.abs(th[bounds[j + 1] : bounds[j + 2]]))
            if j + 1 >= k_imp or nxt < floor:
                end = int(imp[j]) + 1
                break
        return max(end, 2)
    k_imp = WINDOW_IMPACTS if window_impacts is None else window_impacts
    end = n
    if imp.size >= k_imp:
        end = int(imp[k_imp - 1]) + 1
    past = np.flatnonzero(np.abs(th) > alpha + HYSTERESIS_SIGMAS * record.noise)
    if past.size:
        end = min(end, int(past[0]) + 1)
    return max(end, 2)


def record_error(
    theta_model,
    theta_measured,
    end: int,
    alpha: float,
    *,
    align: int = 0,
    sensitivity=None,
    max_dtheta0: float = 0.0,
    valid=None,
) -> float:
    """RMS of min(|theta_model - theta_measured| / alpha, 1) over the first ``end`` samples [-].

    ``align`` > 0 (a free vibration): the release instant and angle are nuisance parameters,
    :func:`release_error`. ``valid`` (bool per sample, None: all): only those samples count (a sensor
    fault's samples are not measurements).
    """
    keep = None if valid is None else np.asarray(valid[:end], dtype=bool)
    if keep is not None and not keep.any():
        return math.nan
    if align > 0:
        return release_error(theta_model, theta_measured, end, alpha, align, sensitivity, max_dtheta0, keep)
    d = np.abs(np.asarray(theta_model[:end]) - np.asarray(theta_measured[:end])) / alpha
    np.minimum(d, ERROR_CLIP, out=d)
    if keep is not None:
        d = d[keep[: d.size]]
    return float(math.sqrt(float(np.mean(d * d))))


def release_error(
    theta_model,
    theta_measured,
    end: int,
    alpha: float,
    max_shift: int,
    sensitivity=None,
    max_dtheta0: float = 0.0,
    keep=None,
) -> float:
    """:func:`record_error` of a free vibration, minimised over its release instant and angle [-].

    A free-vibration record's time axis starts at the release its own theta channel shows and its
    initial angle is fitted there (:func:`housner.scenarios.campaigns.campaign_records.estimate_release`). Near the
    release
    theta falls only as c (t - t_r)^2, so with 0.8 mrad noise the instant is known to about +-20 ms,
    and a hold too short to be told from the fall (measured on the seed specimen: 10 samples, half of
    the time) biases the angle by 0.3-0.45 noise sigmas; either alone costs 2-5 noise sigmas of error
    over the window. Both are nuisance parameters of the measurement, not physics: the model is
    shifted by s samples, |s| <= ``max_shift`` (every whole sample, then the vertex of the parabola
    through the best and its neighbours), its release angle changed by d, |d| <= ``max_dtheta0`` [rad],
    to first order through ``sensitivity`` = d theta / d theta0 on the model's grid (least squares for
    d at each shift), and the smallest error counts.
    """
    m = np.asarray(theta_model, dtype=float)
    g = None if sensitivity is None or max_dtheta0 <= 0 else np.asarray(sensitivity, dtype=float)
    y = np.asarray(theta_measured[:end], dtype=float)
    n, k = y.size, int(max_shift)

    def pad(a: np.ndarray) -> np.ndarray:
        # a[j - s] for every shift s in [-k, k]: held at its first value before it starts and at its
        # last beyond its end
        tail = max(0, n + k - a.size)
        return np.concatenate((np.full(k, a[0]), a[: n + k], np.full(tail, a[-1])))

    def errors(rows_m: np.ndarray, rows_g: np.ndarray | None) -> np.ndarray:
        r = y - rows_m
        if keep is not None:
            r = r[:, keep[:n]]
            rows_g = None if rows_g is None else rows_g[:, keep[:n]]
        if rows_g is not None:
            gg = np.einsum("ij,ij->i", rows_g, rows_g)
            d = np.where(gg > 0, np.einsum("ij,ij->i", r, rows_g) / np.where(gg > 0, gg, 1.0), 0.0)
            r = r - np.clip(d, -max_dtheta0, max_dtheta0)[:, None] * rows_g
        e = np.minimum(np.abs(r) / alpha, ERROR_CLIP)
        return np.sqrt(np.mean(e * e, axis=1))

    # whole-sample shifts at once: row i is the model delayed by s = k - i samples
    win_m = np.lib.stride_tricks.sliding_window_view(pad(m), n)
    win_g = None if g is None else np.lib.stride_tricks.sliding_window_view(pad(g), n)
    vals = errors(win_m, win_g)
    b = int(np.argmin(vals))
    best = float(vals[b])
    if 0 < b < vals.size - 1:
        # a fraction of a sample: the vertex of the parabola through the best shift and its neighbours
        den = vals[b - 1] - 2 * vals[b] + vals[b + 1]
        if den > 0:
            frac = 0.5 * (vals[b - 1] - vals[b + 1]) / den  # in rows, |frac| <= 1/2
            shift = (k - b) - frac
            idx = np.arange(n, dtype=float) - shift
            grid = np.arange(m.size, dtype=float)
            rm = np.interp(idx, grid, m)[None, :]
            rg = None if g is None else np.interp(idx, grid, g)[None, :]
            best = min(best, float(errors(rm, rg)[0]))
    return best


def release_shift_samples(rec: MeasuredRecord) -> int:
    """Samples a free-vibration record's model may be shifted by (0 for a ground motion)."""
    if rec.kind != "free_vibration":
        return 0
    return max(1, int(round(RELEASE_SHIFT / rec.dt)))


def scored_error(theta_model, rec: MeasuredRecord, end: int, alpha: float, sensitivity=None) -> float:
    """The time-history error of one record as the comparison and the diagnosis score it [-]."""
    return record_error(
        theta_model,
        rec.theta,
        end,
        alpha,
        align=release_shift_samples(rec),
        sensitivity=sensitivity,
        max_dtheta0=RELEASE_DTHETA0_SIGMAS * rec.noise,
        valid=rec.valid,
    )


def divergence_time(theta_model, theta_measured, t, noise: float, alpha: float) -> float:
    """First time [s] at which |theta_model - theta_measured| exceeds 5 sigma + 0.05 alpha for 50 ms; NaN if never."""
    d = np.abs(np.asarray(theta_model) - np.asarray(theta_measured))
    thr = DIVERGENCE_SIGMAS * noise + DIVERGENCE_ALPHA * alpha
    over = (d > thr).astype(np.int64)
    dt = float(t[1] - t[0]) if len(t) > 1 else 1.0
    w = max(1, int(round(DIVERGENCE_SUSTAIN / dt)))
    if over.size < w:
        return math.nan
    c = np.concatenate(([0], np.cumsum(over)))
    run = c[w:] - c[:-w]
    k = np.flatnonzero(run == w)
    return float(t[k[0]]) if k.size else math.nan
