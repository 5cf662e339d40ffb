"""The diagnosis' verdict: is the remaining misfit physics, or what a correct model shows anyway?

A held-out time-history error is only meaningful against the error that a
*correct* model would show on the same records: the sensor noise, plus what
chaos makes of parameters that the campaign pins only so well. That floor is
measured here from the campaign itself, by a parametric bootstrap
(:func:`measure_floor`):

1. the fitted model is taken as the truth and run on the measured table
   motions (free vibrations released at the measured angle): the records a
   correct model would have produced;
2. Gaussian noise of each record's measured sigma is added (a fresh draw per
   replica);
3. the model that scores them is the one the real held-out errors use: the
   records of fold k are scored by the model fitted without fold k (its
   parameters differ from the full fit's as they do in the real scoring,
   a fold refit that wandered included), each parameter moved by a
   Gaussian draw of the full fit's own uncertainty (the grouped-jackknife
   standard error over the K fold fits: the bootstrap's truth is the full
   fit, the real truth is within that of it), each draw kept within the
   range the fold fits and the full fit span (the values the data chose: a
   draw beyond them can cross into a regime the data reject, e.g. a sliding
   block's friction coefficient across tan alpha, where the block rocks and
   the error is tens of noise sigmas), and integrated with twice
   the substeps (a measurement is never produced by the model's own
   integrator, and chaos amplifies the difference like any other); the
   stated specimen's p and r are not perturbed: a model that is right about
   them is what "correct" means here;
4. each record is scored with the same error and window as the real one.

The real held-out errors are then tested against the floor record by record
(:func:`residual_test`), separately for ground motions (paired differences,
their mean over its standard error, and the same on 10 %-trimmed means,
Yuen's test: chaos makes them heavy-tailed and independent from record to
record) and free vibrations (not chaotic; each
record's difference over the replicas' spread, combined by Stouffer's sum).
A misfit is *significant* when z > :data:`Z_MISFIT` and its size *matters*
when the error is more than :data:`RATIO_MISFIT` times the floor.

:func:`decide` turns the residual of the plain model and of the final model,
the effects selected and the distributions into one of five statuses:
``no_misfit``, ``explained``, ``partly_explained``, ``unexplained``,
``inconclusive``, with a paragraph that says it in words, where the misfit
shows (localisation items), and which physical classes to look at next
(:func:`physical_classes`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field, replace

import numpy as np
from housner.scenarios.campaigns.campaign import estimate_release
from housner.scenarios.campaigns.compare import (
    METRICS,
    RELEASE_DTHETA0_SIGMAS,
    Comparison,
    record_error,
    release_sensitivities,
    release_shift_samples,
    simulate_records,
)
from housner.scenarios.campaigns.fitting import param_dims
from housner.scenarios.campaigns.model_form import ModelForm, acc_channel_noise
from scipy.stats import kendalltau, norm

from housner.effects import make_effect
from housner.model import default_substeps

__all__ = [
    "CLASSES",
    "RATIO_MISFIT",
    "STATUSES",
    "Z_MISFIT",
    "Floor",
    "Residual",
    "Verdict",
    "decide",
    "distribution_checks",
    "measure_floor",
    "order_drift",
    "physical_classes",
    "residual_test",
]

STATUSES = ("no_misfit", "explained", "partly_explained", "unexplained", "inconclusive")
#: One-sided z above which the error is significantly above the floor (p ~ 1.3e-3) [-].
Z_MISFIT = 3.0
#: |z| beyond which a localisation quantity of a model says it misses something even when its errors
#: are at the floor [-]: with the 17 quantities of housner.scenarios.campaigns.compare.METRICS tested at once, a
#: two-sided 6e-5 each keeps the chance of a false alarm per model near 0.1 % (Bonferroni).
Z_LOCAL = 4.0
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
#: |z| of the rank correlation between the records' excess errors and their recording order beyond
#: which the campaign is said to drift (two models tested, two-sided: 2 x 4.7e-4) [-].
Z_DRIFT = 3.5
#: Share of the ground motions' paired differences trimmed off each end in the robust test [-]: chaos
#: carries a record or two of 60 far off a correct model's floor (measured: one record at 0.66 alpha
#: against a floor of 0.38 +- 0.35 while the other 59 sit at it, median ratio 1.00).
TRIM = 0.1
#: Fewest records of a campaign (free vibration and ground motion) the verdict speaks on [-].
MIN_RECORDS = 8
#: Significance level of each distribution check (KS of theta_max/alpha, overturn fraction) [-].
DIST_LEVEL = 0.01
#: Replicas of the floor bootstrap [-]. Each is one simulation of the campaign.
N_REPLICAS = 6
#: Relative spread of one free-vibration record's error below which the replicas' spread is not
#: trusted (an RMS over ~1000-5000 noisy samples scatters by ~1-2 %) [-].
FV_MIN_REL_SD = 0.02

#: Localisation metric -> physical class it points to.
_CLASS_OF: dict[str, str] = {
    "energy_ratio": "impact",
    "energy_ratio_trend": "impact",
    "energy_ratio_scatter": "impact",
    "flight_ratio": "dissipation",
    "flight_ratio_trend": "dissipation",
    "p": "inertia",
    "alternation": "asymmetry",
    "onset_pos": "asymmetry",
    "onset_neg": "asymmetry",
    "withstood_pos": "asymmetry",
    "withstood_neg": "asymmetry",
    "first_uplift_pos": "asymmetry",
    "share_pos": "asymmetry",
    "tilt_offset": "setup",
    "tilt_slope": "compliance",
    "overturn_fraction": "response",
    "theta_max_median": "response",
    "onset_scatter": "vertical_input",
}
#: Physical class -> what it means, in words.
CLASSES: dict[str, str] = {
    "impact": "impact or contact physics: the energy lost per impact differs from the model's, changes with "
    "amplitude or varies from impact to impact (restitution law, where on the contact strip the impact acts)",
    "dissipation": "dissipation between impacts: energy is lost while the block rocks (air drag, friction or "
    "micro-slip at the pivot, a lossy interface)",
    "inertia": "inertia or foundation: the half-cycle durations depart from Housner's law (p, a compliant base, "
    "a flexible body)",
    "asymmetry": "asymmetry: the two directions differ (mass distribution, pivot geometry, a tilted table)",
    "setup": "set-up or sensor: the block reads a rotation while at rest (sensor offset, a tilted table)",
    "compliance": "base or body compliance: the block rotates before it lifts off (flexible foundation or body)",
    "vertical_input": "the ground input or the effective gravity: the uplift thresholds depart from g tan alpha in "
    "both directions alike, or vary from record to record with the table motion (a vertical table acceleration, "
    "an accelerometer gain, a table that rocks)",
    "drift": "a drift along the recording order: the block or the set-up changed during the campaign (wear of the "
    "contact, a fixture loosening, the temperature); the order of the [[record]] tables is the recording order",
    "response": "response amplitude: the peaks or the overturn fraction differ although the records' details "
    "do not say why (an intensity-dependent effect)",
}


@dataclass(frozen=True)
class Floor:
    """The error a correct model shows on each record, measured by the parametric bootstrap.

    Attributes
    ----------
    mean, sd : ndarray
        Per record (campaign order): mean and standard deviation over the replicas [alpha].
    n_replicas : int
    perturbation : dict
        What was perturbed and by how much: parameter -> standard deviation (units of the parameter),
        and the substeps of the scoring model.
    """

    mean: np.ndarray
    sd: np.ndarray
    n_replicas: int
    perturbation: dict


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
    groups : dict
        ``ground_motion`` / ``free_vibration`` -> {n, error, floor, ratio, z, misfit}.
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
    groups: dict
    detectable_ratio: float
    records_needed: int

    def to_dict(self) -> dict:
        return {
            "error": self.error,
            "floor": self.floor,
            "ratio": self.ratio,
            "z": self.z,
            "misfit": self.misfit,
            "groups": self.groups,
            "detectable_ratio": self.detectable_ratio,
            "records_needed": self.records_needed,
        }


# ----------------------------------------------------------------------------
# the floor
def _perturbed(name: str, params: dict, sd: dict, rng, specimen, hull: dict | None = None) -> dict:
    out = dict(params)
    for d in param_dims(name, specimen):
        key = f"{name}.{d.key}"
        s = sd.get(key, 0.0)
        if s > 0:
            lo, hi = (hull or {}).get(key, (d.lo, d.hi))
            out[d.key] = min(max(params[d.key] + s * rng.standard_normal(), d.lo, lo), d.hi, hi)
    return out


def measure_floor(
    scorer,
    model_full: list[tuple[str, dict]],
    model_folds: list[list[tuple[str, dict]]],
    fold_of: np.ndarray,
    *,
    n_replicas: int = N_REPLICAS,
    seed: int = 0,
    family: str = "any",
) -> Floor:
    """Parametric bootstrap of the error a correct model shows on each record (module docstring).

    Parameters
    ----------
    scorer : housner.scenarios.campaigns.scoring.Scorer
        All records of the campaign (truncated to their error windows), in campaign order.
    model_full : list of (name, params)
        The model fitted on every record: the bootstrap's truth.
    model_folds : list of list of (name, params)
        The same model fitted without each fold: the model that scores that fold's records.
    fold_of : ndarray of int
        Fold of each record.
    n_replicas : int
    seed : int
    family : str
        The family of correct integrators each replica's truth is drawn from
        (:data:`housner.scenarios.campaigns.model_form.FAMILIES`).

    Returns
    -------
    Floor
    """

    camp = scorer.campaign
    spec = camp.specimen
    alpha = spec.alpha
    recs = scorer.records
    k_folds = len(model_folds)
    sd: dict[str, float] = {}
    hull: dict[str, tuple[float, float]] = {}
    for i, (name, p) in enumerate(model_full):
        for key in p:
            vals = np.array([mf[i][1][key] for mf in model_folds], dtype=float)
            # the grouped-jackknife standard error of the full fit: how far the bootstrap's truth may be
            # from the real one
            ss = float(np.sum((vals - vals.mean()) ** 2))
            sd[f"{name}.{key}"] = math.sqrt((k_folds - 1) / k_folds * ss) if k_folds > 1 else 0.0
            hull[f"{name}.{key}"] = (min(float(vals.min()), p[key]), max(float(vals.max()), p[key]))
    settings = dict(scorer.engine_settings)
    truth_eff = [make_effect(n, **p) for n, p in model_full]
    acc_noise = acc_channel_noise(camp)
    # the scoring model integrates with twice the substeps: the measurement was not produced by this
    # integrator, and chaos amplifies such a difference as it amplifies any other
    sub = settings.get("substeps") or default_substeps(spec.frequency_parameter, recs[0].dt)
    model_settings = {**settings, "substeps": 2 * int(sub)}
    errs = np.empty((n_replicas, len(recs)))
    forms = []
    for b in range(n_replicas):
        rng = np.random.default_rng(np.random.SeedSequence([seed, 4241, b]))
        # the replica's truth: the fitted model, produced by "another correct integrator" (module docstring)
        form = ModelForm.draw(np.random.default_rng(np.random.SeedSequence([seed, 4242, b])), acc_noise, family)
        forms.append(form)
        truth = form.simulate(spec, recs, truth_eff, settings)
        model = [None] * len(recs)
        model_sens: list = [None] * len(recs)
        eff_of: dict[int, list] = {}
        for k in range(k_folds):
            idx = np.flatnonzero(fold_of == k)
            if idx.size == 0:
                continue
            # the model that scores fold k's records is the one fitted without them, as in the real
            # held-out errors, moved by the uncertainty of the truth
            eff = [make_effect(n, **_perturbed(n, model_folds[k][j][1], sd, rng, spec, hull))
                   for j, (n, _p) in enumerate(model_full)]  # fmt: skip
            eff_of[k] = eff
            sub = [recs[i] for i in idx]
            res = simulate_records(spec, sub, "housner", eff, model_settings)
            sens = release_sensitivities(spec, sub, res, "housner", eff, model_settings)
            for i, r, g in zip(idx, res, sens, strict=True):
                model[i] = r
                model_sens[i] = g
        for i, rec in enumerate(recs):
            tr, mo = truth[i], model[i]
            if isinstance(tr, str) or isinstance(mo, str) or mo is None:
                errs[b, i] = 1.0
                continue
            th_true = tr
            meas = th_true + rng.normal(0.0, rec.noise, th_true.size)
            g = model_sens[i]
            if rec.kind == "free_vibration":
                # the model of a free vibration starts from the release angle read off the noisy record
                # (campaign.estimate_release), off the true one by its standard error: so here
                mo, g = _from_estimated_release(spec, rec, meas, mo, g, eff_of[int(fold_of[i])], model_settings)
            th_mod = np.asarray(mo.theta, dtype=float)[: rec.theta.size]
            errs[b, i] = record_error(th_mod, meas, scorer.ends[i], alpha, align=release_shift_samples(rec),
                                      sensitivity=None if g is None else g[: rec.theta.size],
                                      max_dtheta0=RELEASE_DTHETA0_SIGMAS * rec.noise)  # fmt: skip
    pert = {k: v for k, v in sd.items() if v > 0}
    pert["substeps"] = model_settings["substeps"]
    pert["model_form"] = {"family": family, "replicas": [f.describe() for f in forms], "acc_noise": acc_noise}
    return Floor(errs.mean(axis=0), errs.std(axis=0, ddof=1) if n_replicas > 1 else np.zeros(len(recs)), n_replicas,
                 pert)  # fmt: skip


def _from_estimated_release(spec, rec, meas, mo, g, eff, settings):
    """The model's response (and release sensitivity) to a free vibration of replica data ``meas``, started
    from the release angle the campaign reader would read off it; ``mo``, ``g`` when it reads the same."""
    try:
        _k, th0 = estimate_release(rec.t, meas, rec.noise)
    except ValueError:
        return mo, g
    if th0 == rec.motion.theta0:
        return mo, g
    moved = replace(rec, motion=replace(rec.motion, theta0=th0))
    res = simulate_records(spec, [moved], "housner", eff, settings)
    if isinstance(res[0], str):
        return mo, g
    return res[0], release_sensitivities(spec, [moved], res, "housner", eff, settings)[0]


# ----------------------------------------------------------------------------
# the residual test
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
        groups[kind] = {"n": n, "error": float(e[m].mean()), "floor": fm, "ratio": ratio, "z": z, "misfit": mis,
                        "ratio_trimmed": ratio_t, "z_trimmed": z_t,
                        "detectable_ratio": max(det_k, RATIO_MISFIT)}  # fmt: skip
        z_all = max(z_all, z, z_t)
        misfit = misfit or mis
        det = min(det, max(det_k, RATIO_MISFIT))
    ok = np.isfinite(e)
    err, flo = float(e[ok].mean()), float(f[ok].mean())
    robust = [g["ratio_trimmed"] if k == "ground_motion" else g["ratio"] for k, g in groups.items()]
    ratio = max(robust) if robust else (err / flo if flo > 0 else math.inf)
    return Residual(err, flo, ratio, z_all, misfit, groups, det, need)


# ----------------------------------------------------------------------------
# where to look
def physical_classes(cmp: Comparison | None, z: float = 3.0) -> list[dict]:
    """Physical classes the localisation points to, strongest first, each with its supporting figures.

    Returns a list of {``class``, ``meaning``, ``z`` (largest |z| of its metrics), ``evidence`` (list of
    {metric, label, measured, measured_se, model, model_se, z})}.
    """
    if cmp is None:
        return []
    by: dict[str, dict] = {}
    found = cmp.discrepancies(z)
    zs = {k: zz for k, zz, *_ in found}
    # The energy ratio of seed eq. 8 is taken peak to peak: it holds the loss at the impact AND the loss
    # while the block rocks. When the loss between impacts (flight ratio) also differs, that is where
    # the energy goes. When it is not resolved, the share of the extra loss that the flight ratio puts
    # between the impacts decides (the likelier of the two): a friction moment at the pivot loses
    # (almost) all of it there, an impact law none.
    share = _flight_share(cmp.localisation()) if "energy_ratio" in zs else None
    flight = any(k.startswith("flight_ratio") for k in zs) or (share is not None and share[0] > 0.5)
    # Uplift thresholds that differ alike in both directions are the input's or gravity's (a gain on
    # the recorded acceleration, a vertical acceleration); differing one way only, or in opposite ways,
    # an asymmetry.
    sides = [(zs.get(f"onset_{d}"), zs.get(f"withstood_{d}")) for d in ("pos", "neg")]
    sign = [next((math.copysign(1.0, v) for v in side if v is not None), 0.0) for side in sides]
    symmetric = sign[0] != 0.0 and sign[0] == sign[1]
    for key, zz, m, x in found:
        c = _CLASS_OF.get(key, "response")
        if flight and key.startswith("energy_ratio") and key != "energy_ratio_scatter":
            c = "dissipation"
        if symmetric and key.startswith(("onset_", "withstood_")):
            c = "vertical_input"
        entry = by.setdefault(c, {"class": c, "meaning": CLASSES[c], "z": 0.0, "evidence": []})
        entry["z"] = max(entry["z"], abs(zz))
        if key == "energy_ratio" and share is not None:
            entry["evidence"].append({
                "metric": "flight_share", "label": "share of the extra loss per half-cycle that the energy kept "
                "between impacts puts between them (1: all of it, 0: none, at the impact)",
                "measured": share[0], "measured_se": share[1], "model": 0.0, "model_se": 0.0,
                "z": share[0] / share[1] if share[1] > 0 else math.inf,
            })  # fmt: skip
        entry["evidence"].append(
            {
                "metric": key,
                "label": METRICS[key][0],
                "measured": m.value,
                "measured_se": m.se,
                "model": x.value,
                "model_se": x.se,
                "z": zz,
            }  # fmt: skip
        )
    return sorted(by.values(), key=lambda d: -d["z"])


def _flight_share(loc: dict) -> tuple[float, float] | None:
    """Share of the extra energy loss per half-cycle that happens between impacts, and its standard error.

    The measured energy ratio c_m falls short of the model's c_x by a factor c_m / c_x; the energy kept
    between impacts f (flight ratio) says how much of that shortfall is lost while the block rocks:
    (1 - f_m / f_x) / (1 - c_m / c_x). None when either is not measured or the ratios agree.
    """
    try:
        (cm, cx), (fm, fx) = loc["energy_ratio"], loc["flight_ratio"]
    except KeyError:
        return None
    vals = (cm.value, cx.value, fm.value, fx.value, fm.se, fx.se)
    if not all(math.isfinite(v) for v in vals) or cx.value <= 0 or fx.value <= 0 or fm.value <= 0:
        return None
    deficit = 1.0 - cm.value / cx.value
    if abs(deficit) < 1e-9:
        return None
    q = fm.value / fx.value
    se = q * math.hypot(fm.se / fm.value, fx.se / fx.value) / abs(deficit)
    return (1.0 - q) / deficit, se


def _energy_drift(energy) -> tuple[float, float, float] | None:
    """Slope of the free vibrations' energy ratio per impact against the recording position [1/record],
    its standard error and z, with the amplitude dependence (a quadratic in the amplitude) held out.

    ``energy`` is (record position, amplitude [alpha], energy ratio [-]) per impact. None when fewer
    than two records or too few impacts carry it.
    """
    if energy is None:
        return None
    pos, amp, c = (np.asarray(v, dtype=float) for v in energy)
    ok = np.isfinite(pos) & np.isfinite(amp) & np.isfinite(c)
    pos, amp, c = pos[ok], amp[ok], c[ok]
    if np.unique(pos).size < 2 or c.size < 8:
        return None
    A = np.column_stack((np.ones_like(amp), amp, amp**2, pos))
    coef, *_ = np.linalg.lstsq(A, c, rcond=None)
    res = c - A @ coef
    s2 = float(res @ res) / (c.size - A.shape[1])
    try:
        se = math.sqrt(max(float(s2 * np.linalg.inv(A.T @ A)[3, 3]), 0.0))
    except np.linalg.LinAlgError:
        return None
    if not se > 0:
        return None
    return float(coef[3]), se, float(coef[3]) / se


def order_drift(excess: Sequence[np.ndarray], energy=None) -> dict | None:
    """A drift along the recording order, as a physical class of :func:`physical_classes`, or None.

    Parameters
    ----------
    excess : sequence of ndarray
        Per record, in campaign (recording) order: a model's held-out error less its floor [alpha],
        for each model judged (the plain model, the final one).
    energy : tuple of ndarray, optional
        The measured free vibrations' (record position, amplitude [alpha], energy ratio [-]) per
        impact (:class:`housner.scenarios.campaigns.localise.Features`).

    Returns
    -------
    dict or None
        The ``drift`` class, when either test's two-sided |z| exceeds :data:`Z_DRIFT`:

        * Kendall's tau of the excess error against the record's position, for the model where it
          is strongest. Under a physics that does not change during the campaign the records' excess
          errors are exchangeable, so the rank test holds its level whatever their (heavy-tailed,
          chaotic) distribution;
        * the slope of the free vibrations' energy ratio per impact against the position of their
          record, the amplitude dependence held out (a restitution that wears shows here first: the
          free vibrations are not chaotic).
    """
    evidence = []
    best = None
    for e in excess:
        e = np.asarray(e, dtype=float)
        ok = np.flatnonzero(np.isfinite(e))
        if ok.size < MIN_RECORDS:
            continue
        res = kendalltau(ok, e[ok])
        if not math.isfinite(res.statistic):
            continue
        z = math.copysign(float(norm.isf(max(res.pvalue, 1e-300) / 2)), res.statistic)
        n = ok.size
        if best is None or abs(z) > abs(best[1]):
            best = (float(res.statistic), z, math.sqrt(2 * (2 * n + 5) / (9 * n * (n - 1))))
    if best is not None:
        tau, z, se = best
        trend = "grows" if tau > 0 else "falls"
        evidence.append({
            "metric": "error_order",
            "label": f"the model's excess error {trend} along the recording order (Kendall's tau)",
            "measured": tau, "measured_se": se, "model": 0.0, "model_se": 0.0, "z": z,
        })  # fmt: skip
    ed = _energy_drift(energy)
    if ed is not None:
        slope, se, z = ed
        evidence.append({
            "metric": "energy_ratio_order",
            "label": "energy ratio per impact of the free vibrations against their record's position in the "
                     "recording order, amplitude held out (slope per record)",
            "measured": slope, "measured_se": se, "model": 0.0, "model_se": 0.0, "z": z,
        })  # fmt: skip
    evidence = sorted((ev for ev in evidence if abs(ev["z"]) > Z_DRIFT), key=lambda ev: -abs(ev["z"]))
    if not evidence:
        return None
    return {"class": "drift", "meaning": CLASSES["drift"], "z": abs(evidence[0]["z"]), "evidence": evidence}


def _beyond(classes: list[dict], z: float) -> list[dict]:
    """The classes of :func:`physical_classes` with only their evidence beyond ``z`` standard errors."""
    out = []
    for c in classes:
        ev = [e for e in c["evidence"] if abs(e["z"]) > z]
        if ev:
            out.append({**c, "z": max(abs(e["z"]) for e in ev), "evidence": ev})
    return out


def _groups_text(r: Residual) -> str:
    names = {"ground_motion": "ground motions", "free_vibration": "free vibrations"}

    def one(k: str, g: dict) -> str:
        if k != "ground_motion":
            return f"{names[k]} {g['ratio']:.2f}x, z = {g['z']:+.1f}"
        # the typical record first (10 %-trimmed); the mean, when the few records chaos carries off weigh on it
        out = f"{names[k]} {g['ratio_trimmed']:.2f}x 10 %-trimmed, z = {g['z_trimmed']:+.1f}"
        if abs(g.get("ratio_trimmed", g["ratio"]) - g["ratio"]) > 0.05:
            out += f" ({g['ratio']:.2f}x on the mean, z = {g['z']:+.1f})"
        return out

    return "; ".join(one(k, g) for k, g in r.groups.items())


def _evidence_text(ev: dict) -> str:
    return (
        f"{ev['label']}: measured {_g(ev['measured'])} +- {_g(ev['measured_se'])}, model {_g(ev['model'])} "
        f"+- {_g(ev['model_se'])} (z = {ev['z']:+.1f})"
    )


def _g(v: float) -> str:
    return f"{v:.4g}" if math.isfinite(v) else str(v)


def distribution_checks(cmp: Comparison | None) -> list[str]:
    """Distribution misfits of the ground-motion records, in words (empty when none is significant)."""
    out: list[str] = []
    if cmp is None or cmp.distribution is None or cmp.distribution.measured.size < 5:
        return out
    d = cmp.distribution
    if d.ks.pvalue < DIST_LEVEL:
        out.append(f"the theta_max/alpha distributions differ (KS D = {d.ks.distance:.3f}, p = {d.ks.pvalue:.2g})")
    n = d.measured.size
    k1, k2 = int(np.isinf(d.measured).sum()), int(np.isinf(d.model).sum())
    pool = (k1 + k2) / (2 * n)
    if 0 < pool < 1:
        zz = (k2 - k1) / n / math.sqrt(2 * pool * (1 - pool) / n)
        if 2 * norm.sf(abs(zz)) < DIST_LEVEL:
            out.append(f"the overturn fractions differ (measured {k1}/{n}, model {k2}/{n}, z = {zz:+.1f})")
    return out


# ----------------------------------------------------------------------------
# the verdict
@dataclass(frozen=True)
class Verdict:
    """What the diagnosis can claim.

    Attributes
    ----------
    status : str
        One of :data:`STATUSES`.
    residual : Residual
        The final model's held-out error against its floor.
    baseline : Residual
        The plain model's.
    text : str
        One paragraph in words (the same in the JSON, the CLI and the report).
    where : list of str
        Localisation items where the final model still differs from the measurement.
    next : list of dict
        Physical classes to look at, strongest first (:func:`physical_classes`).
    distribution : list of str
        Distribution misfits of the final model.
    records_needed : int
        For ``inconclusive``: ground-motion records to add.
    """

    status: str
    residual: Residual
    baseline: Residual
    text: str
    where: list[str] = field(default_factory=list)
    next: list[dict] = field(default_factory=list)
    distribution: list[str] = field(default_factory=list)
    records_needed: int = 0

    def to_dict(self) -> dict:
        r = self.residual
        return {
            "status": self.status,
            "residual": {"error": r.error, "floor": r.floor, "ratio": r.ratio, "z": r.z},
            "residual_detail": r.to_dict(),
            "baseline_residual": self.baseline.to_dict(),
            "text": self.text,
            "where": list(self.where),
            "next": list(self.next),
            "distribution": list(self.distribution),
            "records_needed": self.records_needed,
        }


def decide(
    *,
    n_records: int,
    baseline: Residual,
    final: Residual,
    selected: Sequence[str],
    params: dict[str, dict],
    baseline_cmp: Comparison | None,
    final_cmp: Comparison | None,
    library: Sequence[str],
    added: Sequence[str] = (),
    drift: dict | None = None,
    family: str = "",
    probes: Sequence[dict] = (),
) -> Verdict:
    """The status and its paragraph from the residuals, the effects in the final model and the localisation.

    ``selected`` are the effects the search added, ``added`` those added by hand (both in the final
    model, which is the one judged); ``drift`` is :func:`order_drift`'s class, if any; ``family`` the
    correct integrators the floor was measured over (:data:`housner.scenarios.campaigns.model_form.FAMILIES`).
    """
    dist_final = distribution_checks(final_cmp)
    dist_base = distribution_checks(baseline_cmp)
    # what differs from Housner's physics (the plain model) names the family; what the final model still
    # misses follows
    base_classes = physical_classes(baseline_cmp)
    final_classes = physical_classes(final_cmp)
    have = {c["class"] for c in base_classes}
    classes = base_classes + [c for c in final_classes if c["class"] not in have]
    # a probe of physics outside the library that lowers the error significantly is the most direct
    # pointer there is: its class first (housner.scenarios.campaigns.probes)
    for pr in sorted(probes, key=lambda p: p["z"]):
        pr_ev = {
            "metric": f"probe:{pr['probe']}",
            "label": f"held-out error with the probe {pr['probe']} ("
                     + ", ".join(f"{k} = {v:.3g}" for k, v in pr["params"].items())
                     + f"), against {pr['error']:.4g} without it",
            "measured": pr["error_with"], "measured_se": pr["se"], "model": pr["error"], "model_se": 0.0, "z": pr["z"],
        }  # fmt: skip
        entry = {"class": pr["class"], "meaning": CLASSES[pr["class"]], "z": abs(pr["z"]), "evidence": [pr_ev]}
        old = [c for c in classes if c["class"] == pr["class"]]
        if old:
            entry["evidence"] += old[0]["evidence"]
        classes = [entry, *[c for c in classes if c["class"] != pr["class"]]]
    if drift is not None:
        # a physics that changes along the campaign is what no constant effect explains: named first
        classes = [drift, *[c for c in classes if c["class"] != "drift"]]
    where = [_evidence_text(ev) for c in final_classes for ev in c["evidence"]]
    if drift is not None:
        where = [_evidence_text(ev) for ev in drift["evidence"]] + where
    # a localisation quantity beyond Z_LOCAL standard errors is a misfit the errors may not show
    loc_base = _beyond(base_classes, Z_LOCAL)
    loc_final = _beyond(final_classes, Z_LOCAL)
    # a significant probe is physics the final model misses, whatever the residual test says
    base_mis = baseline.misfit or bool(dist_base) or bool(loc_base) or drift is not None or bool(probes)
    fin_mis = final.misfit or bool(dist_final) or bool(loc_final) or drift is not None or bool(probes)
    powered = final.detectable_ratio <= DETECTABLE_RATIO
    model = [*added, *[n for n in selected if n not in added]]
    need = final.records_needed if model else baseline.records_needed
    eff = "; ".join(f"{n} ({', '.join(f'{k} = {v:.4g}' for k, v in params.get(n, {}).items())})" for n in model)
    fam = f" (correct integrators of the family '{family}')" if family else ""
    figs = f"held-out error {final.error:.4f} alpha against a correct-model floor of {final.floor:.4f}{fam}, " \
           f"residual ratio {final.ratio:.2f} ({_groups_text(final)})"  # fmt: skip
    base_figs = f"the plain Housner model's held-out error is {baseline.error:.4f} alpha against a correct-model " \
                f"floor of {baseline.floor:.4f}{fam}, residual ratio {baseline.ratio:.2f} " \
                f"({_groups_text(baseline)})"  # fmt: skip
    fall = ""
    if model:
        change = "falls" if final.error < baseline.error else "rises"
        how = "added by hand" if not selected else "found by the search" if not added else "added by hand and found"
        fall = f"with {eff} ({how}) the held-out error {change} from {baseline.error:.4f} to {final.error:.4f} alpha"
    if n_records < MIN_RECORDS:
        status = "inconclusive"
        text = (f"Inconclusive: {n_records} usable records are too few to tell a misfit from chance (at least "
                f"{MIN_RECORDS} are needed, with free vibrations among them); {base_figs}.")  # fmt: skip
    elif not model and not base_mis:
        if powered:
            status = "no_misfit"
            text = (f"No misfit: {base_figs}; no group is more than {RATIO_MISFIT}x above it with significance, "
                    f"which is what a correct model shows on these records. No effect is needed. This campaign "
                    f"would have detected a misfit of {final.detectable_ratio:.2f}x the floor or more.")  # fmt: skip
        else:
            status = "inconclusive"
            text = (f"Inconclusive: {base_figs}, not significantly above it, but with these records only a misfit "
                    f"of {final.detectable_ratio:.2f}x the floor or more would show; about {need} more ground-motion "
                    f"records are needed to see one of {DETECTABLE_RATIO}x.")  # fmt: skip
    elif not model:
        status = "unexplained"
        text = (f"Unexplained: {base_figs}, a misfit that no effect in the library "
                f"({', '.join(library)}) reduces significantly.")  # fmt: skip
    elif not fin_mis:
        small = "" if base_mis else (" The plain model was already within the floor's band, yet the fall is "
                                     "significant on the held-out records: a small effect that many records prove.")
        if powered:
            status = "explained"
            doubt = "" if final.ratio <= RATIO_MISFIT else (
                f" Its residual ratio {final.ratio:.2f} lies above the {RATIO_MISFIT}x band, but not significantly "
                f"(z = {final.z:+.1f} <= {Z_MISFIT:g}): these records cannot tell it from the floor.")  # fmt: skip
            text = (f"Explained: {base_figs}; {fall}, residual ratio {final.ratio:.2f} ({_groups_text(final)}), "
                    f"no group more than {RATIO_MISFIT}x above it with significance: what a correct model shows. "
                    f"{' + '.join(model)} explains it.{small}{doubt}")  # fmt: skip
        else:
            status = "inconclusive"
            text = (f"Inconclusive: {base_figs}; {fall}, to a {figs}, but these records would only show a "
                    f"remaining misfit of {final.detectable_ratio:.2f}x or more; about {need} more ground-motion "
                    f"records are needed.")  # fmt: skip
    else:
        status = "partly_explained"
        if final.misfit or dist_final or not (loc_final or drift or probes):
            text = (f"Partly explained: {base_figs}; {fall}, to a {figs}. A misfit of {final.ratio:.2f}x the floor "
                    f"(the typical record) remains that no effect in the library explains.")  # fmt: skip
        else:
            probed = [c for c in classes if any(e["metric"].startswith("probe:") for e in c["evidence"])]
            ev = "; ".join(_evidence_text(e) for c in ([drift] if drift else []) + probed + loc_final
                           for e in c["evidence"][:2])  # fmt: skip
            text = (f"Partly explained: {base_figs}; {fall}, to a {figs}, but the localisation (beyond {Z_LOCAL:g} "
                    f"standard errors), the recording order or a probe of physics outside the library still "
                    f"points to a misfit ({ev}) that no effect in the library explains.")  # fmt: skip
    if status in ("partly_explained", "unexplained"):
        if dist_final:
            text += " The distributions disagree too: " + "; ".join(dist_final) + "."
        if classes:
            top = classes[0]
            ev = "; ".join(_evidence_text(e) for e in top["evidence"][:2])
            text += f" Where to look first: {top['meaning']} ({ev})."
            if len(classes) > 1:
                text += " Then: " + "; ".join(c["class"] for c in classes[1:]) + "."
        else:
            text += f" No localisation quantity differs by more than {Z_MISFIT:g} standard errors: the misfit is " \
                    "in the time histories only."  # fmt: skip
    return Verdict(status, final, baseline, text, where, classes, dist_final,
                   need if status == "inconclusive" else 0)  # fmt: skip
