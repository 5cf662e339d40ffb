"""The correct-model floor: the error a correct model shows on each record, measured from the campaign itself.

A held-out time-history error is only meaningful against the error that a *correct* model would show on
the same records: the sensor noise, plus what chaos makes of parameters that the campaign pins only so
well. :func:`measure_floor` measures it by a parametric bootstrap: the fitted model, run by another
correct integrator, as the truth; the sensor's measured noise and faults added; each record scored, with
the same error and window as the real one, by its fold's model with parameters drawn within their
uncertainty. A non-finite history or floor stops the measurement
(:class:`housner.scenarios.diagnosis.selection.record_scoring.NonFiniteHistory`,
:class:`~housner.scenarios.diagnosis.selection.record_scoring.NonFiniteScore`). The replica step by step is in
``docs/explanation/diagnosis.md`` ("The floor"); the real held-out errors are tested against it by
:func:`housner.scenarios.diagnosis.verdict.residual_test.residual_test`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from housner.effects import make_effect
from housner.model import default_substeps
from housner.scenarios.campaigns.campaign_records import estimate_release
from housner.scenarios.diagnosis.comparison.history_error import (
    RELEASE_DTHETA0_SIGMAS,
    record_error,
    release_shift_samples,
)
from housner.scenarios.diagnosis.comparison.record_comparison import (
    release_sensitivities,
    sensor_reading,
    simulate_records,
)
from housner.scenarios.diagnosis.selection.fitting import param_dims
from housner.scenarios.diagnosis.selection.record_scoring import NonFiniteHistory, check_finite, model_text, non_finite
from housner.scenarios.diagnosis.verdict.integrator_families import ModelForm, acc_channel_noise

__all__ = ["N_REPLICAS", "Floor", "measure_floor"]

#: Replicas of the floor bootstrap [-]. Each is one simulation of the campaign.
N_REPLICAS = 6


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


def _perturbed(name: str, params: dict, sd: dict, rng, specimen, hull: dict | None = None) -> dict:
    """Effect ``name``'s ``params`` each moved by a Gaussian draw of its standard deviation in ``sd``, kept within
    its bounds and within the range ``hull`` (the values the fits chose)."""
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
    """Parametric bootstrap of the error a correct model shows on each record (``docs/explanation/diagnosis.md``).

    Parameters
    ----------
    scorer : housner.scenarios.diagnosis.selection.record_scoring.Scorer
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
        (:data:`housner.scenarios.diagnosis.verdict.integrator_families.FAMILIES`).

    Returns
    -------
    Floor
    """

    camp = scorer.campaign
    spec = camp.specimen
    recs = scorer.records
    sd, hull = _fold_spread(model_full, model_folds)
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
        # the replica's truth: the fitted model, produced by "another correct integrator"
        # (docs/explanation/diagnosis.md, "The floor")
        form = ModelForm.draw(np.random.default_rng(np.random.SeedSequence([seed, 4242, b])), acc_noise, family)
        forms.append(form)
        truth = form.simulate(spec, recs, truth_eff, settings)
        scoring = _FoldModels.run(spec, recs, model_full, model_folds, fold_of, (sd, hull), rng, model_settings)
        errs[b] = _replica_errors(scorer, b, truth, truth_eff, scoring, fold_of, rng, model_settings)
    check_finite("the correct-model floor", errs.mean(axis=0), [r.id for r in recs])
    pert = {k: v for k, v in sd.items() if v > 0}
    pert["substeps"] = model_settings["substeps"]
    pert["model_form"] = {"family": family, "replicas": [f.describe() for f in forms], "acc_noise": acc_noise}
    return Floor(
        errs.mean(axis=0), errs.std(axis=0, ddof=1) if n_replicas > 1 else np.zeros(len(recs)), n_replicas, pert
    )


def _fold_spread(model_full, model_folds) -> tuple[dict[str, float], dict[str, tuple[float, float]]]:
    """Per parameter (``effect.key``): the grouped-jackknife standard error of the full fit over the fold fits
    (how far the bootstrap's truth may be from the real one; 0 with one fold), and the range that the fold fits
    and the full fit span, in the parameter's units."""
    k_folds = len(model_folds)
    sd: dict[str, float] = {}
    hull: dict[str, tuple[float, float]] = {}
    for i, (name, p) in enumerate(model_full):
        for key in p:
            vals = np.array([mf[i][1][key] for mf in model_folds], dtype=float)
            ss = float(np.sum((vals - vals.mean()) ** 2))
            sd[f"{name}.{key}"] = math.sqrt((k_folds - 1) / k_folds * ss) if k_folds > 1 else 0.0
            hull[f"{name}.{key}"] = (min(float(vals.min()), p[key]), max(float(vals.max()), p[key]))
    return sd, hull


@dataclass(frozen=True)
class _FoldModels:
    """One replica's scoring models: per record, the response and release sensitivity of the model fitted
    without its fold; per fold, that model's effects."""

    response: list
    sensitivity: list
    effects: dict[int, list]

    @classmethod
    def run(cls, spec, recs, model_full, model_folds, fold_of, spread, rng, settings) -> _FoldModels:
        """Simulate each fold's records with the model fitted without them, as in the real held-out errors,
        its parameters moved by the uncertainty of the truth (``spread``: :func:`_fold_spread`)."""
        sd, hull = spread
        response: list = [None] * len(recs)
        sensitivity: list = [None] * len(recs)
        effects: dict[int, list] = {}
        for k in range(len(model_folds)):
            idx = np.flatnonzero(fold_of == k)
            if idx.size == 0:
                continue
            eff = [
                make_effect(n, **_perturbed(n, model_folds[k][j][1], sd, rng, spec, hull))
                for j, (n, _p) in enumerate(model_full)
            ]
            effects[k] = eff
            sub = [recs[i] for i in idx]
            res = simulate_records(spec, sub, "housner", eff, settings)
            sens = release_sensitivities(spec, sub, res, "housner", eff, settings)
            for i, r, g in zip(idx, res, sens, strict=True):
                response[i] = r
                sensitivity[i] = g
        return cls(response, sensitivity, effects)


def _replica_errors(
    scorer, b: int, truth: list, truth_eff: list, scoring: _FoldModels, fold_of, rng, settings: dict
) -> np.ndarray:
    """The error of each record [alpha] in replica ``b``: the truth read through the record's sensor, scored by
    its fold's model with the real error and window (1 where either run failed). NonFiniteHistory when the
    truth or the scoring model gives a non-finite theta history."""
    spec = scorer.campaign.specimen
    alpha = spec.alpha
    recs = scorer.records
    errs = np.empty(len(recs))
    for i, rec in enumerate(recs):
        tr, mo = truth[i], scoring.response[i]
        for what, res, eff in (
            ("truth", tr, truth_eff),
            ("scoring model", mo, scoring.effects.get(int(fold_of[i]), [])),
        ):
            if non_finite(res):
                raise NonFiniteHistory(
                    f"the correct-model floor: replica {b + 1}'s {what}, {model_text(eff)}, gives a non-finite "
                    f"theta history on record {rec.id!r}",
                    [getattr(e, "name", str(e)) for e in eff],
                    rec.id,
                )
        if isinstance(tr, str) or isinstance(mo, str) or mo is None:
            errs[i] = 1.0
            continue
        # the record's sensor: its noise (sigma and correlation in time) and its range
        meas = sensor_reading(tr, rec, rng)
        g = scoring.sensitivity[i]
        if rec.kind == "free_vibration":
            # the model of a free vibration starts from the release angle read off the noisy record
            # (records.estimate_release), off the true one by its standard error: so here
            mo, g = _from_estimated_release(spec, rec, meas, mo, g, scoring.effects[int(fold_of[i])], settings)
        th_mod = np.asarray(mo.theta, dtype=float)[: rec.theta.size]
        errs[i] = record_error(
            th_mod,
            meas,
            scorer.ends[i],
            alpha,
            align=release_shift_samples(rec),
            sensitivity=None if g is None else g[: rec.theta.size],
            max_dtheta0=RELEASE_DTHETA0_SIGMAS * rec.noise,
            valid=rec.valid,
        )
    return errs


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
